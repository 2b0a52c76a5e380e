"""The operating modes of manual 4.4, as data: the one place that says what each mode is.

For every MODE_REG value: its name and section, the function block, the registers the mode reads
as parameters ("the parameters are interpreted as follows" of 4.4.x), and what its
configuration list of 4.4.1–4.4.25 says (speed regulator, function correction, current
regulator), with the model's decisions where the manual is silent (docs/model.md §9).
The mode numbers of :mod:`jvl_gym.families.mac050_141.constants`, the boolean tables of
:mod:`mac050_141.firmware.modes` used by the compiled firmware, the register reference and the mode
table of the documentation are all derived from :data:`MODES`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ModeInfo", "MODES", "N_MODES", "MODE_NAMES", "number", "flag_table",
           "modes_using", "markdown_mode_table"]


@dataclass(frozen=True)
class ModeInfo:
    """One row of the mode table.

    Attributes
    ----------
    number, name, section, function_block, parameters
        MODE_REG value, name, manual section, function block and parameter registers.
    regulated : bool
        Speed regulator active (4.2): the motor is assumed to be moving; a change to INIT goes
        through STOP_MODE (4.4.2).
    correcting : bool
        "Correction of function block: active" (docs/model.md §8).
    flwerr : bool
        FLWERR is accumulated (3.2.20; HOME1–3 per 4.4.13–15); zero in the other modes.
    passive : bool
        Current regulator passive: equal or test voltages instead (4.4.1, 4.4.9, 4.4.23).
    in_pos : str
        How IN_POS is judged: ``"position"`` (|P_SOLL − P_FNC/16 + FLWERR| < INPOSWIN),
        ``"gear"`` (|G_FNC|/16 < INPOSWIN, 4.4.4, 4.4.25), ``"velocity"`` (INPOSCNT rules of
        4.1.1) or ``""`` (never set).
    gear : bool
        The function block divides by GEARF2 (a GEARF2 of 0 is refused in these modes).
    """

    number: int
    name: str
    section: str
    function_block: str
    parameters: tuple[str, ...]
    regulated: bool = False
    correcting: bool = False
    flwerr: bool = False
    passive: bool = False
    in_pos: str = ""
    gear: bool = False

    @property
    def speed_regulator(self) -> bool:
        """Speed regulator active (4.2)."""
        return self.regulated

    @property
    def current_regulator(self) -> bool:
        """Current regulator active (4.3)."""
        return not self.passive

    @property
    def correction(self) -> bool:
        """Function correction active (docs/model.md §8)."""
        return self.correcting


_GEAR = ("GEARF1", "GEARF2", "V_SOLL", "A_SOLL", "T_SOLL", "KVOUT")
_POS = ("V_SOLL", "A_SOLL", "T_SOLL", "KVOUT", "INPOSWIN", "INPOSCNT")
_HOME = ("V_HOME", "T_HOME", "P_HOME", "A_SOLL", "STARTMODE", "KVOUT")

#: keyword sets of the configuration lists: a velocity-profile mode, a position mode, a gear mode
_V = {"regulated": True, "flwerr": True}
_P = {"regulated": True, "flwerr": True, "correcting": True, "in_pos": "position"}
_G = {"regulated": True, "flwerr": True, "correcting": True, "in_pos": "gear", "gear": True}

MODES: tuple[ModeInfo, ...] = (
    ModeInfo(0, "INIT_MODE", "4.4.1", "none (coils short-circuited)", ("CNTRL_BITS",),
             passive=True),
    ModeInfo(1, "V_MODE", "4.4.2", "velocity (4.1.1)",
             ("V_SOLL", "A_SOLL", "T_SOLL", "KVOUT", "INPOSWIN", "INPOSCNT"), **_V,
             in_pos="velocity"),
    ModeInfo(2, "P_MODE", "4.4.3", "position (4.1.2)", ("P_SOLL", "P_FNC", *_POS), **_P),
    ModeInfo(3, "GP_MODE", "4.4.4", "gear position (4.1.12)", (*_GEAR, "V_EXT", "INPOSWIN"),
             **_G),
    ModeInfo(4, "AT_MODE", "4.4.5", "torque (4.1.4)", ("T_SOLL", "ANINP", "ANINP_OFFSET")),
    ModeInfo(5, "AV_MODE", "4.4.6", "AV (4.1.5)",
             ("V_SOLL", "A_SOLL", "T_SOLL", "KVOUT", "ANINP", "ANINP_OFFSET"), **_V),
    ModeInfo(6, "AVG_MODE", "4.4.7", "AVG (4.1.7)", (*_GEAR, "V_EXT", "ANINP", "ANINP_OFFSET"),
             **_V, gear=True),
    ModeInfo(7, "MANI_MODE", "4.4.8", "none (stator field by hand)",
             ("MAN_I_NOM", "MAN_ALPHA", "AMPLITUDE")),
    ModeInfo(8, "TESTU_MODE", "4.4.9", "none (voltage step)", ("UMEAS",), passive=True),
    ModeInfo(9, "TESTA_MODE", "4.4.10", "none (torque step)", ("T_SOLL",)),
    ModeInfo(10, "BREAK_MODE", "4.4.11", "none (reversed torque)", ("T_SOLL",)),
    ModeInfo(11, "STOP_MODE", "4.4.12", "stop (4.1.8)", ("A_SOLL", "ACC_EMERG", "T_SOLL", "KVOUT"),
             regulated=True),
    ModeInfo(12, "HOME1_MODE", "4.4.13", "velocity (4.1.1)", _HOME, **_V),
    ModeInfo(13, "HOME2_MODE", "4.4.14", "velocity (4.1.1)", (*_HOME, "T_SOLL", "ANINP"), **_V),
    ModeInfo(14, "HOME3_MODE", "4.4.15", "velocity (4.1.1)", (*_HOME, "T_SOLL", "ANINP"), **_V),
    ModeInfo(15, "SAFE_MODE", "4.4.16", "none (as INIT)", (), passive=True),
    ModeInfo(16, "AVZ_MODE", "4.4.17", "AVZ (4.1.6)",
             ("V_SOLL", "A_SOLL", "T_SOLL", "KVOUT", "ANINP", "ANINP_OFFSET"), **_V),
    ModeInfo(17, "VAT_MODE", "4.4.18", "velocity (4.1.1), analogue torque limit",
             ("V_SOLL", "A_SOLL", "T_SOLL", "KVOUT", "ANINP", "ANINP_OFFSET", "INPOSWIN",
              "INPOSCNT"), **_V, in_pos="velocity"),
    ModeInfo(18, "AG_MODE", "4.4.19", "analogue gear (4.1.9)",
             (*_GEAR, "V_EXT", "ANINP", "ANINP_OFFSET", "INPOSWIN"), **_G),
    ModeInfo(19, "COIL_MODE", "4.4.20", "coil traverse (gear position)",
             (*_GEAR, "V_EXT", "V8", "P1", "P2", "P3", "P4", "P5", "P6", "ANINP"),
             **{**_G, "in_pos": ""}),
    ModeInfo(20, "A2POS_MODE", "4.4.21", "analogue 2 position (4.1.10)",
             ("P1", "P2", "P_SOLL", "ERR_STAT", "ANINP", *_POS), **_P),
    ModeInfo(21, "APOS_MODE", "4.4.22", "analogue position (4.1.11)",
             ("P1", "P2", "P3", "P_SOLL", "ANINP", *_POS), **_P),
    ModeInfo(22, "TESTKI_MODE", "4.4.23", "none (current-gain measurement)", ("UMEAS",),
             passive=True),
    ModeInfo(23, "TESTTQ_MODE", "4.4.24", "velocity (friction measurement)",
             ("V_SOLL", "A_SOLL", "T_SOLL", "KVOUT"), regulated=True),
    ModeInfo(24, "GF_MODE", "4.4.25", "gear follow (4.1.3)", (*_GEAR, "V_EXT", "INPOSWIN"), **_G),
)
#: number of MODE_REG operating-mode values (0 … N_MODES − 1; 256–258 are SAFE_MODE commands)
N_MODES = len(MODES)
#: MODE_REG value → mode name
MODE_NAMES: dict[int, str] = {m.number: m.name for m in MODES}
_NUMBERS = {m.name: m.number for m in MODES}
assert [m.number for m in MODES] == list(range(N_MODES)), "MODES must be in MODE_REG order"


def number(name: str) -> int:
    """MODE_REG value of the mode ``name``."""
    return _NUMBERS[name]


def flag_table(flag: str, value: object = True) -> np.ndarray:
    """(N_MODES,) bool: the modes whose attribute ``flag`` equals ``value`` (compiled
    firmware indexes it by MODE_REG)."""
    return np.array([getattr(m, flag) == value for m in MODES], dtype=np.bool_)


def modes_using(register: str) -> list[str]:
    """Names of the modes that read ``register`` as a parameter."""
    return [m.name for m in MODES if register in m.parameters]


def markdown_mode_table() -> str:
    """The mode table as Markdown (docs/modes.md)."""
    yes = {True: "active", False: "passive"}
    lines = ["# Operating modes", "",
             "Generated from `jvl_gym.families.mac050_141.firmware.mode_table` (manual 4.4); "
             "do not edit by hand.", "",
             "| MODE_REG | mode | manual | function block | speed reg. | current reg. | "
             "correction | parameters |", "|---:|---|---|---|---|---|---|---|"]
    for m in MODES:
        lines.append(f"| {m.number} | {m.name} | {m.section} | {m.function_block} | "
                     f"{yes[m.speed_regulator]} | {yes[m.current_regulator]} | "
                     f"{yes[m.correction]} | {', '.join(m.parameters)} |")
    lines += ["", "256, 257, 258 are SAFE_MODE commands (4.4.16): load ROM defaults and save "
              "to flash with a reset, load ROM defaults, reload the flash parameters.", ""]
    return "\n".join(lines)

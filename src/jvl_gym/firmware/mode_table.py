"""What each operating mode uses, from the mode descriptions of manual 4.4 (one place, as data).

For every MODE_REG value: the function block, whether the speed and current regulators are active,
whether the function correction is active, and the registers the mode reads as parameters
("the parameters are interpreted as follows" of 4.4.x). The register reference and the mode table
of the documentation are generated from it.
"""

from __future__ import annotations

from dataclasses import dataclass

from .modes import CORRECTING, PASSIVE, REGULATED


@dataclass(frozen=True)
class ModeInfo:
    """One row of the mode table."""

    number: int
    name: str
    section: str
    function_block: str
    parameters: tuple[str, ...]

    @property
    def speed_regulator(self) -> bool:
        """Speed regulator active (4.2)."""
        return bool(REGULATED[self.number])

    @property
    def current_regulator(self) -> bool:
        """Current regulator active (4.3)."""
        return not bool(PASSIVE[self.number])

    @property
    def correction(self) -> bool:
        """Function correction active (docs/model.md §8)."""
        return bool(CORRECTING[self.number])


_GEAR = ("GEARF1", "GEARF2", "V_SOLL", "A_SOLL", "T_SOLL", "KVOUT")
_POS = ("V_SOLL", "A_SOLL", "T_SOLL", "KVOUT", "INPOSWIN", "INPOSCNT")
_HOME = ("V_HOME", "T_HOME", "P_HOME", "A_SOLL", "STARTMODE", "KVOUT")

MODES: tuple[ModeInfo, ...] = (
    ModeInfo(0, "INIT_MODE", "4.4.1", "none (coils short-circuited)", ("CNTRL_BITS",)),
    ModeInfo(1, "V_MODE", "4.4.2", "velocity (4.1.1)",
             ("V_SOLL", "A_SOLL", "T_SOLL", "KVOUT", "INPOSWIN", "INPOSCNT")),
    ModeInfo(2, "P_MODE", "4.4.3", "position (4.1.2)", ("P_SOLL", "P_FNC", *_POS)),
    ModeInfo(3, "GP_MODE", "4.4.4", "gear position (4.1.12)", (*_GEAR, "V_EXT", "INPOSWIN")),
    ModeInfo(4, "AT_MODE", "4.4.5", "torque (4.1.4)", ("T_SOLL", "ANINP", "ANINP_OFFSET")),
    ModeInfo(5, "AV_MODE", "4.4.6", "AV (4.1.5)",
             ("V_SOLL", "A_SOLL", "T_SOLL", "KVOUT", "ANINP", "ANINP_OFFSET")),
    ModeInfo(6, "AVG_MODE", "4.4.7", "AVG (4.1.7)", (*_GEAR, "V_EXT", "ANINP", "ANINP_OFFSET")),
    ModeInfo(7, "MANI_MODE", "4.4.8", "none (stator field by hand)",
             ("MAN_I_NOM", "MAN_ALPHA", "AMPLITUDE")),
    ModeInfo(8, "TESTU_MODE", "4.4.9", "none (voltage step)", ("UMEAS",)),
    ModeInfo(9, "TESTA_MODE", "4.4.10", "none (torque step)", ("T_SOLL",)),
    ModeInfo(10, "BREAK_MODE", "4.4.11", "none (reversed torque)", ("T_SOLL",)),
    ModeInfo(11, "STOP_MODE", "4.4.12", "stop (4.1.8)", ("A_SOLL", "ACC_EMERG", "T_SOLL", "KVOUT")),
    ModeInfo(12, "HOME1_MODE", "4.4.13", "velocity (4.1.1)", _HOME),
    ModeInfo(13, "HOME2_MODE", "4.4.14", "velocity (4.1.1)", (*_HOME, "T_SOLL", "ANINP")),
    ModeInfo(14, "HOME3_MODE", "4.4.15", "velocity (4.1.1)", (*_HOME, "T_SOLL", "ANINP")),
    ModeInfo(15, "SAFE_MODE", "4.4.16", "none (as INIT)", ()),
    ModeInfo(16, "AVZ_MODE", "4.4.17", "AVZ (4.1.6)",
             ("V_SOLL", "A_SOLL", "T_SOLL", "KVOUT", "ANINP", "ANINP_OFFSET")),
    ModeInfo(17, "VAT_MODE", "4.4.18", "velocity (4.1.1), analogue torque limit",
             ("V_SOLL", "A_SOLL", "T_SOLL", "KVOUT", "ANINP", "ANINP_OFFSET")),
    ModeInfo(18, "AG_MODE", "4.4.19", "analogue gear (4.1.9)",
             (*_GEAR, "V_EXT", "ANINP", "ANINP_OFFSET", "INPOSWIN")),
    ModeInfo(19, "COIL_MODE", "4.4.20", "coil traverse (gear position)",
             (*_GEAR, "V_EXT", "V8", "P1", "P2", "P3", "P4", "P5", "P6", "ANINP")),
    ModeInfo(20, "A2POS_MODE", "4.4.21", "analogue 2 position (4.1.10)",
             ("P1", "P2", "P_SOLL", "ERR_STAT", "ANINP", *_POS)),
    ModeInfo(21, "APOS_MODE", "4.4.22", "analogue position (4.1.11)",
             ("P1", "P2", "P3", "P_SOLL", "ANINP", *_POS)),
    ModeInfo(22, "TESTKI_MODE", "4.4.23", "none (current-gain measurement)", ("UMEAS",)),
    ModeInfo(23, "TESTTQ_MODE", "4.4.24", "velocity (friction measurement)",
             ("V_SOLL", "A_SOLL", "T_SOLL", "KVOUT")),
    ModeInfo(24, "GF_MODE", "4.4.25", "gear follow (4.1.3)", (*_GEAR, "V_EXT", "INPOSWIN")),
)


def modes_using(register: str) -> list[str]:
    """Names of the modes that read ``register`` as a parameter."""
    return [m.name for m in MODES if register in m.parameters]


def markdown_mode_table() -> str:
    """The mode table as Markdown (docs/modes.md)."""
    yes = {True: "active", False: "passive"}
    lines = ["# Operating modes", "",
             "Generated from `jvl_gym.firmware.mode_table` (manual 4.4); do not edit by hand.", "",
             "| MODE_REG | mode | manual | function block | speed reg. | current reg. | "
             "correction | parameters |", "|---:|---|---|---|---|---|---|---|"]
    for m in MODES:
        lines.append(f"| {m.number} | {m.name} | {m.section} | {m.function_block} | "
                     f"{yes[m.speed_regulator]} | {yes[m.current_regulator]} | "
                     f"{yes[m.correction]} | {', '.join(m.parameters)} |")
    lines += ["", "256, 257, 258 are SAFE_MODE commands (4.4.16): load ROM defaults and save "
              "to flash with a reset, load ROM defaults, reload the flash parameters.", ""]
    return "\n".join(lines)

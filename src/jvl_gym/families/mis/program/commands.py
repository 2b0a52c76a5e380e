"""The program commands of the MIS (MIS manual §9.7): one table of keywords and dialogue fields.

Each entry is a command of the §9.7 toolbox with the fields of its dialogue, in the order the
dialogue shows them, and the section that describes it. §9.7.3 ("Move operations") introduces
the five move commands and §9.7.26 ("Calculator (options)") is the options tab of the calculator
dialogue: the calculator line carries its one option (``precision``, 32-bit only) itself.

A :class:`Command` is a keyword and its field values; :mod:`.format` reads and writes them as
text, :mod:`.binary` as flash bytes, :mod:`.executor` runs them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .fields import (
    INPUT_NAMES,
    OPERATORS,
    Choice,
    Expression,
    Field,
    Hex,
    Int,
    Pattern,
    RegisterField,
    Source,
    Text,
    Value,
    Velocity,
)

__all__ = ["Command", "Spec", "SPECS", "MAX_LINES", "FASTMAC_NUMBERS", "cost_us"]

#: jump targets are program lines 1 … MAX_LINES (the 3072-byte program flash, §15 data)
MAX_LINES = 3072
#: FastMac numbers of the §8.2.21 table; command number = 96 + FastMac number (97 = FastMac 1)
FASTMAC_NUMBERS = (0, 1, 2, 3, 5, 7, 12, 13, 14, 15, 17, 18, 20, 21, 22, 23, 24, 25)

_OUTPUTS = tuple(str(k) for k in range(1, 9))
_CONDITIONS = ("low", "high", "falling", "rising")
_YES_NO = ("yes", "no")

_ACC = Int(0, 500000)  # RPM/s, 0: keep A_SOLL (§9.7.4)
_LINE = Int(1, MAX_LINES)
_MOVE = {"acceleration": (_ACC, 0), "velocity": (Velocity(), 0)}


@dataclass(frozen=True)
class Spec:
    """One command type: its keyword, section and fields.

    Attributes
    ----------
    keyword : str
        First word of a program line.
    section : str
        Section of the MIS manual.
    fields : dict of str to (Field, default)
        The dialogue's fields in order; default ``None``: required.
    """

    keyword: str
    section: str
    title: str
    fields: dict[str, tuple[Field, object]]


def _spec(keyword: str, section: str, title: str, **fields: tuple[Field, object]) -> Spec:
    return Spec(keyword, section, title, dict(fields))


_COND = {"input": (Choice(INPUT_NAMES), None), "condition": (Choice(_CONDITIONS), None)}
_MULTI = {"operand": (Choice(("and", "or")), None), "inputs": (Pattern(INPUT_NAMES), None)}

#: every command type, by keyword
SPECS: dict[str, Spec] = {s.keyword: s for s in (
    _spec("remark", "§9.7.1", "Enter your own remarks", text=(Text(), "")),
    _spec("mode", "§9.7.2", "Set operation mode",
          mode=(Choice(("passive", "velocity", "position", "gear")), None)),
    _spec("move_relative", "§9.7.4", "Move (Relative)", distance=(Source(), None), **_MOVE,
          wait=(Choice(_YES_NO), "yes")),
    _spec("move_relative_change", "§9.7.5", "Move (Relative + velocity change at a distance)",
          distance=(Source(), None), **_MOVE, change_distance=(Source(lo=0), None),
          new_velocity=(Velocity(), None)),
    _spec("move_relative_outputs", "§9.7.6", "Move (Relative + set outputs)",
          distance=(Source(), None), **_MOVE, outputs=(Pattern(_OUTPUTS), None)),
    _spec("move_absolute", "§9.7.7", "Move (Absolute)", position=(Source(), None), **_MOVE,
          wait=(Choice(_YES_NO), "yes")),
    _spec("move_sensor", "§9.7.8", "Move (Sensor)", distance=(Source(), None), **_MOVE,
          safety_distance=(Source(lo=0), 0), **_COND),
    _spec("set_output", "§9.7.9", "Set outputs (single)", output=(Choice(_OUTPUTS), None),
          state=(Choice(("low", "high", "low_pulse", "high_pulse")), None),
          pulse_ms=(Int(0, 32767), 0)),
    _spec("set_outputs", "§9.7.9", "Set outputs (multiple)",
          outputs=(Pattern(_OUTPUTS), None)),
    _spec("jump", "§9.7.10", "Unconditional jump", line=(_LINE, None)),
    _spec("jump_input", "§9.7.11", "Conditional jump (single input)", **_COND,
          line=(_LINE, None)),
    _spec("jump_inputs", "§9.7.12", "Conditional jump (multiple inputs)", **_MULTI,
          line=(_LINE, None)),
    _spec("wait_ms", "§9.7.13", "Wait for (x) ms before continuing",
          time=(Int(0, 32767), None)),
    _spec("wait_input", "§9.7.14", "Wait for an input (single)", **_COND),
    _spec("wait_inputs", "§9.7.15", "Wait for an input combination (multiple)", **_MULTI),
    _spec("set_register", "§9.7.16", "Set a register", register=(RegisterField(True), None),
          value=(Value(), None)),
    _spec("jump_register", "§9.7.17", "Jump according to a register",
          register=(RegisterField(), None), operator=(Choice(OPERATORS), None),
          value=(Value(), None), line=(_LINE, None)),
    _spec("wait_register", "§9.7.18", "Wait for a register value",
          register=(RegisterField(), None), operator=(Choice(OPERATORS), None),
          value=(Value(), None)),
    _spec("save_position", "§9.7.19", "Save position",
          register=(Choice(("register1", "register2", "register3")), None)),
    _spec("set_position", "§9.7.20", "Set position", position=(Source(), None)),
    _spec("zero_search", "§9.7.21", "Zero search", mode=(Choice(("sensor1", "sensor2")), None)),
    _spec("fastmac", "§9.7.22", "Send FastMAC command (change mode and activate register)",
          mode=(Choice(("passive", "velocity", "position")), None),
          register=(Choice(("position", "velocity", "acceleration", "torque")), None),
          number=(Int(1, 8), None)),
    _spec("fastmac_command", "§9.7.23", "Send FastMAC command (macro command)",
          command=(Choice(tuple(str(n) for n in FASTMAC_NUMBERS)), None)),
    _spec("binary", "§9.7.24", "Binary command", code=(Hex(), None)),
    _spec("calculate", "§9.7.25", "Calculator", register=(RegisterField(True), None),
          expression=(Expression(), None), precision=(Choice(("32",)), "32")),
    _spec("jump_compare", "§9.7.27", "Jump according to a comparison",
          register=(RegisterField(), None), operator=(Choice(OPERATORS), None),
          register2=(RegisterField(), None), line=(_LINE, None)),
)}

#: FastMAC register groups (§9.7.22): register name prefix and how many the MIS has
#: (§8.2.41–44: P1–P8, V1–V8, A1–A4, T1–T4) and the register each one activates
FASTMAC_GROUPS = {"position": ("P", 8, "P_SOLL"), "velocity": ("V", 8, "V_SOLL"),
                  "acceleration": ("A", 4, "A_SOLL"), "torque": ("T", 4, "RUN_CURRENT")}

@dataclass(frozen=True)
class Command:
    """One program line: a keyword of :data:`SPECS` and its field values.

    Attributes
    ----------
    keyword : str
        The command type.
    values : dict of str to object
        Every field of the type (defaults filled in), except ``pulse_ms`` of a level output.
    """

    keyword: str
    values: dict[str, object] = field(default_factory=dict)

    @property
    def spec(self) -> Spec:
        return SPECS[self.keyword]

    def __getitem__(self, name: str) -> object:
        return self.values[name]


def _move_cost(cmd: Command, base: int) -> int:
    return (base + (60 if cmd["velocity"] else 0)
            + (60 if cmd["acceleration"] else 0))


def cost_us(cmd: Command) -> int:
    """Execution time of one line [µs], from the §9.8 table (MIS manual "Command timing": one
    instruction per main-loop pass of about 30 µs); lines the table does not list are counted
    as the instructions they need (``docs/families/mis-sim.md``, "Programs")."""
    k = cmd.keyword
    if k == "remark":
        return 0
    if k in ("move_relative", "move_relative_change", "move_relative_outputs", "move_sensor"):
        return _move_cost(cmd, 90)
    if k == "move_absolute":
        return _move_cost(cmd, 60)
    if k == "set_outputs":
        return 30 * len(cmd["outputs"])  # type: ignore[arg-type]
    if k == "calculate":
        return 60 * len(cmd["expression"])  # type: ignore[arg-type]
    return {"mode": 60, "set_output": 30, "jump": 30, "jump_input": 60, "jump_inputs": 60,
            "set_register": 60, "jump_register": 120, "jump_compare": 120,
            "save_position": 60, "set_position": 90, "fastmac": 30, "fastmac_command": 30,
            "binary": 30, "zero_search": 60}.get(k, 30)

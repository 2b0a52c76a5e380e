"""The program text format of the simulated MIS: one line per §9.7 command (MIS manual).

A line is the command's keyword and its dialogue fields as ``key=value``, separated by spaces::

    mode mode=position
    move_relative distance=409600 acceleration=1000 velocity=300 wait=yes
    wait_input input=3 condition=rising
    set_output output=1 state=high_pulse pulse_ms=100
    jump_register register=P_IST operator=>= value=2rev line=7
    calculate register=V_SOLL expression=V_SOLL+100
    remark text="wait for the part"

Line *n* of the text is program line *n* (jump targets ``line=n``); every line is a command
(``remark`` is the comment). A value with spaces or quotes is written in double quotes with
``\\"`` and ``\\\\`` escapes. Fields with a default may be left out; :func:`print_program` writes
every field, so ``parse_program(print_program(p)) == p``.

Size. The program flash holds 3072 bytes (:data:`.binary.FLASH_BYTES`): a 2-byte line count and
instructions of at least :data:`MIN_INSTRUCTION_BYTES` (an empty remark), so at most
:data:`MAX_PROGRAM_LINES` lines; a line is at most :data:`MAX_LINE_BYTES` bytes (every canonical
line is shorter: a remark of 255 quotes escaped is 524). No text above :data:`MAX_TEXT_BYTES`
can be a program the motor holds; :func:`text_size_refusal` says so from the size alone, before
the text is read. Errors show a piece of the text they quote, never more than
:data:`~jvl_gym.registers.errors.ECHO_LIMIT` characters and its length
(:func:`~jvl_gym.registers.errors.echo`).
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from ....registers.errors import ECHO_LIMIT, echo
from .binary import FLASH_BYTES, decode_command
from .commands import FASTMAC_GROUPS, SPECS, Command
from .fields import FieldError

__all__ = ["ProgramError", "parse_program", "parse_line", "print_program", "print_line",
           "MAX_TEXT_BYTES", "MAX_LINE_BYTES", "MAX_PROGRAM_LINES", "MIN_INSTRUCTION_BYTES",
           "text_size_refusal"]

_BARE = re.compile(r'[^\s"]+\Z')

#: the shortest instruction in the flash: a command byte and a length byte (an empty remark)
MIN_INSTRUCTION_BYTES = 2
#: the most lines a program in the flash can have (after its 2-byte line count)
MAX_PROGRAM_LINES = (FLASH_BYTES - 2) // MIN_INSTRUCTION_BYTES
#: the longest line of a program text [bytes of UTF-8, without the line break]
MAX_LINE_BYTES = 1024
#: the largest program text a program the flash holds can have [bytes]: its most lines, each
#: at its longest with a CR LF line break
MAX_TEXT_BYTES = MAX_PROGRAM_LINES * (MAX_LINE_BYTES + 2)
#: characters of the text an error message shows at most
def _cut(name: str) -> str:
    """A field name as an error names it: at most :data:`ECHO_LIMIT` characters."""
    return name if len(name) <= ECHO_LIMIT else name[:ECHO_LIMIT] + "…"


def text_size_refusal(size: int) -> str | None:
    """Why a program text of ``size`` bytes cannot be a program of the motor (None: it may)."""
    if size <= MAX_TEXT_BYTES:
        return None
    return (f"{size} bytes is more than any program the {FLASH_BYTES}-byte program flash holds "
            f"({MAX_PROGRAM_LINES} lines of at most {MAX_LINE_BYTES} bytes: {MAX_TEXT_BYTES} "
            "bytes)")


class ProgramError(ValueError):
    """A program text is malformed; ``line`` (1-based) and ``field`` (or None) say where.

    Attributes
    ----------
    line : int
        Program line.
    field : str or None
        The field (``None``: the line as a whole or its keyword).
    """

    def __init__(self, line: int, field: str | None, message: str) -> None:
        where = f"line {line}" + (f", field {field}" if field else "")
        super().__init__(f"{where}: {message}")
        self.line = line
        self.field = field


def _tokens(text: str, n: int) -> list[tuple[str, str | None]]:
    """The words of a line: (word, None), or ("key=", value) for a quoted value."""
    out: list[tuple[str, str | None]] = []
    k = 0
    while k < len(text):
        if text[k] in " \t":
            k += 1
            continue
        start = k
        while k < len(text) and text[k] not in ' \t"':
            k += 1
        tok = text[start:k]
        quoted = None
        if k < len(text) and text[k] == '"':
            if not tok.endswith("="):
                raise ProgramError(n, None, f"a quote must follow 'key=' (at character {k + 1})")
            k += 1
            chars: list[str] = []
            while True:
                if k >= len(text):
                    raise ProgramError(n, tok[:-1], "unterminated quoted value")
                ch = text[k]
                if ch == "\\" and k + 1 < len(text) and text[k + 1] in '"\\':
                    chars.append(text[k + 1])
                    k += 2
                elif ch == '"':
                    k += 1
                    break
                else:
                    chars.append(ch)
                    k += 1
            if k < len(text) and text[k] not in " \t":
                raise ProgramError(n, tok[:-1], "a space must follow the closing quote")
            quoted = "".join(chars)
        out.append((tok, quoted))
    return out


def parse_line(text: str, n: int = 1) -> Command:
    """One program line → :class:`Command`; ProgramError naming line ``n`` and the field."""
    size = len(text.encode("utf-8", "surrogatepass"))
    if size > MAX_LINE_BYTES:
        raise ProgramError(n, None, f"the line has {size} bytes, more than {MAX_LINE_BYTES}: "
                                    f"{echo(text)}")
    toks = _tokens(text, n)
    if not toks:
        raise ProgramError(n, None, "empty line (every line is a command; use remark)")
    keyword = toks[0][0]
    spec = SPECS.get(keyword)
    if spec is None:
        raise ProgramError(n, None, f"unknown command {echo(keyword)}; the commands are "
                                    f"{', '.join(SPECS)}")
    got: dict[str, str] = {}
    if toks[0][1] is not None:
        raise ProgramError(n, None, "a line starts with its command")
    for tok, quoted in toks[1:]:
        key, sep, value = tok.partition("=")
        if not sep or not key:
            raise ProgramError(n, None, f"{echo(tok)} is not key=value")
        value = value if quoted is None else quoted
        if key not in spec.fields:
            raise ProgramError(n, _cut(key), f"{keyword} has no field {echo(key)}; its fields "
                                             f"are {', '.join(spec.fields)}")
        if key in got:
            raise ProgramError(n, _cut(key), "given twice")
        if len(value) > 400:
            raise ProgramError(n, _cut(key), "the value is longer than 400 characters: "
                                             f"{echo(value)}")
        got[key] = value
    values: dict[str, object] = {}
    for key, (ftype, default) in spec.fields.items():
        if key not in got:
            if default is None:
                raise ProgramError(n, key, f"missing ({spec.title}, MIS manual {spec.section})")
            values[key] = default
            continue
        try:
            values[key] = ftype.parse(got[key])
        except FieldError as exc:
            text = got[key]
            raise ProgramError(n, key, str(exc).replace(repr(text), echo(text))) from None
    _check(Command(keyword, values), got, n)
    if keyword == "set_output" and not str(values["state"]).endswith("_pulse"):
        values.pop("pulse_ms")
    return Command(keyword, values)


def _check(cmd: Command, got: dict[str, str], n: int) -> None:
    """Rules between fields."""
    k = cmd.keyword
    if k == "set_output":
        pulse = str(cmd["state"]).endswith("_pulse")
        if pulse and not cmd["pulse_ms"]:
            raise ProgramError(n, "pulse_ms", "a pulse needs its length (1 … 32767 ms)")
        if not pulse and "pulse_ms" in got:
            raise ProgramError(n, "pulse_ms", "only a pulse has a length")
    elif k == "fastmac":
        _, count, _ = FASTMAC_GROUPS[str(cmd["register"])]
        if int(cmd["number"]) > count:  # type: ignore[call-overload]
            raise ProgramError(n, "number", f"the MIS has {count} {cmd['register']} registers "
                                            "(§8.2.41–8.2.44)")
    elif k == "binary":
        try:
            inner = decode_command(bytes.fromhex(str(cmd["code"])))
        except FieldError as exc:
            raise ProgramError(n, "code", f"not an instruction: {exc}") from None
        if inner.keyword == "binary":
            raise ProgramError(n, "code", "a binary command cannot hold a binary command")


def _show(value: str) -> str:
    if value and _BARE.match(value):
        return value
    return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'


def print_line(cmd: Command) -> str:
    """The canonical text of one command (every field, in the dialogue's order)."""
    parts = [cmd.keyword]
    for key, (ftype, _) in cmd.spec.fields.items():
        if key in cmd.values:
            parts.append(f"{key}={_show(ftype.show(cmd.values[key]))}")
    return " ".join(parts)


def parse_program(text: str) -> list[Command]:
    """A program text → its commands, checked as a whole (jump targets inside the program).

    Raises
    ------
    ProgramError
        The first malformed line, with its number and field.
    """
    if not isinstance(text, str):
        raise ProgramError(1, None, f"a program is text, got {type(text).__name__}")
    why = text_size_refusal(len(text))  # characters: at most the bytes of their UTF-8
    if why is not None:
        raise ProgramError(1, None, f"the text of {len(text)} characters cannot be a program: "
                                    f"{why}")
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    if not lines:
        raise ProgramError(1, None, "the program is empty")
    cmds = [parse_line(line.rstrip("\r"), n) for n, line in enumerate(lines, 1)]
    check_program(cmds)
    return cmds


def check_program(cmds: Sequence[Command]) -> None:
    """Jump targets must be lines of the program."""
    for n, cmd in enumerate(cmds, 1):
        target = cmd.values.get("line")
        if target is not None and int(target) > len(cmds):  # type: ignore[call-overload]
            raise ProgramError(n, "line", f"jump to line {target}, but the program has "
                                          f"{len(cmds)} lines")


def print_program(cmds: Sequence[Command]) -> str:
    """The canonical text of a program (one line per command, ending in a newline)."""
    return "".join(print_line(c) + "\n" for c in cmds)

"""The program executor of the MIS firmware (MIS manual chapter 9, §18.2.10).

Timing (§9.8, §9.9): the firmware runs one program instruction per pass of its main loop (about
30 µs); a line takes the time of the §9.8 table (:func:`.commands.cost_us`). The simulated
firmware runs the main loop between its 1 ms outer samples: before each outer sample a running
program gets 1000 µs of lines (a line that runs past the outer sample takes its overrun from
the next one). The registers it reads are those the last outer sample left (so a
jump on an input reads INPUTS, the filtered inputs of §2.2.6, and a wait for a register sees it
as the firmware updates it); a line that waits (for time, an input, a register, in-position)
re-tests every pass, and as nothing changes between two outer samples, it holds the program
until the next one. An edge ("falling"/"rising") is a change since the previous pass (§9.7.11:
"the transition must have taken place during the last 30 microseconds"): a wait sees every
edge, a jump only one that happened just before it ran, in the first pass after an outer sample.

A move that waits tests the in-position bit (STATUSBITS bit 4, §8.2.24) from the next outer
sample on, when the firmware has taken the new target; so do the zero search (until MODE_REG
leaves 13/14) and the moves that always wait (§9.7.5, §9.7.6, §9.7.8). A fatal error leaves the
motor passive, never in position: the program stays at the move until the motor is reset
(§9.7.5).

Program states (§18.2.10): 0 passive, 1 running, 2 single step, 3 paused, 5 program overflow
(the program pointer ran past the last line), 6 invalid instruction, 7 stopped, 9 starting,
11 flash checksum error. States 4, 5, 6, 10 and 11 are errors.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from ....physics.fixed import wrap32
from ....registers import RegisterError
from .. import constants as c
from .. import layout as L
from ..firmware import regs as R
from ..table import TABLE
from .binary import checksum, decode_command, decode_program, encode_program
from .commands import FASTMAC_GROUPS, Command, cost_us
from .fields import INPUT_NAMES, FieldError

__all__ = ["ProgramRunner", "ProgramStatus", "STATE_NAMES", "ERROR_STATES", "PASS_US",
           "SAMPLE_US"]

REFUSALS_KEPT = 100  #: refused writes remembered (the latest)
PASS_US = 30  #: one main-loop pass (§9.9: "approximately 30 microseconds")
SAMPLE_US = 1000  #: main-loop time between two outer samples of the simulated firmware


class ProgramHost(Protocol):
    """What the executor uses of the MIS motor array (:class:`~..motors.MisMotorArray`, which
    runs the executor): its register banks and state rows (N, ·), and a validated write."""

    regs: np.ndarray
    state: np.ndarray

    def write_raw(self, key: Any, raw: Any, index: Any = None) -> None: ...


STATE_NAMES = {0: "passive", 1: "running", 2: "single step", 3: "paused", 4: "stack overflow",
               5: "program overflow", 6: "invalid instruction", 7: "stopped",
               8: "communication error", 9: "starting program", 10: "flash error",
               11: "flash checksum error"}
PASSIVE, RUNNING, SINGLE_STEP, PAUSED, STACK_OVERFLOW, PROGRAM_OVERFLOW, INVALID, STOPPED = \
    range(8)
STARTING, FLASH_ERROR, CHECKSUM_ERROR = 9, 10, 11
ERROR_STATES = frozenset({STACK_OVERFLOW, PROGRAM_OVERFLOW, INVALID, FLASH_ERROR,
                          CHECKSUM_ERROR})

_MODES = {"passive": c.PASSIVE, "velocity": c.VELOCITY, "position": c.POSITION,
          "gear": c.GEAR}
_POS_REG = {f"register{k}": TABLE.lookup(f"P{k}").number for k in (1, 2, 3)}
_P1 = _POS_REG["register1"]
_P_NEW = R.P_NEW
_I32 = 2**31 - 1


@dataclass(frozen=True)
class ProgramStatus:
    """What the program status command reports (§18.2.10) and the line it means.

    Attributes
    ----------
    state : int
        Program state code (§18.2.10 table).
    name : str
        Its name.
    line : int
        Program line the pointer is at (1-based; 0: no program).
    error : bool
        The program stopped on an error (states 4, 5, 6, 10, 11).
    checksum : int
        16-bit sum of the program bytes (computed when the program is started).
    """

    state: int
    name: str
    line: int
    error: bool
    checksum: int


def _word(regs) -> int:
    """Inputs 1–8, Motor Error and In Position as bits 0–9 (§9.7.11)."""
    return (int(regs[R.INPUTS]) & 0xFF) | ((regs[R.ERR_BITS] != 0) << 8) | (
        (int(regs[R.STATUSBITS]) & c.ST_IN_POSITION != 0) << 9)


def _compare(a: int, op: str, b: int) -> bool:
    return {"=": a == b, "!=": a != b, "<": a < b, ">": a > b, "<=": a <= b,
            ">=": a >= b}[op]


class ProgramRunner:
    """The program of one motor: its flash copy and the executor's state.

    Parameters
    ----------
    cmds : sequence of Command
        The program (checked by :func:`.format.parse_program`).
    image : tuple (bytes, int), optional
        Flash bytes and their stored checksum instead (a flash image: bytes that are no
        program stop it with "flash error" when it starts, a checksum that does not match with
        "flash checksum error").
    """

    def __init__(self, cmds: Sequence[Command],
                 image: tuple[bytes, int] | None = None) -> None:
        self.cmds = list(cmds)
        self.flash = encode_program(self.cmds) if image is None else bytes(image[0])
        self.stored_checksum = checksum(self.flash) if image is None else image[1]
        self.corrupt = False
        if image is not None:
            try:
                self.cmds = decode_program(self.flash)
            except FieldError:
                self.corrupt = True
        self.state = STOPPED
        self.pc = 0
        self.sum = 0
        self.seen = 0  # input word at the previous pass
        self.area = (0, 0)  # lines a single step runs in
        self.carry = 0  # µs of the last line that ran into the next outer sample
        self.wait: str | None = None  # what the line at pc waits for
        self.wait_tick = 0  # first tick the wait may end (or the wait-ms deadline)
        self.search = 0  # move_sensor: 0 searching, 1 target set
        self.changed = False  # move_relative_change: new velocity given
        self.start_pos = 0
        self.pulses: dict[int, tuple[int, bool]] = {}  # output bit → (end tick, level after)
        self.refusals: deque[str] = deque(maxlen=REFUSALS_KEPT)

    # ------------------------------------------------------------------ control
    @property
    def active(self) -> bool:
        """Whether the program runs (or runs a single step, or is being started)."""
        return self.state in (RUNNING, SINGLE_STEP, STARTING) or bool(self.pulses)

    def start(self, resume: bool = True) -> None:
        """Program command 1 (§18.2.10): a paused program resumes (``resume``), else the
        program starts at line 1 (state "starting program", running from the next pass)."""
        if resume and self.state == PAUSED:
            self.state = RUNNING
            return
        self.pc = 0
        self.wait = None
        self.state = STARTING

    def stop(self) -> None:
        """Program command 2: stopped."""
        self.state = STOPPED
        self.wait = None

    def pause(self) -> None:
        """Program command 3: paused, can be resumed."""
        if self.state in (RUNNING, SINGLE_STEP, STARTING):
            self.state = PAUSED

    def run_area(self, first: int, last: int) -> None:
        """Program command 4: run until the pointer is outside lines ``first`` … ``last``
        (1-based), then pause."""
        if self.state == STARTING:
            self.pc = 0
        self.area = (first, last)
        self.state = SINGLE_STEP

    def step_line(self) -> None:
        """Run the line at the pointer, then pause (command 4 with the area of that line)."""
        line = (0 if self.state == STARTING else self.pc) + 1
        self.run_area(line, line)

    def status(self) -> ProgramStatus:
        return ProgramStatus(self.state, STATE_NAMES[self.state], self.pc + 1,
                             self.state in ERROR_STATES, self.sum)

    # ------------------------------------------------------------------ main loop
    def sample(self, m: ProgramHost, i: int) -> None:
        """The main-loop passes before one outer sample of motor ``i``."""
        regs = m.regs[i]
        tick = int(m.state[i, L.S_TICK])
        if self.pulses:
            self._end_pulses(m, i, tick)
        if self.state == STARTING:
            self.sum = checksum(self.flash)
            if self.sum != self.stored_checksum:
                self.state = CHECKSUM_ERROR
                return
            self.state = RUNNING
            self.seen = _word(regs)
        if self.state not in (RUNNING, SINGLE_STEP):
            return
        if self.corrupt:
            self.state = FLASH_ERROR
            return
        word = _word(regs)
        used, self.carry = self.carry, 0
        while used < SAMPLE_US and self.state in (RUNNING, SINGLE_STEP):
            if self.pc >= len(self.cmds):
                self.state = PROGRAM_OVERFLOW
                break
            prev, self.seen = self.seen, word
            if self.wait is not None:
                if not self._waited(m, i, regs, tick, prev, word):
                    break
                used += PASS_US
            else:
                cmd = self.cmds[self.pc]
                used += max(cost_us(cmd), 1)
                self._run(m, i, cmd, regs, tick, prev, word)
            if self.state == SINGLE_STEP and self.wait is None and not (
                    self.area[0] <= self.pc + 1 <= self.area[1]):
                self.state = PAUSED
            if self.wait is not None and self.wait_tick > tick:
                break  # the line waits for a later outer sample
        else:
            self.carry = max(used - SAMPLE_US, 0)  # a line that ran past the outer sample

    def _end_pulses(self, m: ProgramHost, i: int, tick: int) -> None:
        for bit, (end, level) in list(self.pulses.items()):
            if tick >= end:
                self._output(m, i, bit, level)
                del self.pulses[bit]

    # ------------------------------------------------------------------ registers
    def _write(self, m: ProgramHost, i: int, num: int, value: int) -> None:
        """A register write by the firmware's rules; a refused write changes nothing and the
        program goes on (the refusal is kept in :attr:`refusals`)."""
        reg = TABLE.lookup(num)
        value = min(max(int(value), reg.raw_min), reg.raw_max)
        try:
            m.write_raw(num, value, index=i)
        except (RegisterError, ValueError) as exc:
            self.refusals.append(f"line {self.pc + 1}: {exc}")

    def _output(self, m: ProgramHost, i: int, bit: int, high: bool) -> None:
        out = int(m.regs[i, R.OUTPUTS])
        m.regs[i, R.OUTPUTS] = (out | bit) if high else (out & ~bit)

    def _source(self, regs, value: object) -> int:
        if isinstance(value, str):
            return int(regs[_POS_REG[value]])
        return int(value)  # type: ignore[call-overload]

    def _test(self, cmd: Command, prev: int, word: int) -> bool:
        """An input condition of a jump, wait or sensor move."""
        if "inputs" in cmd.values:
            hits = [bool(word >> INPUT_NAMES.index(n) & 1) == (lv == "high")
                    for n, lv in cmd["inputs"]]  # type: ignore[attr-defined]
            return all(hits) if cmd["operand"] == "and" else any(hits)
        bit = 1 << INPUT_NAMES.index(str(cmd["input"]))
        now, was = bool(word & bit), bool(prev & bit)
        return {"low": not now, "high": now, "falling": was and not now,
                "rising": now and not was}[str(cmd["condition"])]

    # ------------------------------------------------------------------ lines
    def _next(self) -> None:
        self.pc += 1
        self.wait = None

    def _jump(self, cmd: Command, taken: bool) -> None:
        if taken:
            self.pc = int(cmd["line"]) - 1  # type: ignore[call-overload]
            self.wait = None
        else:
            self._next()

    def _profile(self, m: ProgramHost, i: int, cmd: Command) -> None:
        """V_SOLL and A_SOLL from a move's fields (0: keep, §9.7.4)."""
        if cmd["velocity"]:
            self._write(m, i, R.V_SOLL, int(cmd["velocity"]))  # type: ignore[call-overload]
        if cmd["acceleration"]:
            self._write(m, i, R.A_SOLL, int(cmd["acceleration"]))  # type: ignore[call-overload]

    def _relative(self, m: ProgramHost, i: int, regs, distance: int) -> None:
        """P1 := distance; P_SOLL := P_IST + P1 (§9.7.4: "Register no. 49 (P1) is always
        overwritten by this command")."""
        regs[_P1] = distance
        self._write(m, i, R.P_SOLL, wrap32(int(regs[R.P_IST]) + distance))

    def _await(self, what: str, tick: int, delay: int = 1) -> None:
        self.wait = what
        self.wait_tick = tick + delay

    def _run(self, m: ProgramHost, i: int, cmd: Command, regs, tick: int, prev: int,
             word: int) -> None:
        k = cmd.keyword
        v = cmd.values
        if k == "remark":
            self._next()
        elif k == "mode":
            self._write(m, i, R.MODE_REG, _MODES[str(v["mode"])])
            self._next()
        elif k in ("move_relative", "move_relative_change", "move_relative_outputs"):
            self._profile(m, i, cmd)
            self._relative(m, i, regs, self._source(regs, v["distance"]))
            self.changed = False
            if k == "move_relative" and v["wait"] == "no":
                self._next()
            else:
                self._await(k, tick)
        elif k == "move_absolute":
            self._profile(m, i, cmd)
            self._write(m, i, R.P_SOLL, self._source(regs, v["position"]))
            if v["wait"] == "no":
                self._next()
            else:
                self._await(k, tick)
        elif k == "move_sensor":
            self._profile(m, i, cmd)
            distance = self._source(regs, v["distance"])
            safety = abs(self._source(regs, v["safety_distance"])) or _I32
            regs[_P1] = distance
            self.start_pos = int(regs[R.P_IST])
            self.search = 0
            way = -1 if distance < 0 else 1
            self._write(m, i, R.P_SOLL, wrap32(self.start_pos + way * safety))
            self._await(k, tick)
        elif k == "set_output":
            bit = 1 << (int(v["output"]) - 1)  # type: ignore[call-overload]
            state = str(v["state"])
            if state.endswith("_pulse"):
                high = state == "high_pulse"
                self._output(m, i, bit, high)
                self.pulses[bit] = (tick + int(v["pulse_ms"]), not high)  # type: ignore[call-overload]
            else:
                self._output(m, i, bit, state == "high")
                self.pulses.pop(bit, None)
            self._next()
        elif k == "set_outputs":
            self._set_outputs(m, i, v["outputs"])
            self._next()
        elif k == "jump":
            self._jump(cmd, True)
        elif k in ("jump_input", "jump_inputs"):
            self._jump(cmd, self._test(cmd, prev, word))
        elif k == "wait_ms":
            self._await(k, tick, int(v["time"]))  # type: ignore[call-overload]
            if int(v["time"]) == 0:  # type: ignore[call-overload]
                self._next()
        elif k in ("wait_input", "wait_inputs", "wait_register"):
            self._await(k, tick, 0)
            if self._waited(m, i, regs, tick, prev, word):
                return
        elif k == "set_register":
            self._write(m, i, int(v["register"]), int(v["value"]))  # type: ignore[call-overload]
            self._next()
        elif k == "jump_register":
            self._jump(cmd, _compare(int(regs[int(v["register"])]), str(v["operator"]),  # type: ignore[call-overload]
                                     int(v["value"])))  # type: ignore[call-overload]
        elif k == "jump_compare":
            self._jump(cmd, _compare(int(regs[int(v["register"])]), str(v["operator"]),  # type: ignore[call-overload]
                                     int(regs[int(v["register2"])])))  # type: ignore[call-overload]
        elif k == "save_position":
            regs[_POS_REG[str(v["register"])]] = regs[R.P_IST]
            self._next()
        elif k == "set_position":
            regs[_P_NEW] = self._source(regs, v["position"])
            self._write(m, i, R.COMMAND, c.CMD_SET_POSITION)
            self._next()
        elif k == "zero_search":
            self._write(m, i, R.MODE_REG, c.ZERO_SEARCH_1 if v["mode"] == "sensor1"
                        else c.ZERO_SEARCH_2)
            self._await(k, tick)
        elif k == "fastmac":
            prefix, _, target = FASTMAC_GROUPS[str(v["register"])]
            self._write(m, i, R.MODE_REG, _MODES[str(v["mode"])])
            self._write(m, i, TABLE.lookup(target).number,
                        int(regs[TABLE.lookup(f"{prefix}{v['number']}").number]))
            self._next()
        elif k == "fastmac_command":
            self._write(m, i, R.COMMAND, 96 + int(v["command"]))  # type: ignore[call-overload]
            self._next()
        elif k == "binary":
            try:
                inner = decode_command(bytes.fromhex(str(v["code"])))
            except FieldError:
                self.state = INVALID
                return
            self._run(m, i, inner, regs, tick, prev, word)
        elif k == "calculate":
            self._write(m, i, int(v["register"]), _calculate(regs, v["expression"]))  # type: ignore[call-overload]
            self._next()
        else:  # pragma: no cover - every keyword of SPECS is handled above
            self.state = INVALID

    def _set_outputs(self, m: ProgramHost, i: int, pattern: object) -> None:
        for name, level in pattern:  # type: ignore[attr-defined]
            bit = 1 << (int(name) - 1)
            self.pulses.pop(bit, None)
            self._output(m, i, bit, level == "high")

    def _in_position(self, regs) -> bool:
        return bool(int(regs[R.STATUSBITS]) & c.ST_IN_POSITION)

    def _waited(self, m: ProgramHost, i: int, regs, tick: int, prev: int, word: int) -> bool:
        """Test the wait of the line at pc; True (and the program goes on) when it ends."""
        what = self.wait
        cmd = self.cmds[self.pc]
        if cmd.keyword == "binary":
            cmd = decode_command(bytes.fromhex(str(cmd["code"])))
        if tick < self.wait_tick:
            return False
        done = False
        if what == "wait_ms":
            done = True
        elif what in ("wait_input", "wait_inputs"):
            done = self._test(cmd, prev, word)
        elif what == "wait_register":
            done = _compare(int(regs[int(cmd["register"])]), str(cmd["operator"]),  # type: ignore[call-overload]
                            int(cmd["value"]))  # type: ignore[call-overload]
        elif what == "zero_search":
            done = int(regs[R.MODE_REG]) not in (c.ZERO_SEARCH_1, c.ZERO_SEARCH_2)
        elif what == "move_sensor":
            if self.search == 0:
                if self._test(cmd, prev, word):
                    self._sensor_hit(m, i, cmd, regs)
                    self.wait_tick = tick + 1
                    return False
            done = self._in_position(regs)
        elif what == "move_relative_change":
            left = abs(wrap32(int(regs[R.P_SOLL]) - int(regs[R.P_IST])))
            if not self.changed and left <= self._source(regs, cmd["change_distance"]):
                self.changed = True
                if cmd["new_velocity"]:
                    self._write(m, i, R.V_SOLL, int(cmd["new_velocity"]))  # type: ignore[call-overload]
            done = self._in_position(regs)
        else:  # move_relative, move_absolute, move_relative_outputs
            done = self._in_position(regs)
            if done and what == "move_relative_outputs":
                self._set_outputs(m, i, cmd["outputs"])
        if done:
            self._next()
        return done

    def _sensor_hit(self, m: ProgramHost, i: int, cmd: Command, regs) -> None:
        """The sensor condition is met: stop ``distance`` further on, but not past the
        safety distance from the start (§9.7.8)."""
        self.search = 1
        distance = int(regs[_P1])
        target = int(regs[R.P_IST]) + distance
        safety = abs(self._source(regs, cmd["safety_distance"]))
        if safety:
            lo, hi = self.start_pos - safety, self.start_pos + safety
            target = min(max(target, lo), hi)
        self._write(m, i, R.P_SOLL, wrap32(target))


def _calculate(regs, terms: object) -> int:
    """Left to right in 32-bit signed arithmetic (§9.7.25: "Arithmetic operations take place in
    the order that they are specified"; overflow wraps); division truncates towards zero and a
    division by zero gives 0 (the integer divide of the firmware's 32-bit processor)."""
    acc = 0
    for op, kind, value in terms:  # type: ignore[attr-defined]
        x = int(regs[value]) if kind == "reg" else int(value)
        if op == "":
            acc = x
        elif op == "+":
            acc = wrap32(acc + x)
        elif op == "-":
            acc = wrap32(acc - x)
        elif op == "*":
            acc = wrap32(acc * x)
        else:
            acc = 0 if x == 0 else wrap32(int(abs(acc) // abs(x)) * (1 if (acc < 0) == (x < 0)
                                                                     else -1))
    return acc

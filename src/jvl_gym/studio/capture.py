"""The motor's sample buffer and its TESTU/TESTA records, as the studio triggers them.

The recipe is read from the register table, so it is the same for a simulated motor and a motor
on a line:

* a table with ``S_CONTROL`` (MIS manual §8.2.60–8.2.63): SAMPLE1–4 name the registers,
  REC_CNT the number of samples, S_TIME the interval [ms]; S_CONTROL = 1 initialises, 2 starts,
  and the firmware sets it back to 0 when the samples are taken;
* otherwise the RECORD and REWIND bits of the control-bit register (MAC050–141 manual
  3.2.36, 3.2.112–3.2.116: REWIND sets REC_CNT = 0; while RECORD is set each sample of
  SAMPLE1–4 is stored at REC_CNT, which then counts up).

TESTU and TESTA (MAC050–141 manual 4.4.9, 4.4.10) start from mode 0 with their parameters
written and end back in mode 0 with their record in the buffer.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence

import numpy as np

from ..registers import RegisterTable
from .bits import bit_of
from .motor import StudioMotor
from .trigger import TIME, Trigger, crossing_time, find_trigger

__all__ = ["CaptureError", "control_register", "capture", "run_test", "triggered"]


class CaptureError(RuntimeError):
    """A capture the motor cannot do or that did not finish (one line, what to do)."""


def control_register(table: RegisterTable) -> tuple[str, int, int] | None:
    """(register name, RECORD bit, REWIND bit) of the control-bit register, or None."""
    for reg in table:
        rec, rew = bit_of(reg, "RECORD"), bit_of(reg, "REWIND")
        if rec is not None and rew is not None:
            return reg.name, rec, rew
    return None


def _wait(motor: StudioMotor, done: callable, seconds: float, what: str) -> None:
    end = time.monotonic() + seconds
    while not done():
        if time.monotonic() > end:
            raise CaptureError(f"{motor.label}: {what} did not finish within {seconds:.1f} s "
                               "(is the simulation paused or the motor gone?)")
        time.sleep(0.02)


def capture(motor: StudioMotor, registers: Sequence[str], samples: int,
            timeout: float | None = None) -> dict[str, np.ndarray]:
    """Record ``samples`` samples of up to four ``registers`` in the motor's sample buffer and
    read it back: ``"t [s]"`` and ``"<register> [<unit>]"`` → values in the register's unit.

    Raises
    ------
    CaptureError
        The family has no sample buffer, or the record did not finish.
    RegisterError
        A register, or a sample count, the motor refuses (nothing recorded).
    """
    table = motor.table
    names = [motor.register(r).name for r in registers][:4]
    if not names:
        raise CaptureError("pick one to four registers to record")
    for k in range(4):
        motor.register(f"SAMPLE{k + 1}")  # the family has the buffer's channel registers
    numbers = [motor.register(n).number for n in names]
    numbers += [numbers[-1]] * (4 - len(numbers))
    interval = 1.0 / motor.facts.outer_hz
    timeout = timeout if timeout is not None else 5.0 + 3.0 * samples * interval
    if "S_CONTROL" in {r.name for r in table}:
        rec_cnt = motor.register("REC_CNT")
        if not 1 <= samples <= rec_cnt.maximum:
            raise CaptureError(f"samples: 1..{int(rec_cnt.maximum)} (REC_CNT)")
        for k, n in enumerate(numbers):
            motor.write(f"SAMPLE{k + 1}", n)
        motor.write("REC_CNT", samples)
        interval = motor.read("S_TIME") * 1e-3
        motor.write("S_CONTROL", 1)
        motor.write("S_CONTROL", 2)
        _wait(motor, lambda: motor.read_raw("S_CONTROL") == 0,
              5.0 + 3.0 * samples * interval, "the sample buffer record")
    else:
        ctl = control_register(table)
        if ctl is None:
            raise CaptureError(f"{motor.label}: the {motor.facts.title} have no sample buffer")
        name, rec, rew = ctl
        depth = int(motor.register("REC_CNT").maximum)
        if not 1 <= samples <= depth:
            raise CaptureError(f"samples: 1..{depth} (the buffer's depth, REC_CNT)")
        for k, n in enumerate(numbers):
            motor.write(f"SAMPLE{k + 1}", n)
        with motor.lock:
            bits = motor.read_raw(name) & ~(1 << rec)
            motor.write(name, bits | (1 << rew))
            motor.write(name, (motor.read_raw(name) & ~(1 << rew)) | (1 << rec))
        _wait(motor, lambda: motor.read_raw("REC_CNT") >= samples, timeout,
              "the sample buffer record")
        with motor.lock:
            motor.write(name, motor.read_raw(name) & ~(1 << rec))
    buf = motor.sample_buffer()
    count = min(len(v) for v in buf.values()) if buf else 0
    count = min(count, samples)
    out = {"t [s]": np.arange(count) * interval}
    for k, (key, values) in enumerate(buf.items()):
        if k < len(names):
            out[_label(motor, key)] = np.asarray(values, dtype=float)[:count]
    return out


def _label(motor: StudioMotor, key: str) -> str:
    """``"<register> [<unit>]"`` for a buffer channel named by its register, else ``key``."""
    try:
        unit = motor.register(key).unit
    except KeyError:
        return key
    return f"{key} [{unit}]" if unit else key


def run_test(motor: StudioMotor, test: str, setup: Mapping[str, float],
             timeout: float = 10.0) -> dict[str, np.ndarray]:
    """Run the family's ``test`` (``"TESTU"`` or ``"TESTA"``) from mode 0 and return its
    record (MAC050–141 manual 4.4.9, 4.4.10).

    Raises
    ------
    CaptureError
        The family has no such test mode, the motor is not in mode 0, or the test did not end.
    """
    modes = motor.facts.test_modes()
    if test not in modes:
        raise CaptureError(f"{motor.label}: the {motor.facts.title} have no {test} mode")
    mode_reg = motor.facts.mode_register
    if motor.read_raw(mode_reg) != 0:
        raise CaptureError(f"{test} starts from mode 0 ({motor.facts.mode_name(0)}; "
                           "MAC050–141 manual 4.4.9, 4.4.10): press 'passive' first")
    for name, value in setup.items():
        motor.write(name, value)
    motor.write(mode_reg, modes[test])
    _wait(motor, lambda: motor.read_raw(mode_reg) == 0, timeout, test)
    buf = motor.sample_buffer()
    n = min(len(v) for v in buf.values()) if buf else 0
    out = {"sample": np.arange(n, dtype=float)}
    out.update({_label(motor, k): np.asarray(v, dtype=float)[:n] for k, v in buf.items()})
    return out


def triggered(series: Mapping[str, np.ndarray], trigger: Trigger) -> dict[str, np.ndarray]:
    """A captured ``series`` (:func:`capture`) on the live scope's trigger: the whole record
    with time 0 at the first crossing of the trigger's level on its edge
    (:func:`.trigger.find_trigger`, :func:`.trigger.crossing_time`), the samples at the
    firmware's exact interval.

    Raises
    ------
    CaptureError
        The record does not cross the level on the edge, or has no such channel.
    """
    if trigger.channel not in series:
        raise CaptureError(f"no channel {trigger.channel!r} in the record to trigger on")
    t = np.asarray(series[TIME], dtype=float)
    v = np.asarray(series[trigger.channel], dtype=float)
    k = find_trigger(v, trigger)
    if k is None:
        raise CaptureError(f"{trigger.channel} does not cross {trigger.level:g} "
                           f"({trigger.edge.value}) in the record")
    t0 = crossing_time(t, v, k, trigger.level)
    out = {key: np.asarray(a, dtype=float) for key, a in series.items()}
    out[TIME] = t - t0
    return out

"""The serial link to a motor, measured: how much motor time a request's round trip costs.

A procedure that acts on what it reads (the brake of the resonance step,
:mod:`tuning.identify_resonance`) works only while the motor does not move far between the read
and the write that answers it.
Over a serial line a MacTalk round trip (MAC050–141 manual 5.1: request, then the motor's
reply) takes milliseconds; the twin ``jvl-gym serve --speed S`` runs S motor seconds per
wall-clock second, so there a round trip costs S times its wall-clock time. The link is measured
by timing a few register reads just before the step that needs it, and the step compares the
motor time of a round trip with what its timing allows, refusing in one line
(:class:`LinkTooSlow`) rather than reporting what it did not measure.

The measured round trip also sets how long a request waits for its answer
(:func:`reply_timeout`): :data:`TIMEOUT_ROUND_TRIPS` round trips, never less than the client's
own timeout. Over a slow link a fixed timeout sends requests again whose answers are only late:
each request sent again costs the link once more, and a MacTalk answer does not say which request
it answers (MAC050–141 manual 5.1).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

from .records import RecordError

__all__ = ["LinkTiming", "LinkTooSlow", "measure_link", "reply_timeout", "LINK_READS",
           "TIMEOUT_ROUND_TRIPS"]

#: register reads timed per measurement
LINK_READS: int = 8
#: measured round trips a request waits for its answer before it is sent again
TIMEOUT_ROUND_TRIPS: float = 20.0


class LinkTooSlow(RecordError):
    """The link's round trip is too long for the timing a step of the procedure needs."""


@dataclass(frozen=True)
class LinkTiming:
    """A measured link.

    Attributes
    ----------
    wall_s : float
        Round trip of a register read [wall-clock s]: the second longest of the reads timed
        (one slow read, e.g. a pause of this process, does not decide; several do).
    median_s : float
        Median round trip [wall-clock s].
    motor_s : float
        Motor time that passes during ``wall_s`` [s] (0 where the caller advances the motor's
        clock itself: a simulated clock).
    """

    wall_s: float
    median_s: float
    motor_s: float

    def describe(self) -> str:
        """One phrase: the round trip in wall-clock and motor time."""
        return (f"a register read's round trip takes {1e3 * self.wall_s:.2f} ms "
                f"({1e3 * self.motor_s:.2f} ms of motor time)")


def measure_link(m: Any, reads: int = LINK_READS, register: str = "MODE_REG") -> LinkTiming:
    """Time ``reads`` reads of ``register`` on ``m`` (a :class:`tuning.serial_source.SerialMotor`
    or anything with ``read`` and ``motor_seconds``; a simulator without ``motor_seconds``
    costs no motor time)."""
    times = []
    for _ in range(max(int(reads), 2)):
        t0 = time.perf_counter()
        m.read(register)
        times.append(time.perf_counter() - t0)
    times.sort()
    wall = times[-2]
    to_motor = getattr(m, "motor_seconds", None)
    return LinkTiming(wall, times[len(times) // 2], 0.0 if to_motor is None else to_motor(wall))


def reply_timeout(timing: LinkTiming, floor: float) -> float:
    """Seconds a request waits for its answer over the measured link: :data:`TIMEOUT_ROUND_TRIPS`
    round trips (``timing.wall_s``), at least ``floor`` (the client's own timeout)."""
    return max(float(floor), TIMEOUT_ROUND_TRIPS * timing.wall_s)

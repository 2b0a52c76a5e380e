"""The sample buffer as MacTalk reads it (53h, MAC050–141 manual 5.1; the 32-bit MacTalk the
same): one sample per request, from the first on.

Each motor has a cursor: a request returns the sample under it (SAMPLE1…4 as four 32-bit values,
low byte first, 16 bytes) and moves it on; after the last of the recorded samples a request
returns nothing (an empty reply) and the cursor starts again from the first. A reset, or a
write that starts a new recording (CNTRL_BITS, MODE_REG, REC_CNT), restarts it.
"""

from __future__ import annotations

from typing import Any

from .codec16 import long_to_bytes

__all__ = ["SampleCursor"]


class SampleCursor:
    """The 53h read cursor of every motor of ``motors`` (anything with ``n`` and
    ``sample_buffer_raw(index)``, a :class:`~jvl_gym.MotorArray`)."""

    def __init__(self, motors: Any) -> None:
        self.m = motors
        self.position = [0] * motors.n

    def restart(self, i: int) -> None:
        """The next request of motor ``i`` reads its first sample."""
        self.position[i] = 0

    def next(self, i: int) -> bytes:
        """The data of the next sample of motor ``i`` (16 bytes), or b"" after the last."""
        buf = self.m.sample_buffer_raw(i)
        k = self.position[i]
        if k >= len(buf):
            self.position[i] = 0
            return b""
        self.position[i] = k + 1
        return b"".join(long_to_bytes(int(v) & 0xFFFFFFFF) for v in buf[k])

"""NMT states, boot-up, heartbeat and node guarding of a node (MIS manual §11.9.2, §11.9.6,
§11.9.7, §11.4.3).

=====================  ==============================================================
boot-up                ``700h + node id``, one byte 0, after power-on and every reset
NMT command (COB 0)    byte 0: 1 start, 2 stop, 128 pre-operational, 129 reset node,
                       130 reset communication; byte 1: node id or 0 for all
heartbeat              ``700h + node id``, the state byte (4 stopped, 5 operational,
                       127 pre-operational) every 1017h ms while 1017h ≠ 0
node guarding          an RTR on ``700h + node id`` is answered with the state and a toggle
                       bit (bit 7, 0 in the first answer, reset only by reset communication);
                       once guarded, no request within 100Ch × 100Dh ms is a life guarding
                       event (EMCY 8130h, "node guard fail", §11.4.2)
=====================  ==============================================================

Only one of heartbeat and node guarding is active: the heartbeat when 1017h ≠ 0 (§11.9.7).
Neither is enabled at start-up (§11.9.7). Times are the node's simulated milliseconds.
"""

from __future__ import annotations

import enum

__all__ = ["NmtState", "NmtCommand", "Guarding", "Heartbeat", "BOOTUP_COB", "NMT_COB"]

#: COB-ID base of boot-up, heartbeat and node guarding; COB-ID of NMT commands
BOOTUP_COB, NMT_COB = 0x700, 0x000


class NmtState(enum.IntEnum):
    """Communication states and their code in heartbeat and guarding (§11.9.7)."""

    INITIALISING = 0
    STOPPED = 4
    OPERATIONAL = 5
    PRE_OPERATIONAL = 127


class NmtCommand(enum.IntEnum):
    """NMT command specifiers (§11.9.6)."""

    START = 1
    STOP = 2
    PRE_OPERATIONAL = 128
    RESET_NODE = 129
    RESET_COMMUNICATION = 130


class Heartbeat:
    """Heartbeat producer: due times of the heartbeat of period ``period_ms`` (0: none)."""

    def __init__(self) -> None:
        self.period_ms = 0
        self.next_ms: int | None = None

    def configure(self, period_ms: int, now_ms: int) -> None:
        """A new producer time (1017h): the first heartbeat one period from now."""
        self.period_ms = int(period_ms)
        self.next_ms = now_ms + self.period_ms if self.period_ms else None

    def due(self, now_ms: int) -> bool:
        """Whether a heartbeat is due at ``now_ms`` (then the next one is scheduled)."""
        if self.next_ms is None or now_ms < self.next_ms:
            return False
        self.next_ms += self.period_ms
        return True


class Guarding:
    """Node guarding and life guarding of a node (§11.4.3, §11.9.7)."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """Reset communication: toggle 0, no guarding yet."""
        self.toggle = 0
        self.last_ms: int | None = None
        self.failed = False

    def answer(self, state: NmtState, now_ms: int) -> bytes:
        """The answer to a guarding request at ``now_ms``: state with the toggle bit."""
        data = bytes((int(state) & 0x7F | self.toggle << 7,))
        self.toggle ^= 1
        self.last_ms = now_ms
        self.failed = False
        return data

    def lost(self, guard_ms: int, factor: int, now_ms: int) -> bool:
        """Whether the life time (``guard_ms`` × ``factor``) has just run out since the last
        request (once per loss; never before the first request, or when either is 0)."""
        life = int(guard_ms) * int(factor)
        if not life or self.last_ms is None or self.failed:
            return False
        if now_ms - self.last_ms > life:
            self.failed = True
            return True
        return False

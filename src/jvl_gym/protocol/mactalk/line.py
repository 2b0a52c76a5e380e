"""Motors of several families on one serial line, each in its own MacTalk dialect.

A :class:`Bus` holds one :class:`~.twin16.Twin` per family (each twin: a ``MotorArray`` of that
family and the dialect its family declares, :mod:`.dialect`). Every byte the master sends reaches
every unit, as on an RS-485 line: a :class:`BusSession` feeds each chunk to the session of every
twin, and each twin decodes it in its own dialect and answers only the frames addressed to one of
its motors. A frame of another dialect that a unit cannot parse (a MAC050–141 sees a 59h group
write as garbage) is counted in that twin's ``errors`` and changes nothing. A broadcast (FFh) is
carried out by every unit and answered by none, as several units would answer at once.

Examples
--------
>>> from jvl_gym import MotorArray
>>> bus = Bus([Twin(MotorArray("MAC140", n=1, seed=0), [19])])
>>> bus.addresses()
[19]
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

from .twin16 import Twin, UserInterfaceSession

__all__ = ["Bus", "BusSession"]


class Bus:
    """Twins of several families on one line.

    Parameters
    ----------
    twins : sequence of Twin
        At least one; their motors' addresses (MYADDR) must differ.

    Attributes
    ----------
    twins : list of Twin
    user : list of UserInterfaceSession
        The FastMAC/FlexMAC user interfaces of all motors, twin by twin.
    """

    def __init__(self, twins: Sequence[Twin]) -> None:
        self.twins = list(twins)
        if not self.twins:
            raise ValueError("a bus needs at least one twin")
        seen: dict[int, int] = {}
        for k, twin in enumerate(self.twins):
            for a in twin.addresses():
                if a in seen:
                    raise ValueError(f"address {a} is used by two motors on the bus (twins "
                                     f"{seen[a]} and {k}); give every motor its own address")
                seen[a] = k
        alone = sum(t.m.n for t in self.twins) == 1
        for twin in self.twins:
            twin.alone = alone
        self.user: list[UserInterfaceSession] = [u for t in self.twins for u in t.user]

    @property
    def stats(self) -> Counter[str]:
        """The twins' statistics added up."""
        total: Counter[str] = Counter()
        for twin in self.twins:
            total.update(twin.stats)
        return total

    def addresses(self) -> list[int]:
        """MYADDR of every motor now, twin by twin."""
        return [a for t in self.twins for a in t.addresses()]

    def advance(self, seconds: float) -> None:
        """Advance every twin by ``seconds`` of simulated time (each at its own sample rate)."""
        for twin in self.twins:
            twin.advance(seconds)

    def warm_up(self) -> None:
        """Make every twin's motors ready to answer at once (:meth:`MotorTwin.warm_up`)."""
        for twin in self.twins:
            twin.warm_up()

    def close(self) -> None:
        """Give up every twin's flash directory (:meth:`MotorTwin.close`)."""
        for twin in self.twins:
            twin.close()

    def session(self) -> BusSession:
        """A new session of the line (one per connection)."""
        return BusSession(self)


class BusSession:
    """One byte stream of the line: every chunk goes to every twin's session; the replies are
    concatenated in twin order."""

    def __init__(self, bus: Bus) -> None:
        self.sessions = [t.session() for t in bus.twins]

    def feed(self, chunk: bytes) -> bytes:
        """Received bytes → the replies they call for."""
        return b"".join(s.feed(chunk) for s in self.sessions)

    def flush(self) -> bytes:
        """Inter-character timeout: every twin's partial frame is truncated."""
        return b"".join(s.flush() for s in self.sessions)

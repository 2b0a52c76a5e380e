"""The python-can bus of a CAN serving side (CANopen, J1939): opened one way, refused in one
line.

Any python-can interface serves: ``socketcan`` on a ``can``/``vcan`` device, ``virtual`` (only
the same process reaches it), or ``udp_multicast``, which carries the frames between the
processes of one host as UDP datagrams to a multicast group (the channel: a group address
such as :data:`DEFAULT_GROUP`). On ``udp_multicast`` the bus is opened loopback only: hop limit
(TTL) 0, so that no frame leaves the host.
"""

from __future__ import annotations

from typing import Any

import can

__all__ = ["open_bus", "UDP_MULTICAST", "DEFAULT_GROUP"]

#: python-can's interface of CAN frames as UDP multicast datagrams
UDP_MULTICAST = "udp_multicast"
#: python-can's default IPv4 group of that interface
DEFAULT_GROUP = "239.74.163.2"


def open_bus(interface: str, channel: str, bitrate: int | None = None) -> can.BusABC:
    """The python-can bus ``interface``/``channel`` (``bitrate`` where the interface sets one;
    ``udp_multicast`` on loopback only).

    Raises
    ------
    ValueError
        The bus cannot be opened (one line: the interface, the channel and python-can's
        reason).
    """
    kw: dict[str, Any] = {"interface": interface, "channel": channel}
    if interface == UDP_MULTICAST:
        kw["hop_limit"] = 0  # the frames stay on this host
    elif bitrate:
        kw["bitrate"] = bitrate
    try:
        return can.Bus(**kw)
    except (can.CanError, OSError, ValueError, ImportError, NotImplementedError,
            TypeError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ValueError(f"cannot open CAN bus {interface}:{channel}: {reason}") from None

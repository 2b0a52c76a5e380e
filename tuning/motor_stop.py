"""Leaving a motor passive after a tuning run over a port, whatever ended the run.

The family's stop is its passive mode (the family contract's ``twin.passive_mode``: INIT_MODE on
the MAC050–141, manual 4.4.1; PASSIVE_MODE on the MAC800): MODE_REG is written to it and read
back until the motor reports it. The firmware takes the way its manual describes: a regulated
mode ramps down through STOP_MODE (MAC050–141 manual 4.4.2, 4.4.12), AT_MODE sets the torque to
0 and goes to INIT below 300 rpm (4.4.5), TESTA brakes (4.4.11), so the read-back may take a
while. Over a slow or broken link the write is sent again, on a new connection when the old one
fails, a few times; when the motor's answer never says passive, :func:`stop_motor` returns why,
and the caller reports it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

__all__ = ["stop_motor", "STOP_ATTEMPTS", "STOP_MOTOR_S"]

#: times the stop is sent (each on a new connection after a failed one)
STOP_ATTEMPTS: int = 4
#: motor time [s] a stop may take to be confirmed (a ramp, or AT_MODE's coast below 300 rpm)
STOP_MOTOR_S: float = 20.0


def stop_motor(m: Any, reconnect: Callable[[], Any] | None = None,
               attempts: int = STOP_ATTEMPTS, within_s: float = STOP_MOTOR_S) -> str | None:
    """Put the motor of ``m`` (a :class:`tuning.serial_source.SerialMotor`) in its family's
    passive mode and confirm it by reading MODE_REG back.

    Parameters
    ----------
    m : SerialMotor
        The motor; ``m.family.twin.passive_mode`` is its stop.
    reconnect : callable, optional
        Returns a new client for ``m`` (``m.client`` is replaced) after the link failed.
    attempts : int
        How often the stop is sent.
    within_s : float
        Motor time [s] the motor may take to reach the passive mode after each write.

    Returns
    -------
    str or None
        None when the motor reported the passive mode; else why it could not be confirmed.
    """
    passive = m.family.twin.passive_mode
    if passive is None:
        return f"the {m.family.title} has no passive mode to stop in"
    why = "no attempt"
    for attempt in range(max(int(attempts), 1)):
        try:
            if attempt and reconnect is not None:
                _replace_client(m, reconnect)
            m.write("MODE_REG", passive)
            mode = _wait_mode(m, passive, within_s)
        except KeyboardInterrupt:
            why = "interrupted again while stopping"
            continue
        except Exception as exc:  # noqa: BLE001  (a broken link: try again, then report)
            why = f"{type(exc).__name__}: {str(exc).splitlines()[0][:200] if str(exc) else ''}"
            continue
        if mode == passive:
            return None
        why = f"MODE_REG still reads {mode}, not the passive mode {passive}"
    return f"{why} (after {max(int(attempts), 1)} attempts)"


def _replace_client(m: Any, reconnect: Callable[[], Any]) -> None:
    old = m.client
    try:
        m.client = reconnect()
    finally:
        close = getattr(old, "close", None)
        if close is not None and m.client is not old:
            try:
                close()
            except Exception:  # noqa: BLE001  (the old link is broken; its close may be too)
                pass


def _wait_mode(m: Any, passive: int, within_s: float) -> int:
    """Read MODE_REG until it is ``passive`` or ``within_s`` of motor time have passed (a ramp
    or a coast); its last value."""
    dt = 0.05  # motor seconds between reads
    waited = 0.0
    wall_end = time.monotonic() + m.wall_seconds(within_s) + 5.0
    while True:
        mode = int(m.read("MODE_REG")[0])
        if mode == passive or waited >= within_s or time.monotonic() > wall_end:
            return mode
        m.wait(dt)
        waited += dt

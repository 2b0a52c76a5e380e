"""The safety supervisor of a deployed policy: what reaches the motor, and how it is stopped.

Every command passes :meth:`Supervisor.command`: the action is clipped to the task's bounds
(:class:`Limits`: each component within [low, high]) and rate limited (it moves at most
``max_step`` per period from the command before), then mapped to register values by the task's
bridge and clipped to each register's range in the family's register table; only then is it
written. The loop's timing is watched by :class:`PolicyRunner`: the policy runs in a thread of
its own and a step it has not finished by the deadline stops the loop. The motor is put passive
by its family's stop, MODE_REG = ``family.twin.passive_mode`` (the power stage off: MAC050–141
manual 4.4.1 INIT_MODE; MAC800 Passive; MIS PASSIVE):

==========================  ================================================================
what fails                  what stops the motor, and when
==========================  ================================================================
the policy stalls           the loop, at the deadline; it writes passive and tells the
                            watchdog to (it writes passive at once on its own connection)
the link drops              the client's time-out (``timeout`` × (1 + ``retries``)); then as
                            above: the loop's own write cannot get through, the watchdog's does
an exception, Ctrl-C,       the loop's ``finally``: passive at once, the watchdog told
SIGTERM
the process is killed       the watchdog process: its end of the heartbeat pipe closes, it
(SIGKILL)                   writes passive at once
the process hangs           the watchdog: no heartbeat for ``watchdog_timeout`` seconds
==========================  ================================================================

The watchdog (:mod:`jvl_gym.rl.watchdog`) is a separate process in a session of its own, with
its own connection to the motor, so it outlives the loop's process. A cut of the one cable to
the motor is covered only where the motor has a bus time-out of its own (the MIS Modbus
time-out, MIS manual §12); the MAC050–141 has none, so on a single serial line to a MAC a cut
cable leaves the last command standing. Against a twin the loop's link and the watchdog's are
two TCP sessions: cutting the loop's stops the motor through the watchdog's.
"""

from __future__ import annotations

import contextlib
import queue
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from ..envs.link import register_bounds

__all__ = ["Limits", "MotorLink", "Supervisor", "Stopped", "PolicyRunner", "Watchdog",
           "register_bounds"]


class Stopped(RuntimeError):
    """The supervisor stopped the loop; ``reason`` says why."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


class MotorLink(Protocol):
    """What the supervisor writes through: register values and the passive stop."""

    def write_raws(self, values: Mapping[str, int]) -> None: ...
    def passive(self) -> None: ...


@dataclass(frozen=True)
class Limits:
    """The task's bounds on a command.

    Attributes
    ----------
    low, high : tuple of float
        Bounds of each action component.
    max_step : float
        Largest change of a component from one period to the next.
    """

    low: tuple[float, ...]
    high: tuple[float, ...]
    max_step: float

    def __post_init__(self) -> None:
        lo, hi = np.asarray(self.low, float), np.asarray(self.high, float)
        if lo.shape != hi.shape or not (np.isfinite(lo).all() and np.isfinite(hi).all()
                                        and (lo <= hi).all()):
            raise ValueError(f"limits: low {self.low} and high {self.high} must be finite with "
                             "low <= high")
        if not self.max_step > 0:
            raise ValueError(f"limits: max_step must be > 0, got {self.max_step}")


class Supervisor:
    """Bounds every command and stops the motor (module docstring).

    Parameters
    ----------
    link : MotorLink
        Where commands go.
    limits : Limits
        The task's bounds.
    to_registers : callable
        The bridge's map from a bounded action to raw register values.
    bounds : mapping of str to (int, int)
        Each register's raw range (:func:`register_bounds`), itself within the task's.
    watchdog : Watchdog, optional
        Told to stop the motor too when the loop stops.
    """

    def __init__(self, link: MotorLink, limits: Limits,
                 to_registers: Callable[[np.ndarray], dict[str, int]],
                 bounds: Mapping[str, tuple[int, int]], watchdog: Any = None) -> None:
        self.link = link
        self.limits = limits
        self.to_registers = to_registers
        self.bounds = dict(bounds)
        self.watchdog = watchdog
        self.last = np.zeros(len(limits.low))
        self.reason = ""

    def bound(self, action: Any) -> np.ndarray:
        """The action within the task's bounds and the rate limit (a component that is not a
        number holds the last command)."""
        a = np.asarray(action, dtype=np.float64).reshape(-1)
        if a.shape != self.last.shape:
            raise Stopped(f"policy gave an action of shape {a.shape}, expected "
                          f"{self.last.shape}")
        a = np.where(np.isfinite(a), a, self.last)
        a = np.clip(a, self.limits.low, self.limits.high)
        step = self.limits.max_step
        return np.clip(a, self.last - step, self.last + step)

    def registers(self, action: np.ndarray) -> dict[str, int]:
        """Raw register values of a bounded ``action``, each clipped to its range."""
        raws = self.to_registers(action)
        out = {}
        for name, raw in raws.items():
            lo, hi = self.bounds[name]
            out[name] = int(min(max(int(raw), lo), hi))
        return out

    def command(self, action: Any) -> tuple[np.ndarray, dict[str, int]]:
        """Bound ``action``, write its registers; returns both."""
        a = self.bound(action)
        raws = self.registers(a)
        self.link.write_raws(raws)
        self.last = a
        return a, raws

    def stop(self, reason: str) -> None:
        """Put the motor passive (the loop's link, and the watchdog's), once; keep why."""
        if self.reason:
            return
        self.reason = reason
        if self.watchdog is not None:
            self.watchdog.trip()
        with contextlib.suppress(Exception):
            self.link.passive()


class PolicyRunner:
    """Runs the policy in a daemon thread so that a stalled policy can be given up on.

    Parameters
    ----------
    policy : callable
        ``(1, K) observation -> (1, A) action``.
    """

    def __init__(self, policy: Callable[[np.ndarray], Any]) -> None:
        self.policy = policy
        self._in: queue.Queue[np.ndarray] = queue.Queue(1)
        self._out: queue.Queue[tuple[bool, Any]] = queue.Queue(1)
        self._thread = threading.Thread(target=self._run, name="policy", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while True:
            obs = self._in.get()
            try:
                self._out.put((True, self.policy(obs)))
            except BaseException as exc:  # noqa: BLE001 - handed to the loop
                self._out.put((False, exc))

    def __call__(self, obs: np.ndarray, deadline: float) -> Any:
        """The policy's action for ``obs``; :class:`Stopped` when it has none within
        ``deadline`` seconds."""
        self._in.put(obs)
        try:
            ok, value = self._out.get(timeout=max(deadline, 0.0))
        except queue.Empty:
            raise Stopped(f"policy stalled: no action within the deadline ({deadline:.3g} s)"
                          ) from None
        if not ok:
            raise value
        return value


class Watchdog:
    """The watchdog process (:mod:`jvl_gym.rl.watchdog`) and its heartbeat pipe.

    Parameters
    ----------
    url : str
        pyserial URL of its own connection to the motor.
    address : int
        The motor's address.
    motor_type : str
        The motor type (its family gives the dialect and the passive mode).
    timeout : float
        Seconds without a heartbeat after which it puts the motor passive.
    """

    def __init__(self, url: str, address: int, motor_type: str, timeout: float) -> None:
        self.timeout = float(timeout)
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "jvl_gym.rl.watchdog", url, str(int(address)), motor_type,
             repr(self.timeout)],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, start_new_session=True)
        line = self.proc.stdout.readline() if self.proc.stdout else b""
        if not line.startswith(b"ready"):
            self.proc.kill()
            raise RuntimeError(f"the watchdog did not start: {line.decode(errors='replace')}"
                               .strip())

    def _send(self, byte: bytes) -> None:
        with contextlib.suppress(OSError, ValueError):
            assert self.proc.stdin is not None
            self.proc.stdin.write(byte)
            self.proc.stdin.flush()

    def beat(self) -> None:
        """A heartbeat: the loop is alive."""
        self._send(b".")

    def check(self) -> None:
        """Raise :class:`Stopped` when the watchdog has ended: it put the motor passive (no
        heartbeat within its time-out) or lost its own connection, and the loop must not
        command the motor past it.

        Raises
        ------
        Stopped
            The watchdog ended; ``reason`` carries what it printed.
        """
        if self.proc.poll() is None:
            return
        said = b""
        with contextlib.suppress(OSError, ValueError):
            said = self.proc.stdout.read() if self.proc.stdout else b""
        what = said.decode(errors="replace").strip().splitlines()
        raise Stopped(f"watchdog: {what[-1] if what else 'ended'}")

    def trip(self) -> None:
        """Put the motor passive now."""
        self._send(b"!")

    def close(self, passive: bool = True) -> None:
        """End the watchdog (after putting the motor passive unless ``passive`` is False)."""
        self._send(b"!" if passive else b"q")
        with contextlib.suppress(OSError, ValueError):
            assert self.proc.stdin is not None
            self.proc.stdin.close()
        try:
            self.proc.wait(timeout=max(5.0, 10 * self.timeout))
        except subprocess.TimeoutExpired:
            self.proc.kill()


def wait_until(predicate: Callable[[], bool], seconds: float, poll: float = 0.002) -> bool:
    """Poll ``predicate`` for up to ``seconds``; whether it became true."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(poll)
    return predicate()

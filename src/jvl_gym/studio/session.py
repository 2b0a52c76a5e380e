"""The motors of one studio and the real-time clock of the simulated ones.

A :class:`Session` holds the motors of the studio: simulated motors in-process
(:class:`~.motor.SimMotor`, any families side by side) and motors on lines
(:class:`~.line.LineMotor`, several lines at once). The command line names the first ones;
the Connections view (:mod:`.connections`) adds and removes motors and lines while the
studio runs. Its clock thread advances every simulated motor that is not paused by as many
firmware samples as wall-clock time has passed (times ``speed``), so the simulated motors run
in real time while the pages read and write them.

The motor list is replaced, never changed in place (:meth:`Session.add`,
:meth:`Session.remove`, under one lock), so the clock, STOP and the pages each work on the
list as it was when they read it, while another thread adds or removes a motor.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Mapping, Sequence

from .line import ANSWER_TIMEOUT_S, Line, LineMotor, scan
from .motor import SimMotor, StudioMotor
from .toolkit import TuningToolkit, find_toolkit

__all__ = ["Session", "plan_motors", "pair_scanned", "DEFAULT_MOTOR"]

#: the motor type when none is named (MotorArray's default)
DEFAULT_MOTOR = "MAC140"


def plan_motors(motors: Sequence[str], addresses: Sequence[int], default: str
                ) -> list[tuple[str, int]]:
    """Pair motor types with addresses as ``jvl-gym serve`` does: one type for every address
    or one per address; no address: 1, 2, … per type; no type: ``default``.

    Raises
    ------
    ValueError
        Types and addresses that do not pair, or an address outside 1..254.
    """
    types = list(motors) or [default]
    addrs = list(addresses) or list(range(1, len(types) + 1))
    if len(types) == 1 and len(addrs) > 1:
        types = types * len(addrs)
    if len(types) != len(addrs):
        raise ValueError(f"give one --motor, or one per --address ({len(addrs)} addresses, "
                         f"{len(types)} motors)")
    bad = [a for a in addrs if not 1 <= a <= 254]
    if bad:
        raise ValueError(f"--address {bad[0]} is no unit address (1..254, MYADDR)")
    if len(set(addrs)) != len(addrs):
        raise ValueError("two motors at one address: give each --address once")
    return list(zip(types, addrs))


def pair_scanned(found: Mapping[int, str], motors: Sequence[str]) -> list[tuple[str, int]]:
    """The type of each scanned address: the one of ``motors`` (default
    :data:`DEFAULT_MOTOR`) whose family speaks the MacTalk dialect the unit answered in.

    Raises
    ------
    ValueError
        A unit whose dialect no given type speaks, or two given types of one dialect (the
        reply does not tell their families apart: give ``--address`` per ``--motor``).
    """
    from ..families import family_of_motor

    types = list(dict.fromkeys(motors or [DEFAULT_MOTOR]))
    by_dialect: dict[str, list[str]] = {}
    for t in types:
        by_dialect.setdefault(family_of_motor(t).twin.dialect, []).append(t)
    plan = []
    for address, dialect in found.items():
        speaking = by_dialect.get(dialect, [])
        if not speaking:
            raise ValueError(f"the unit at address {address} speaks {dialect}, which none of "
                             f"{', '.join(types)} does: add its type with --motor")
        if len(speaking) > 1:
            raise ValueError(f"{' and '.join(speaking)} both speak {dialect}: a scan cannot "
                             "tell them apart; give --address for each --motor instead")
        plan.append((speaking[0], address))
    return plan


def _check_speed(speed: float) -> None:
    """Refuse a ``speed`` (simulated seconds per wall-clock second) that is not > 0."""
    if not speed > 0:
        raise ValueError(f"speed must be > 0, got {speed}")


class Session:
    """The studio's motors.

    Parameters
    ----------
    motors : list of StudioMotor
        The motors, in the order the pages list them.
    speed : float
        Simulated seconds per wall-clock second: of the simulated motors' clock, or of the
        other end of the line (a twin's ``--speed``; 1 for real motors), which the tuning page
        gives the tuning run.
    line : Line, optional
        The line the line motors share.
    toolkit : TuningToolkit, optional
        The tuning toolkit of the tuning page (default: the installed one,
        :func:`~jvl_gym.studio.toolkit.find_toolkit`; None if there is none).
    answer_timeout : float
        Seconds each line opened later (the Connections view) waits for a reply.
    """

    def __init__(self, motors: list[StudioMotor] | None = None, speed: float = 1.0,
                 line: Line | None = None, toolkit: TuningToolkit | None = None,
                 answer_timeout: float = ANSWER_TIMEOUT_S) -> None:
        _check_speed(speed)
        if not 0 < answer_timeout < float("inf"):
            raise ValueError(f"the answer timeout must be a finite number of seconds > 0, "
                             f"got {answer_timeout}")
        self.answer_timeout = float(answer_timeout)
        #: the motors, in the order the pages list them (a new list after every change)
        self.motors: list[StudioMotor] = []
        #: the open lines, by port (a new dict after every change)
        self.lines: dict[str, Line] = {}
        self.speed = float(speed)
        self.toolkit = find_toolkit(toolkit)
        self._change = threading.RLock()
        if line is not None:
            self.add_line(line)
        for m in motors or []:
            self.add(m)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        #: last error of the clock (a motor that refused to step), None if none
        self.clock_problem: str | None = None

    @classmethod
    def simulated(cls, motors: Sequence[str], addresses: Sequence[int] = (), seed: int = 0,
                  speed: float = 1.0, toolkit: TuningToolkit | None = None,
                  answer_timeout: float = ANSWER_TIMEOUT_S) -> Session:
        """Simulated motors of the given types (any families), one MotorArray each."""
        plan = plan_motors(motors, addresses, DEFAULT_MOTOR)
        return cls([SimMotor(t, a, seed=seed + k) for k, (t, a) in enumerate(plan)], speed,
                   toolkit=toolkit, answer_timeout=answer_timeout)

    @classmethod
    def on_line(cls, port: str, motors: Sequence[str], addresses: Sequence[int] = (),
                scan_range: Sequence[int] | None = None,
                toolkit: TuningToolkit | None = None, speed: float = 1.0,
                answer_timeout: float = ANSWER_TIMEOUT_S) -> Session:
        """Motors on the line at ``port``: the ``addresses`` given, or those of ``scan_range``
        that answer, each of the ``motors`` type whose family speaks the dialect its reply
        is in (:func:`pair_scanned`); ``speed``: the other end's simulated seconds per
        wall-clock second (a twin's ``--speed``; 1 for real motors); ``answer_timeout``: the
        seconds the line waits for each reply."""
        _check_speed(speed)
        line = Line(port, timeout=answer_timeout)
        if scan_range is not None and not addresses:
            found = scan(line, scan_range)
            if not found:
                raise ValueError(f"no motor answered on {port} at addresses "
                                 f"{min(scan_range)}..{max(scan_range)}")
            plan = pair_scanned(found, motors)
        else:
            plan = plan_motors(motors, addresses, DEFAULT_MOTOR)
        return cls([LineMotor(line, t, a) for t, a in plan], speed, line=line, toolkit=toolkit,
                   answer_timeout=answer_timeout)

    # ------------------------------------------------------------------ lines and motors
    @property
    def line(self) -> Line | None:
        """The first open line (None without one)."""
        return next(iter(self.lines.values()), None)

    def add_line(self, line: Line) -> Line:
        """Hold ``line`` (the one already held at its port, if any)."""
        with self._change:
            if line.port in self.lines:
                return self.lines[line.port]
            self.lines = {**self.lines, line.port: line}
            return line

    def drop_line(self, port: str) -> list[str]:
        """Remove every motor on the line at ``port`` (:meth:`remove`) and close the line;
        return what each removal did (one line each).

        Raises
        ------
        KeyError
            No line is open at ``port``.
        """
        with self._change:
            if port not in self.lines:
                raise KeyError(f"no line is open at {port!r}; open: "
                               f"{', '.join(self.lines) or 'none'}")
            line = self.lines[port]
            said = [self.remove(m.label) for m in self.motors
                    if getattr(m, "line", None) is line]
            self.lines = {p: ln for p, ln in self.lines.items() if p != port}
        line.close()
        return said

    def add(self, motor: StudioMotor) -> StudioMotor:
        """Add ``motor`` to the studio (safe while the clock runs and pages poll); a
        simulated motor starts running with the clock from now on.

        Raises
        ------
        ValueError
            A motor of that label (type and address, on that line) is in the studio already.
        """
        with self._change:
            if motor.label in self.labels():
                raise ValueError(f"{motor.label} is in the studio already; remove it first or "
                                 "give another address")
            line = getattr(motor, "line", None)
            if line is not None and line.port not in self.lines:
                self.add_line(line)
            self.motors = [*self.motors, motor]
        return motor

    def remove(self, label: str) -> str:
        """Stop the motor shown as ``label`` (:meth:`~.motor.StudioMotor.stop_motor`, so no
        motor the studio set moving runs on out of its reach) and remove it; return what the
        stop did (one line). A motor that does not answer is removed all the same.

        Raises
        ------
        KeyError
            No motor of that label.
        """
        with self._change:
            motor = self.motor(label)
            self.motors = [m for m in self.motors if m is not motor]
        try:
            said = motor.stop_motor()
        except Exception as exc:  # noqa: BLE001 - removed all the same, the reason is said
            said = f"{motor.label}: not stopped ({exc})"
        return f"removed {said}"

    def motor(self, label: str) -> StudioMotor:
        """The motor shown as ``label`` (``"MAC140 @ 1"``)."""
        for m in self.motors:
            if m.label == label:
                return m
        raise KeyError(f"no motor {label!r}; the studio has "
                       f"{', '.join(self.labels()) or 'none'}")

    def labels(self) -> list[str]:
        """The motors' labels."""
        return [m.label for m in self.motors]

    # ------------------------------------------------------------------ STOP
    def stop_motors(self, wait: float = 10.0) -> list[str]:
        """Stop every motor of the studio, each by its family's stop
        (:meth:`~.motor.StudioMotor.stop_motor`), all at once, and say how (one line each).

        Each motor is stopped in a thread of its own, so a motor that does not answer does
        not hold up the others. A motor that a long run (a tuning) holds is stopped as soon as
        the run lets go of it; its line says so ("STOP pending") when that takes longer than
        ``wait`` seconds.

        Parameters
        ----------
        wait : float
            Seconds to wait for the motors' answers.

        Returns
        -------
        list of str
            One line per motor, in the studio's order.
        """
        outcomes: dict[int, str] = {}
        motors = self.motors  # the motors of this moment, even if one is added meanwhile

        def stop(k: int, motor: StudioMotor) -> None:
            try:
                outcomes[k] = motor.stop_motor()
            except Exception as exc:  # noqa: BLE001 - reported per motor, the others go on
                outcomes[k] = f"{motor.label}: STOP failed: {exc}"

        threads = [threading.Thread(target=stop, args=(k, m), daemon=True, name="studio-stop")
                   for k, m in enumerate(motors)]
        for t in threads:
            t.start()
        end = time.monotonic() + wait
        for t in threads:
            t.join(max(0.0, end - time.monotonic()))
        return [outcomes.get(k, f"{m.label}: STOP pending (a run holds the motor, or the line "
                             "is slow); it is stopped as soon as it can be")
                for k, m in enumerate(motors)]

    # ------------------------------------------------------------------ clock
    def start(self, period: float = 0.005) -> None:
        """Start the real-time clock of the simulated motors (a daemon thread), which also
        runs the simulated motors added later."""
        if self._thread is not None:
            return
        from .compiling import install

        install()  # the pages say what numba compiles while the first steps wait for it
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, args=(period,), daemon=True,
                                        name="studio-clock")
        self._thread.start()

    def _run(self, period: float) -> None:
        start = time.monotonic()
        done: dict[int, int] = {}  # id of a motor → firmware samples it has run
        while not self._stop.wait(period):
            self.tick((time.monotonic() - start) * self.speed, done)

    def tick(self, elapsed: float, done: dict[int, int]) -> None:
        """Bring every simulated motor of the studio now to ``elapsed`` simulated seconds
        since the clock started; ``done``: id of a motor → the samples it has run (a motor
        new to it starts from now)."""
        sims = [m for m in self.motors if isinstance(m, SimMotor)]
        for m in sims:
            due = int(elapsed * m.facts.outer_hz)
            ran = done.setdefault(id(m), due)
            if m.paused:
                done[id(m)] = due
                continue
            n = min(due - ran, int(m.facts.outer_hz))  # at most 1 s behind
            if n > 0:
                try:
                    m.step(n)
                except Exception as exc:  # noqa: BLE001 - shown on the page, clock runs on
                    self.clock_problem = f"{m.label}: {exc}"
                done[id(m)] = due
        for key in set(done) - {id(m) for m in sims}:  # removed motors
            del done[key]

    def stop(self) -> None:
        """Stop the clock and close the line."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        for line in self.lines.values():
            line.close()

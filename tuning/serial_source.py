"""A motor on a serial line (or the digital twin) seen through the MotorArray interface.

The identification procedure of :mod:`tuning.autotune` drives "a MotorArray or compatible":
``read``/``write`` by register name, ``step`` to let time pass, ``set_record_length``,
``sample_buffer``, ``load_setup`` and ``motor_configs``. :class:`SerialMotor` provides these
for one motor behind a :class:`jvl_gym.protocol.MacTalkClient` (manual 5.1): reads and writes
become MacTalk frames, ``step(n)`` waits n outer samples of wall-clock time (divided by the
twin's ``time_scale``), and the sample buffer is read out with the MacTalk sample-buffer command.
A twin whose clock the caller runs (``TwinServer(run_clock=False)``) is stepped instead through
``clock``: then the motor's time passes only when the procedure waits, and the link costs none.

A run over a port measures the link first (:mod:`tuning.link`): a request then waits for its
answer as many round trips of the measured link as :func:`tuning.link.reply_timeout` says (at
least the client's own timeout), and each later measurement sets it again. Whatever ends the
run (the end, an error, a broken link, Ctrl-C), the motor is left in its family's passive mode,
confirmed by reading MODE_REG back (:mod:`tuning.motor_stop`), on a new connection with the same
timeout if the old one broke.

The record length of TESTU/TESTA is the motor's: the manual's firmware records 11 samples; the
twin records what ``jvl-gym serve --record-length N`` sets. Asking for more than the motor
recorded raises :class:`tuning.records.RecordError` saying so.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from .family import tuned_family
from .link import measure_link, reply_timeout
from .motor_stop import stop_motor
from .records import RecordError
from .testmode_facts import record_facts_of


class SerialMotor:
    """One motor behind a MacTalk client, with the MotorArray subset the toolkit uses.

    Parameters
    ----------
    client : jvl_gym.protocol.MacTalkClient
        An open client addressed to the motor.
    motor : str or MotorConfig
        Motor type (the data the identification starts from).
    time_scale : float
        Simulated seconds per wall-clock second of the other end (1 for a real motor; the
        twin's ``--speed``).
    clock : callable, optional
        ``clock(seconds)`` advances the other end's simulated time by ``seconds`` (a twin served
        with ``run_clock=False``, e.g. ``MotorTwin.advance``); waits then step the twin instead
        of sleeping, and no motor time passes during a request.
    """

    n = 1

    def __init__(self, client: Any, motor: Any, time_scale: float = 1.0,
                 clock: Callable[[float], None] | None = None) -> None:
        if not time_scale > 0:
            raise ValueError(f"time_scale must be > 0, got {time_scale}")
        self.client = client
        self.family = tuned_family(motor)
        self.config = self.family.load_motor(motor)
        self.time_scale = float(time_scale)
        self.clock = clock
        self._wanted = 0
        #: the client's own timeout, the least a measured link sets
        self.least_timeout = float(client.timeout) if hasattr(client, "timeout") else 0.0

    def motor_seconds(self, wall_s: float) -> float:
        """Motor time that passes in ``wall_s`` wall-clock seconds (0 on a simulated clock)."""
        return 0.0 if self.clock is not None else wall_s * self.time_scale

    def wall_seconds(self, motor_s: float) -> float:
        """Wall-clock time [s] ``motor_s`` of motor time take (0 on a simulated clock)."""
        return 0.0 if self.clock is not None else motor_s / self.time_scale

    def wait(self, motor_s: float) -> None:
        """Let ``motor_s`` seconds of motor time pass (sleep, or step a simulated clock)."""
        if self.clock is not None:
            self.clock(motor_s)
        else:
            time.sleep(motor_s / self.time_scale)

    def measure_link(self) -> Any:
        """The link's round trip now (:func:`tuning.link.measure_link`); the client's timeout
        becomes :func:`tuning.link.reply_timeout` of it."""
        timing = measure_link(self)
        if hasattr(self.client, "timeout"):
            self.client.timeout = reply_timeout(timing, self.least_timeout)
        return timing

    @property
    def motor_configs(self) -> list[Any]:
        """The motor type's data, as MotorArray.motor_configs."""
        return [self.config]

    def read(self, key: str | int) -> np.ndarray:
        """Register value in user units, shape (1,)."""
        return np.asarray([self.client.read(key)])

    def write(self, key: str | int, value: Any, index: Any = None) -> None:
        """Write a register (scalar or a one-element array) over MacTalk."""
        arr = np.asarray(value, dtype=float).reshape(-1)
        if arr.size != 1:
            raise ValueError(f"{key}: one motor takes one value, got {arr.size}")
        self.client.write(key, float(arr[0]))

    def load_setup(self, setup: Mapping[str, Any], index: Any = None) -> None:
        """Write a register set and read it back (``{"registers": {...}}`` or a bare mapping)."""
        regs = setup.get("registers", setup)
        self.client.write_registers({k: float(v) for k, v in regs.items()})

    def step(self, n_outer: int = 1) -> None:
        """Let ``n_outer`` outer samples (1.92 ms each) of motor time pass."""
        self.wait(n_outer * self.family.tuning.outer_dt)

    def set_record_length(self, n_samples: int) -> None:
        """Remember the record length the next test needs (the motor's own is fixed)."""
        self._wanted = int(n_samples)

    def sample_buffer(self, timeout: float = 10.0) -> dict[str, np.ndarray]:
        """The sample buffer as {register name: (1, REC_CNT)}; checks the record length.

        Waits (polling REC_CNT and RECORDBIT) until the recording has stopped: the other end's
        clock, not this process, decides when samples exist, and the buffer is read out only
        when no sample is being added. ``timeout`` is in seconds of wall-clock time, or, on a
        simulated clock (``clock``), of motor time: how busy this machine is then does not
        change when the wait ends.
        """
        end = time.monotonic() + timeout
        waited = 0.0  # motor time stepped on a simulated clock
        while (waited < timeout if self.clock is not None else time.monotonic() < end):
            count = int(self.client.read("REC_CNT"))
            recording = int(self.client.read("CNTRL_BITS")) & self.family.constants.RECORDBIT
            if count > 0 and not recording:
                break
            if self.clock is not None:
                self.wait(self.family.tuning.outer_dt)
                waited += self.family.tuning.outer_dt
            else:
                time.sleep(0.005)
        buf = self.client.sample_buffer()
        got = min((len(v) for v in buf.values()), default=0)
        if got < self._wanted:
            raise RecordError(
                f"the motor recorded {got} samples but {self._wanted} were asked for: use "
                f"--n-coil/--n-mech {got} (the manual's firmware records 11) or start the twin "
                f"with --record-length {self._wanted}")
        return {k: np.asarray(v)[None, :] for k, v in buf.items()}


class MotorNotStopped(RuntimeError):
    """The run ended but the motor's passive mode could not be confirmed."""


def autotune_over_serial(port: str, motor: str, address: int = 1, time_scale: float = 1.0,
                         n_coil: int | None = None, n_mech: int | None = None,
                         structure: str = "pi", write: bool = False, progress: Any = None,
                         two_mass: Any = None,
                         clock: Callable[[float], None] | None = None) -> tuple[Any, Any]:
    """Identify and design on a motor behind ``port`` (device path or pyserial URL).

    Runs TESTU and the two-level TESTA through MacTalk with the firmware's record length
    (``n_coil``, ``n_mech``; None: the family's, 11 samples, manual 4.4.9/4.4.10; several
    records are combined,
    :func:`tuning.autotune.testa_repeats`, :func:`tuning.autotune.testu_repeats`),
    synthesises and quantises the filters, keeps the best candidate by the acceptance step
    (simulated on the identified motor, :func:`tuning.pipeline.design_and_accept`), and, with
    ``write``, writes the kept registers to the motor and reads them back. Returns
    ``(Identification, Result)``. The motor must be in INIT_MODE and free to turn.

    The link is measured first and reported through ``progress``. However the run ends (done,
    an error, a broken link, KeyboardInterrupt) the motor is put in its family's passive mode
    and the mode read back (:func:`tuning.motor_stop.stop_motor`, on a new connection if the
    old one broke); a stop that cannot be confirmed is reported through ``progress`` and, after
    a run that otherwise succeeded, raised as :class:`MotorNotStopped`.

    ``two_mass(m, result)``, if given, runs on the motor (``m``, a :class:`SerialMotor`)
    after the design and before the write, e.g. the resonance step of ``jvl-tune autotune
    --resonance`` (:mod:`tuning.identify_resonance`, which measures the link again before each
    record and skips or refuses the records whose brake the link cannot keep); it may change
    ``result.chosen.registers``. ``clock``: see :class:`SerialMotor`.
    """
    from jvl_gym.protocol import MacTalkClient

    from .pipeline import design_and_accept
    from .strategy import strategy_of

    say = progress or (lambda _msg: None)
    strategy = strategy_of(motor)
    samples = record_facts_of(motor).test_record_samples
    n_coil, n_mech = n_coil or samples, n_mech or samples
    m = SerialMotor(MacTalkClient(port, address=address), motor, time_scale, clock)
    try:
        say(f"link to {port}: {m.measure_link().describe()}")
        if int(m.read("MODE_REG")[0]) != 0:  # refused before anything is changed
            raise RecordError("the motor must be in INIT_MODE (MODE_REG = 0) to be identified")
        try:
            ident = strategy.identify(m, {"n_coil": n_coil, "n_mech": n_mech}, say)[0]
            say("acceptance: simulating the candidates on the identified motor")
            result = design_and_accept(strategy, [ident], {"structure": structure})[0]
            if two_mass is not None:
                two_mass(m, result)
            bad = strategy.failures(result.chosen)
            if write and not bad:
                say("writing the synthesised registers and reading them back")
                m.client.write_registers(result.chosen.registers)
        except BaseException:
            _stop(m, port, address, say)
            raise
        why = _stop(m, port, address, say)
        if why is not None:
            raise MotorNotStopped(f"the run ended but the motor's passive mode could not be "
                                  f"confirmed: {why}; stop the motor by hand")
    finally:
        try:
            m.client.close()
        except Exception:  # noqa: BLE001  (a broken link's close)
            pass
    return ident, result


def _stop(m: SerialMotor, port: str, address: int, say: Callable[[str], None]) -> str | None:
    """Stop the motor (:func:`tuning.motor_stop.stop_motor`, reconnecting to ``port``); say
    what happened; the reason when the passive mode was not confirmed."""
    from jvl_gym.protocol import MacTalkClient

    timeout = m.client.timeout  # the measured link's (a broken link's new connection too)
    why = stop_motor(m, reconnect=lambda: MacTalkClient(port, address=address, timeout=timeout))
    if why is None:
        say("the motor is passive (MODE_REG read back)")
    else:
        say(f"could not confirm that the motor is passive: {why}; stop it by hand")
    return why

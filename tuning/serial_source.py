"""A motor on a serial line (or the digital twin) seen through the MotorArray interface.

The identification procedure of :mod:`tuning.autotune` drives "a MotorArray or compatible":
``read``/``write`` by register name, ``step`` to let time pass, ``set_record_length``,
``sample_buffer``, ``load_setup`` and ``motor_configs``. :class:`SerialMotor` provides these
for one motor behind a :class:`jvl_gym.protocol.MacTalkClient` (manual 5.1): reads and writes
become MacTalk frames, ``step(n)`` waits n outer samples of wall-clock time (divided by the
twin's ``time_scale``), and the sample buffer is read out with the MacTalk sample-buffer command.

The record length of TESTU/TESTA is the motor's: the manual's firmware records 11 samples; the
twin records what ``jvl-gym serve --record-length N`` sets. Asking for more than the motor
recorded raises :class:`tuning.records.RecordError` saying so.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from .family import tuned_family
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
    """

    n = 1

    def __init__(self, client: Any, motor: Any, time_scale: float = 1.0) -> None:
        if not time_scale > 0:
            raise ValueError(f"time_scale must be > 0, got {time_scale}")
        self.client = client
        self.family = tuned_family(motor)
        self.config = self.family.load_motor(motor)
        self.time_scale = float(time_scale)
        self._wanted = 0

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
        time.sleep(n_outer * self.family.tuning.outer_dt / self.time_scale)

    def set_record_length(self, n_samples: int) -> None:
        """Remember the record length the next test needs (the motor's own is fixed)."""
        self._wanted = int(n_samples)

    def sample_buffer(self, timeout: float = 10.0) -> dict[str, np.ndarray]:
        """The sample buffer as {register name: (1, REC_CNT)}; checks the record length.

        Waits (polling REC_CNT and RECORDBIT) until the recording has stopped: the other end's
        clock, not this process, decides when samples exist, and the buffer is read out only
        when no sample is being added.
        """
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            count = int(self.client.read("REC_CNT"))
            recording = int(self.client.read("CNTRL_BITS")) & self.family.constants.RECORDBIT
            if count > 0 and not recording:
                break
            time.sleep(0.005)
        buf = self.client.sample_buffer()
        got = min((len(v) for v in buf.values()), default=0)
        if got < self._wanted:
            raise RecordError(
                f"the motor recorded {got} samples but {self._wanted} were asked for: use "
                f"--n-coil/--n-mech {got} (the manual's firmware records 11) or start the twin "
                f"with --record-length {self._wanted}")
        return {k: np.asarray(v)[None, :] for k, v in buf.items()}


def autotune_over_serial(port: str, motor: str, address: int = 1, time_scale: float = 1.0,
                         n_coil: int | None = None, n_mech: int | None = None,
                         structure: str = "pi", write: bool = False, progress: Any = None,
                         two_mass: Any = None) -> tuple[Any, Any]:
    """Identify and design on a motor behind ``port`` (device path or pyserial URL).

    Runs TESTU and the two-level TESTA through MacTalk with the firmware's record length
    (``n_coil``, ``n_mech``; None: the family's, 11 samples, manual 4.4.9/4.4.10; several
    records are combined,
    :func:`tuning.autotune.testa_repeats`, :func:`tuning.autotune.testu_repeats`),
    synthesises and quantises the filters, keeps the best candidate by the acceptance step
    (simulated on the identified motor, :func:`tuning.pipeline.design_and_accept`), and, with
    ``write``, writes the kept registers to the motor and reads them back. Returns
    ``(Identification, Result)``. The motor must be in INIT_MODE and free to turn.

    ``two_mass(m, result)``, if given, runs on the motor (``m``, a :class:`SerialMotor`)
    after the design and before the write, e.g. the resonance step of ``jvl-tune autotune
    --resonance`` (:mod:`tuning.identify_resonance`: one continuous sample-buffer record per
    torque step, so the link's timing does not matter as long as a frame's round trip is short
    against the 114 ms record); it may change ``result.chosen.registers``.
    """
    from jvl_gym.protocol import MacTalkClient

    from .pipeline import design_and_accept
    from .strategy import strategy_of

    say = progress or (lambda _msg: None)
    strategy = strategy_of(motor)
    samples = record_facts_of(motor).test_record_samples
    n_coil, n_mech = n_coil or samples, n_mech or samples
    with MacTalkClient(port, address=address) as client:
        m = SerialMotor(client, motor, time_scale)
        if int(m.read("MODE_REG")[0]) != 0:
            raise RecordError("the motor must be in INIT_MODE (MODE_REG = 0) to be identified")
        ident = strategy.identify(m, {"n_coil": n_coil, "n_mech": n_mech}, say)[0]
        say("acceptance: simulating the candidates on the identified motor")
        result = design_and_accept(strategy, [ident], {"structure": structure})[0]
        if two_mass is not None:
            two_mass(m, result)
        bad = strategy.failures(result.chosen)
        if write and not bad:
            say("writing the synthesised registers and reading them back")
            client.write_registers(result.chosen.registers)
    return ident, result

"""Identification records: format, validation, CSV files, and where records come from.

A :class:`Record` is one test-mode measurement from the sample buffer:

* ``TESTU`` (manual 4.4.9): inner rate 7812.5 Hz; ``input`` = UA_VAL [PWM counts] (SAMPLE1 =
  145), ``output`` = IC_IST [ADC counts] (SAMPLE2 = 139). UA = UMEAS, UB = 0, UC = −UMEAS, so
  the line-to-line circuit a–c (2R, 2L) is driven with 2·UMEAS PWM counts.
* ``TESTA`` (manual 4.4.10): outer rate 520.83 Hz; ``input`` = T_SOLL [1/1023 of peak torque]
  (SAMPLE1 = 7), ``output`` = V_IST [counts/sample] (SAMPLE2 = 12); the motor runs at constant
  torque VF_OUT = T_SOLL from rest.

Sample 0 is the first sample of the test mode (the motor at rest, no current). A TESTA record
from a motor (:func:`acquire_testa`) carries the registers the electrical TESTA model needs
(:data:`TESTA_REGISTERS`: the current loop, PHASE_COMP, AMPLITUDE) in ``meta["registers"]``; the
CSV keeps them in the ``# registers:`` line. CSV layout::

    # jvl_gym record v1
    # kind: TESTU
    # rate_hz: 7812.5
    # motor: MAC140
    # registers: KIFX2=1.2 KIFX1=-1.0 KIFY1=1 KIFY0=0 KIB1=1 KIB0=0 PHASE_COMP=5 AMPLITUDE=0.828125
    # <any other meta key>: <value>
    sample,UA_VAL,IC_IST
    0,100,0
    ...

:func:`validate` raises :class:`RecordError` with a message that says what is wrong and what to
do (too short, saturated, wrong rate, no excitation, motor did not move …).

Sources: :func:`simulate_testu` / :func:`simulate_testa` (the exact discrete model, with
quantisation and noise options, for tests), :func:`acquire_testu` / :func:`acquire_testa` (any
object with the ``MotorArray`` register interface: ``write``, ``read``, ``step``,
``set_record_length``, ``sample_buffer``), and :func:`load_csv`. A real motor joins through
:data:`SERIAL_SOURCE_HOOK` once the protocol client exists.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from jvl_gym.families import UnsupportedOperation

from .models import MotorData
from .testmode_facts import RecordFacts, record_facts_of

__all__ = [
    "Record",
    "RecordError",
    "CHANNELS",
    "MIN_SAMPLES",
    "validate",
    "validated",
    "save_csv",
    "load_csv",
    "simulate_testu",
    "simulate_testa",
    "acquire_testu",
    "acquire_testa",
    "SERIAL_SOURCE_HOOK",
    "TESTA_REGISTERS",
    "record_registers",
]

CHANNELS: dict[str, tuple[str, str]] = {"TESTU": ("UA_VAL", "IC_IST"), "TESTA": ("T_SOLL", "V_IST")}
MIN_SAMPLES: dict[str, int] = {"TESTU": 8, "TESTA": 6}
MAX_TESTA_SPEED: int = 400  #: |V_IST| above this (3052 rpm) leaves the constant-torque region
#: registers a TESTA record is taken with that the electrical model needs (manual 3.2.106–111,
#: 3.2.126, 3.2.127); :func:`acquire_testa` stores them in ``meta["registers"]``
TESTA_REGISTERS: tuple[str, ...] = ("KIFX2", "KIFX1", "KIFY1", "KIFY0", "KIB1", "KIB0",
                                    "PHASE_COMP", "AMPLITUDE")


class RecordError(ValueError):
    """A record cannot be used for identification (the message says why and what to do)."""


@dataclass
class Record:
    """One TESTU or TESTA record.

    Attributes
    ----------
    kind : {"TESTU", "TESTA"}
    rate_hz : float
        Sample rate [Hz]: the family's current-loop rate (TESTU) or servo rate (TESTA),
        7812.5 or 520.833 on the MAC050–141 (:attr:`RecordFacts.rates`).
    input : ndarray, shape (n,)
        UA_VAL [PWM counts] or T_SOLL [0..1023].
    output : ndarray, shape (n,)
        IC_IST [ADC counts] or V_IST [counts/sample].
    motor : str or None
        Motor type, used for the physical scales and the family's rates (a record without one
        is validated with the facts its user gives).
    meta : dict
        Free-form information (source, seed, UMEAS …).
    """

    kind: str
    rate_hz: float
    input: np.ndarray
    output: np.ndarray
    motor: str | None = None
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.input = np.asarray(self.input, dtype=float).ravel()
        self.output = np.asarray(self.output, dtype=float).ravel()

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.output.size)

    @property
    def channels(self) -> tuple[str, str]:
        """Register names of (input, output)."""
        return CHANNELS[self.kind]


def facts_of_record(rec: Record) -> RecordFacts:
    """The TESTU/TESTA facts of the family of the record's motor type; :class:`RecordError`
    where the record names none or one of a family without test modes."""
    if not rec.motor:
        raise RecordError(f"{rec.kind}: the record names no motor type, so its family's sample "
                          "rates and scales are unknown; add a '# motor:' header line or give "
                          "the motor")
    try:
        return record_facts_of(rec.motor)
    except (ValueError, UnsupportedOperation) as exc:
        raise RecordError(f"{rec.kind}: motor {rec.motor!r}: {exc}") from exc


def validate(rec: Record, facts: RecordFacts | None = None) -> Record:
    """Check a record and return it; raise :class:`RecordError` if it cannot be used.

    ``facts`` are those of the motor the record is used with; None: those of the record's own
    motor type (:func:`facts_of_record`)."""
    if facts is None:
        facts = facts_of_record(rec)
    if rec.kind not in CHANNELS:
        raise RecordError(f"record kind must be TESTU or TESTA, got {rec.kind!r}")
    if rec.input.shape != rec.output.shape:
        raise RecordError(f"{rec.kind}: input and output lengths differ "
                          f"({rec.input.size} vs {rec.output.size})")
    want = facts.rates[rec.kind]
    if not math.isfinite(rec.rate_hz) or abs(rec.rate_hz / want - 1.0) > 1e-3:
        hint = " (inner rate, RECINNERBIT = 1)" if rec.kind == "TESTU" else " (outer rate)"
        raise RecordError(f"{rec.kind}: wrong sample rate {rec.rate_hz:.6g} Hz; the record must "
                          f"be sampled at {want:.6g} Hz{hint}, manual 4.4.9/4.4.10")
    if rec.n < MIN_SAMPLES[rec.kind]:
        raise RecordError(f"{rec.kind}: too short ({rec.n} samples); at least "
                          f"{MIN_SAMPLES[rec.kind]} are needed, 64 are recommended "
                          "(MotorArray.set_record_length / REC_CNT)")
    if not (np.all(np.isfinite(rec.input)) and np.all(np.isfinite(rec.output))):
        raise RecordError(f"{rec.kind}: the record contains NaN or infinite values")
    a_in, a_out = CHANNELS[rec.kind]
    if rec.kind == "TESTU":
        if np.any(np.abs(rec.output) >= facts.adc_full):
            raise RecordError(f"TESTU: {a_out} saturated at ±{facts.adc_full} ADC counts; "
                              "lower UMEAS")
        if np.any(np.abs(rec.input) >= facts.pwm_full):
            raise RecordError(f"TESTU: {a_in} saturated at ±{facts.pwm_full}; lower UMEAS")
        if np.all(rec.input == 0):
            raise RecordError("TESTU: no excitation (UA_VAL = 0 throughout); set UMEAS > 0")
        if np.max(np.abs(rec.output)) < 5:
            raise RecordError("TESTU: the current hardly moved (< 5 ADC counts); raise UMEAS")
    else:
        if np.any(rec.input <= 0) or np.any(rec.input > 1023):
            raise RecordError("TESTA: T_SOLL must be within 1..1023 (manual 3.2.7)")
        if np.any(np.abs(rec.output) > MAX_TESTA_SPEED):
            raise RecordError(f"TESTA: V_IST reached {np.max(np.abs(rec.output)):.0f} counts/"
                              f"sample (> {MAX_TESTA_SPEED}): the torque is no longer constant "
                              "(back-EMF); lower T_SOLL or shorten the record")
        if np.count_nonzero(rec.output) < 3:
            raise RecordError("TESTA: the motor did not move; T_SOLL is below the static "
                              "friction torque or the record is too short")
    return rec


def validated(records: Record | Sequence[Record], kind: str, motor: MotorData,
              user: str) -> list[Record]:
    """``records`` as a list, at least one, each valid for ``motor``'s family (:func:`validate`)
    and of ``kind``; :class:`RecordError` naming ``user`` (the fit) otherwise."""
    recs = [records] if isinstance(records, Record) else list(records)
    if not recs:
        raise RecordError(f"{user} needs at least one {kind} record")
    facts = record_facts_of(motor)
    for r in recs:
        validate(r, facts)
        if r.kind != kind:
            raise RecordError(f"{user} needs {kind} records, got {r.kind}")
    return recs


# ----------------------------------------------------------------------------- CSV
def save_csv(rec: Record, path: str | os.PathLike[str]) -> Path:
    """Write a record in the documented CSV layout (module docstring)."""
    path = Path(path)
    a_in, a_out = CHANNELS[rec.kind]
    lines = ["# jvl_gym record v1", f"# kind: {rec.kind}", f"# rate_hz: {rec.rate_hz!r}"]
    if rec.motor:
        lines.append(f"# motor: {rec.motor}")
    for k, v in rec.meta.items():
        if isinstance(v, dict):  # e.g. registers: NAME=value NAME=value …
            v = " ".join(f"{n}={float(x)!r}" for n, x in v.items())
        lines.append(f"# {k}: {v}")
    lines.append(f"sample,{a_in},{a_out}")
    for i, (u, y) in enumerate(zip(rec.input, rec.output)):
        lines.append(f"{i},{u:.10g},{y:.10g}")
    path.write_text("\n".join(lines) + "\n")
    return path


def _registers_header(path: Path, ln: int, text: str, facts: RecordFacts) -> dict[str, float]:
    """The ``# registers:`` line ``text`` (line ``ln`` of ``path``): NAME=value pairs of
    distinct writable registers of the family's table, each value finite and in its range."""
    from jvl_gym.registers import Access, RegisterError, to_raw

    out: dict[str, float] = {}
    for item in text.split():
        name, eq, value = item.partition("=")
        where = f"{path}:{ln}: '# registers:' item {item!r}"
        if not eq:
            raise RecordError(f"{where} is not NAME=value (pairs separated by spaces)")
        if name in out:
            raise RecordError(f"{where}: {name} is given more than once")
        try:
            reg = facts.table.lookup(name)
            number = float(value)
            if reg.access != Access.RW:
                raise RecordError(f"{where}: {name} is not a parameter register")
            to_raw(reg, number)
        except (RegisterError, ValueError) as exc:
            raise RecordError(f"{where}: {exc}") from exc
        out[name] = number
    return out


def load_csv(path: str | os.PathLike[str], motor: str | None = None) -> Record:
    """Read and validate a record CSV; :class:`RecordError` on any format problem.

    The record is of the motor type of its ``# motor:`` header line, else of ``motor``; its
    family's rates, scales and register table apply.

    The error names the file and, for a problem of one line, the line: a file that is not
    UTF-8 text, a repeated header key or column name, a row with the wrong number of fields or
    a value that is not a finite number, a ``sample`` column that does not count 0, 1, 2, …,
    a ``# registers:`` item that is not a writable register with a value in its range.
    """
    path = Path(path)
    if not path.is_file():
        raise RecordError(f"record file not found: {path}")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise RecordError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start}); save the "
                          "record as UTF-8 CSV") from exc
    except OSError as exc:
        raise RecordError(f"{path}: cannot be read: {exc.strerror or exc}") from exc
    header: dict[str, str] = {}
    header_line: dict[str, int] = {}
    rows: list[list[float]] = []
    columns: list[str] | None = None
    for ln, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if not line:
            continue
        if line.startswith("#"):
            if ":" in line:
                k, v = line[1:].split(":", 1)
                k = k.strip()
                if k in header:
                    raise RecordError(f"{path}:{ln}: header '# {k}:' repeats line "
                                      f"{header_line[k]}")
                header[k] = v.strip()
                header_line[k] = ln
            continue
        fields = [f.strip() for f in line.split(",")]
        if columns is None:
            twice = sorted({f for f in fields if fields.count(f) > 1})
            if twice:
                raise RecordError(f"{path}:{ln}: column {', '.join(twice)} appears more than "
                                  "once; a record has one column per channel")
            columns = fields
            continue
        if len(fields) != len(columns):
            raise RecordError(f"{path}:{ln}: expected {len(columns)} fields "
                              f"({','.join(columns)}), got {len(fields)}")
        try:
            row = [float(f) for f in fields]
        except ValueError as exc:
            raise RecordError(f"{path}:{ln}: not numeric: {line!r}") from exc
        if not all(math.isfinite(x) for x in row):
            raise RecordError(f"{path}:{ln}: values must be finite numbers, got {line!r}")
        if "sample" in columns and row[columns.index("sample")] != len(rows):
            raise RecordError(f"{path}:{ln}: sample {fields[columns.index('sample')]} where "
                              f"{len(rows)} is due; rows must count 0, 1, 2, … in order")
        rows.append(row)
    kind = header.get("kind")
    if kind not in CHANNELS:
        raise RecordError(f"{path}: header '# kind:' must be TESTU or TESTA, got {kind!r}")
    if "rate_hz" not in header:
        raise RecordError(f"{path}: header '# rate_hz:' is missing")
    a_in, a_out = CHANNELS[kind]
    if columns is None or a_in not in columns or a_out not in columns:
        raise RecordError(f"{path}: a {kind} record needs columns {a_in} and {a_out}")
    data = np.array(rows, dtype=float).reshape(len(rows), len(columns))
    try:
        rate = float(header["rate_hz"])
    except ValueError as exc:
        raise RecordError(f"{path}:{header_line['rate_hz']}: '# rate_hz:' is not a number: "
                          f"{header['rate_hz']!r}") from exc
    meta: dict[str, Any] = {k: v for k, v in header.items()
                            if k not in ("kind", "rate_hz", "motor")}
    rec = Record(kind, rate, data[:, columns.index(a_in)], data[:, columns.index(a_out)],
                 header.get("motor") or motor, meta)
    try:
        facts = facts_of_record(rec)
        if "registers" in meta:
            meta["registers"] = _registers_header(path, header_line["registers"],
                                                  meta["registers"], facts)
        return validate(rec, facts)
    except RecordError as exc:
        text = str(exc)
        raise RecordError(text if text.startswith(str(path)) else f"{path}: {text}") from exc


def record_registers(recs: Record | Sequence[Record]) -> dict[str, float] | None:
    """The registers the records were taken with (``meta["registers"]``), or None.

    Several records must agree (they are one identification); a register missing from one
    record is dropped. Returns None when no record carries registers.

    Raises
    ------
    RecordError
        Two records were taken with different register values.
    """
    recs = [recs] if isinstance(recs, Record) else list(recs)
    sets = [r.meta.get("registers") for r in recs]
    if not any(sets):
        return None
    common = set.intersection(*(set(x or {}) for x in sets))
    out: dict[str, float] = {}
    for name in sorted(common):
        vals = {float(x[name]) for x in sets if x}
        if len(vals) > 1:
            raise RecordError(f"the records were taken with different {name} ({sorted(vals)}); "
                              "identify them separately")
        out[name] = vals.pop()
    return out


# ----------------------------------------------------------------------------- generators
def simulate_testu(motor: MotorData, umeas: float = 100.0, n: int = 11, quantize: bool = True,
                   noise_std: float = 0.0, rng: np.random.Generator | int | None = None
                   ) -> Record:
    """TESTU record of the exact discrete coil model (no back-EMF: rotor d-aligned).

    ``i(k+1) = a·i(k) + g(1−a)·u(k−d)`` in ADC counts (line current a→c), IC_IST = −i,
    optionally plus Gaussian noise of ``noise_std`` counts and rounded to integers.
    """
    rng = np.random.default_rng(rng)
    facts = record_facts_of(motor)
    a, g, d = motor.coil_pole, motor.coil_gain, int(motor.pwm_delay)
    u = np.full(n, float(umeas))
    i = np.zeros(n)
    for k in range(n - 1):
        i[k + 1] = a * i[k] + g * (1 - a) * (u[k - d] if k - d >= 0 else 0.0)
    y = -i + noise_std * rng.standard_normal(n)
    if quantize:
        y = np.clip(np.round(y), -facts.adc_full, facts.adc_full)
    return Record("TESTU", facts.rates["TESTU"], u, y, motor.name,
                  {"source": "simulate_testu", "UMEAS": umeas})


def simulate_testa(motor: MotorData, J: float, t_soll: float, n: int = 11, viscous: float = 0.0,
                   coulomb: float = 0.0, quantize: bool = True, position_noise: float = 0.0,
                   rng: np.random.Generator | int | None = None) -> Record:
    """TESTA record of an ideal-current-loop rigid rotor at constant torque from rest.

    ``J dω/dt = K_vf·T_SOLL − b·ω − T_c`` (exact exponential solution), the encoder position
    ``P = floor(θ·4096/2π)`` (if ``quantize``) plus Gaussian noise of ``position_noise`` counts,
    ``V_IST(k) = P(k) − P(k−1)`` with V_IST(0) = 0.
    """
    rng = np.random.default_rng(rng)
    facts = record_facts_of(motor)
    t = np.arange(n) * facts.ts_o
    drive = motor.torque_per_vf * t_soll - coulomb
    if drive <= 0:
        theta = np.zeros(n)
    elif viscous > 0:
        beta = viscous / J
        theta = drive / viscous * (t + np.expm1(-beta * t) / beta)
    else:
        theta = 0.5 * drive / J * t**2
    p = theta * facts.counts_per_rad
    if quantize:
        p = np.floor(p)
    p = p + position_noise * rng.standard_normal(n) * (np.arange(n) > 0)
    if quantize:
        p = np.round(p)
    v = np.diff(np.r_[p[0], p])
    return Record("TESTA", facts.rates["TESTA"], np.full(n, float(t_soll)), v, motor.name,
                  {"source": "simulate_testa", "T_SOLL": t_soll})


# ----------------------------------------------------------------------------- motors
#: Real motors: a serial client exposing the same register interface as ``MotorArray``
#: (``write``, ``read``, ``step``/wait, ``set_record_length``, ``sample_buffer``) can be passed
#: to :func:`acquire_testu` / :func:`acquire_testa`. The protocol client is not written yet;
#: this hook names the place where ``jvl-tune`` will open it.
SERIAL_SOURCE_HOOK: str = "tuning.serial_source.SerialMotor (MacTalk client, jvl-tune --port)"

ALIGN_ELDEG: int = 341  #: ELDEG_IST whose zero-torque axis is the TESTU a–c current (60° el.)
MANI_CURRENT: int = 400  #: MAN_I_NOM of the final alignment (332 ADC counts at AMPLITUDE 0.83)


def _step_until(m: Any, done: Any, max_samples: int, chunk: int = 5) -> None:
    for _ in range(0, max_samples, chunk):
        if done():
            return
        m.step(chunk)


def align_rotor(m: Any, timeout_s: float = 3.0) -> None:
    """Turn the rotor (P_MODE, the motor's present setup) to ELDEG_IST = :data:`ALIGN_ELDEG`.

    There the TESTU current (ia = −ic, ib = 0) lies on the rotor's d-axis, produces no torque,
    and the rotor stays at rest during the record: no back-EMF disturbs it. Then 0.3 s of
    MANI_MODE with the field on that axis (MAN_ALPHA = 341 ≙ 60° el.). Restores P_SOLL, V_SOLL,
    A_SOLL, MAN_I_NOM and leaves the motor in INIT_MODE.
    """
    ts_o = record_facts_of(m).ts_o
    saved = {k: np.asarray(m.read(k)).copy() for k in ("P_SOLL", "V_SOLL", "A_SOLL")}
    el = np.asarray(m.read("ELDEG_IST"))
    d = ((ALIGN_ELDEG - el + 1024) % 2048) - 1024
    m.write("P_SOLL", np.asarray(m.read("P_IST")) + d)
    m.write("V_SOLL", 500)
    m.write("A_SOLL", 20)
    m.write("MODE_REG", 2)
    quiet = np.zeros(m.n, dtype=int)

    def settled() -> bool:
        v = np.asarray(m.read("V_IST"))
        err = np.abs(((np.asarray(m.read("ELDEG_IST")) - ALIGN_ELDEG + 1024) % 2048) - 1024)
        quiet[:] = np.where((v == 0) & (err <= 1), quiet + 1, 0)
        return bool(np.all(quiet >= 4))

    _step_until(m, settled, int(timeout_s / ts_o))
    _to_init(m)
    # Friction can stop the position loop short of the angle. Finish with the stator field
    # itself (MANI_MODE, 3.2.128/129) on the TESTU axis, stronger than the TESTU current: the
    # rotor turns until the misalignment torque equals the friction, so the weaker TESTU
    # current cannot move it. Without friction the rotor is already aligned (±1 count).
    man = np.asarray(m.read("MAN_I_NOM")).copy()
    m.write("MAN_I_NOM", MANI_CURRENT)
    m.write("MAN_ALPHA", ALIGN_ELDEG)
    m.write("MODE_REG", 7)
    m.step(int(0.3 / ts_o))
    _to_init(m)
    m.step(int(0.05 / ts_o))  # let the MANI current decay (L/R ≈ 1 ms) before TESTU
    m.write("MAN_I_NOM", man)
    for k, v in saved.items():
        m.write(k, v)


def _to_init(m: Any) -> None:
    m.write("MODE_REG", 0)
    _step_until(m, lambda: bool(np.all(np.asarray(m.read("MODE_REG")) == 0)), 2000, 1)


def acquire_testu(m: Any, umeas: int = 100, n_samples: int = 64, align: bool = True
                  ) -> list[Record]:
    """Run TESTU (manual 4.4.9) on every motor of ``m`` and return one record per motor.

    Parameters
    ----------
    m : MotorArray or compatible
        Motors in INIT_MODE.
    umeas : int
        UMEAS [PWM counts] (0..100, 3.2.130).
    n_samples : int
        Record length (manual: 11; recommended 64 ≈ 8 coil time constants of 1 ms).
    align : bool
        Turn the rotor to the zero-torque angle first (:func:`align_rotor`).
    """
    facts = record_facts_of(m)
    if align:
        align_rotor(m)
    m.set_record_length(n_samples)
    m.write("UMEAS", umeas)
    m.write("MODE_REG", 8)
    m.step(int(math.ceil(n_samples / facts.inner_per_outer)) + 2)
    buf = m.sample_buffer()
    names = [cfg.name for cfg in getattr(m, "motor_configs", [None] * m.n)]
    return [validate(Record("TESTU", facts.rates["TESTU"], buf["UA_VAL"][i, :n_samples],
                            buf["IC_IST"][i, :n_samples], names[i],
                            {"source": "MotorArray", "UMEAS": umeas}), facts)
            for i in range(m.n)]


def acquire_testa(m: Any, t_soll: Sequence[float] | np.ndarray | float, n_samples: int = 64
                  ) -> list[Record]:
    """Run TESTA (manual 4.4.10) once on every motor with per-motor ``t_soll``; wait for
    BREAK_MODE to stop the motor and INIT_MODE; return one record per motor.

    Each record's ``meta["registers"]`` holds the :data:`TESTA_REGISTERS` read from the motor
    (the current loop, PHASE_COMP, AMPLITUDE the record was taken with), so the electrical
    TESTA model can be used on the record alone (also after :func:`save_csv`/:func:`load_csv`).
    """
    t = np.broadcast_to(np.asarray(t_soll, dtype=float), (m.n,)).round()
    old = np.asarray(m.read("T_SOLL")).copy()
    m.set_record_length(n_samples)
    m.write("T_SOLL", t)
    m.write("MODE_REG", 9)
    m.step(n_samples + 2)
    buf = m.sample_buffer()
    _step_until(m, lambda: bool(np.all(np.asarray(m.read("MODE_REG")) == 0)), 20000, 10)
    m.step(20)
    m.write("T_SOLL", old)
    names = [cfg.name for cfg in getattr(m, "motor_configs", [None] * m.n)]
    regs = {k: np.broadcast_to(np.asarray(m.read(k), dtype=float), (m.n,)) for k in TESTA_REGISTERS}
    rate = record_facts_of(m).rates["TESTA"]
    return [Record("TESTA", rate, buf["T_SOLL"][i, :n_samples],
                   buf["V_IST"][i, :n_samples], names[i],
                   {"source": "MotorArray", "T_SOLL": float(t[i]),
                    "registers": {k: float(v[i]) for k, v in regs.items()}})
            for i in range(m.n)]

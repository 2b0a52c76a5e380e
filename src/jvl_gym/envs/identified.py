"""Envs of an identified motor: an env's motor and randomisation from what ``jvl-tune
autotune`` measured.

``jvl-tune autotune --out DIR`` (the tuning toolkit, docs/tuning.md) writes ``DIR/report.txt``
(the identified values with their 95 % intervals: total inertia J, viscous friction b, Coulomb
friction T_c, and with ``--resonance`` the two-mass load's resonance) and ``DIR/setup.yaml``
(the motor type and the register set it designed and, with ``--write``, wrote to the motor).
:func:`read_identification` reads that output; :func:`identification_of` takes the same from
the toolkit's result in memory (``tuning.serial_source.autotune_over_serial``,
``tuning.pipeline.autotune``). :func:`env_kwargs_from_identification` turns either into the
keyword arguments of an env whose motor is the one measured:

- ``motor_type``: the setup's motor type;
- ``randomization``: the identified 95 % intervals, clipped to physical bounds (nothing below
  0): ``inertia_ratio`` = (J − J_m)/J_m with the type's rotor inertia J_m (the env's load is
  ``inertia_ratio × J_m``), ``viscous_friction`` = b, ``coulomb_ratio`` = T_c / rated torque,
  and for a detected two-mass resonance ``resonance_hz`` over its interval with the identified
  damping ratio (docs/envs.md "Compliant loads"); each where the env has that range;
- ``setup``: the motor type's default setup with the written registers over it, the registers
  the motor holds after ``jvl-tune autotune --write`` (the env's motors power on with them;
  what a task writes at its reset comes after, e.g. Positioning's KVOUT for the drawn load).

``jvl_gym`` does not import the toolkit: the report is read as text, the result in memory by
its attributes.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["Identified", "IdentificationError", "read_identification", "parse_report",
           "identification_of", "env_kwargs_from_identification", "REPORT_FILE", "SETUP_FILE",
           "MAX_REPORT_BYTES"]

#: the files ``jvl-tune autotune --out DIR`` writes that an identified env is built from
REPORT_FILE = "report.txt"
SETUP_FILE = "setup.yaml"
#: the largest report read [bytes] (one is a few kB): a larger file is refused by its size, unread
MAX_REPORT_BYTES = 1 << 20

#: the rows of the report's identification table (``tuning.report.identification_table``)
#: read, label → field
_ROWS = {"J total [kg m^2]": "inertia", "viscous b [N m s/rad]": "viscous",
         "Coulomb Tc [N m]": "coulomb"}
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_ROW = re.compile(rf"^(?P<label>{'|'.join(re.escape(k) for k in _ROWS)})\s+"
                  rf"(?P<value>{_NUMBER})\s+\[(?P<lo>{_NUMBER}),\s*(?P<hi>{_NUMBER})\]")
#: the two-mass line of ``jvl-tune autotune --resonance``'s report section
_RESONANCE = re.compile(rf"^\s*resonance (?P<f>{_NUMBER}) Hz \(95 % (?P<lo>{_NUMBER}) \.\. "
                        rf"(?P<hi>{_NUMBER})\),.*damping ratio (?P<zeta>{_NUMBER}), detected "
                        r"(?P<detected>True|False)")


class IdentificationError(ValueError):
    """An identification an env cannot be built from (one line: the file and the reason)."""


@dataclass(frozen=True)
class Identified:
    """What an identification says of a motor, as an env takes it.

    Attributes
    ----------
    motor_type : str
        The motor type (its family's name for it).
    inertia, viscous, coulomb : tuple of float
        (estimate, low, high) of the total inertia J [kg·m²], the viscous friction b
        [N·m·s/rad] and the Coulomb friction T_c [N·m]: the estimate and its 95 % interval.
    resonance : tuple of float or None
        (estimate, low, high) [Hz] of a detected two-mass resonance, else None.
    damping_ratio : float
        The two-mass coupling's modal damping ratio (with ``resonance``).
    registers : dict
        The register set designed for the motor (the setup), name → value.
    source : str
        Where it was read (a path, or ``"result"``).
    """

    motor_type: str
    inertia: tuple[float, float, float]
    viscous: tuple[float, float, float]
    coulomb: tuple[float, float, float]
    resonance: tuple[float, float, float] | None = None
    damping_ratio: float = 0.0
    registers: dict[str, float] = field(default_factory=dict)
    source: str = "result"


# ----------------------------------------------------------------------------- reading
def _files(path: str | os.PathLike[str]) -> tuple[Path, Path]:
    """``report.txt`` and ``setup.yaml`` of an autotune output: its folder, or either file."""
    p = Path(path)
    folder = p if p.is_dir() else p.parent
    if not p.exists():
        raise IdentificationError(f"{p}: not found; give the folder `jvl-tune autotune --out` "
                                  f"wrote ({REPORT_FILE} and {SETUP_FILE})")
    if not p.is_dir() and p.name not in (REPORT_FILE, SETUP_FILE):
        raise IdentificationError(f"{p}: not an autotune output; give the folder `jvl-tune "
                                  f"autotune --out` wrote ({REPORT_FILE} and {SETUP_FILE})")
    report, setup = folder / REPORT_FILE, folder / SETUP_FILE
    for f in (report, setup):
        if not f.is_file():
            raise IdentificationError(f"{folder}: no {f.name}; an identified env needs both "
                                      f"files `jvl-tune autotune --out` writes ({REPORT_FILE} "
                                      f"and {SETUP_FILE})")
    return report, setup


def _text(path: Path) -> str:
    try:
        size = path.stat().st_size
        if size > MAX_REPORT_BYTES:
            raise IdentificationError(f"{path}: {size} bytes is more than an autotune report "
                                      f"has ({MAX_REPORT_BYTES} bytes at most); give the "
                                      "folder `jvl-tune autotune --out` wrote")
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise IdentificationError(f"{path}: not UTF-8 text ({exc.reason} at byte "
                                  f"{exc.start})") from None
    except OSError as exc:
        raise IdentificationError(f"{path}: cannot be read: {exc.strerror or exc}") from None


def _triple(where: str, name: str, value: float, lo: float, hi: float
            ) -> tuple[float, float, float]:
    """(value, lo, hi), checked: finite, ``lo <= value <= hi``."""
    if not all(math.isfinite(x) for x in (value, lo, hi)):
        raise IdentificationError(f"{where}: {name} is not a finite number with a finite "
                                  f"interval: {value} [{lo}, {hi}]")
    if not lo <= hi or not lo - 1e-3 * abs(lo) <= value <= hi + 1e-3 * abs(hi):
        raise IdentificationError(f"{where}: {name} {value:g} with interval [{lo:g}, {hi:g}]: "
                                  "the interval must hold the estimate")
    return float(value), float(lo), float(hi)


def parse_report(text: str, where: str = "report") -> dict[str, Any]:
    """The identified values of a ``report.txt``'s text: ``inertia``, ``viscous``,
    ``coulomb`` as (estimate, low, high), and ``resonance`` (or None) and
    ``damping_ratio`` of a two-mass section.

    Raises
    ------
    IdentificationError
        A row missing or repeated, a value or interval that is not a finite number, an
        interval that does not hold its estimate, J not above 0.
    """
    found: dict[str, tuple[float, float, float]] = {}
    resonance: tuple[float, float, float] | None = None
    zeta = 0.0
    for ln, line in enumerate(text.splitlines(), 1):
        m = _ROW.match(line)
        if m is not None:
            key = _ROWS[m["label"]]
            if key in found:
                raise IdentificationError(f"{where}:{ln}: '{m['label']}' appears twice; one "
                                          "report holds one identification")
            found[key] = _triple(f"{where}:{ln}", m["label"], float(m["value"]),
                                 float(m["lo"]), float(m["hi"]))
            continue
        r = _RESONANCE.match(line)
        if r is not None and r["detected"] == "True":
            resonance = _triple(f"{where}:{ln}", "resonance", float(r["f"]), float(r["lo"]),
                                float(r["hi"]))
            zeta = float(r["zeta"])
            if resonance[1] <= 0.0 or not math.isfinite(zeta) or zeta < 0.0:
                raise IdentificationError(f"{where}:{ln}: a detected resonance needs an "
                                          "interval above 0 Hz and a damping ratio >= 0")
    missing = [label for label, key in _ROWS.items() if key not in found]
    if missing:
        raise IdentificationError(f"{where}: no row {', '.join(repr(k) for k in missing)} with "
                                  "an estimate and a 95 % interval; is it the report.txt of "
                                  "`jvl-tune autotune`?")
    if found["inertia"][0] <= 0.0:
        raise IdentificationError(f"{where}: the identified J is {found['inertia'][0]:g}; an "
                                  "env needs an inertia above 0")
    return {**found, "resonance": resonance, "damping_ratio": zeta}


def _setup(path: Path) -> tuple[str, dict[str, float]]:
    """The motor type and registers of a setup file, each register checked against its
    family's table (a writable register with a value in range)."""
    from ..families import family_of_motor
    from ..families.config import ConfigError, load_setup
    from ..registers import Access, RegisterError, to_raw

    try:
        cfg = load_setup(path)
    except ConfigError as exc:
        raise IdentificationError(" ".join(str(exc).split())) from None
    if not cfg.motor:
        raise IdentificationError(f"{path}: no 'motor:' line; `jvl-tune autotune` names the "
                                  "motor type the setup is for")
    try:
        fam = family_of_motor(cfg.motor)
    except (ConfigError, KeyError, ValueError) as exc:
        raise IdentificationError(f"{path}: motor {cfg.motor!r}: "
                                  f"{' '.join(str(exc).split())}") from None
    regs: dict[str, float] = {}
    for name, value in (cfg.registers or {}).items():
        try:
            reg = fam.table.lookup(name)
            if reg.access != Access.RW:
                raise RegisterError(f"{name} is not a parameter register")
            to_raw(reg, float(value))
        except (RegisterError, KeyError, ValueError, TypeError) as exc:
            raise IdentificationError(f"{path}: register {name}: "
                                      f"{' '.join(str(exc).split())}") from None
        regs[reg.name] = float(value)
    return fam.canonical_name(cfg.motor), regs


def read_identification(path: str | os.PathLike[str]) -> Identified:
    """The identification ``jvl-tune autotune --out DIR`` wrote: ``DIR`` or one of its files
    (``report.txt``, ``setup.yaml``; the other is read from the same folder).

    Raises
    ------
    IdentificationError
        One line naming the file: a file missing or unreadable, a report without the
        identified values and their intervals (:func:`parse_report`), a setup without a known
        motor type or with a register its family's table refuses.
    """
    report, setup = _files(path)
    values = parse_report(_text(report), str(report))
    motor_type, regs = _setup(setup)
    return Identified(motor_type, values["inertia"], values["viscous"], values["coulomb"],
                      values["resonance"], values["damping_ratio"], regs, str(report.parent))


def identification_of(result: Any, registers: Mapping[str, float] | None = None) -> Identified:
    """An :class:`Identified` from the toolkit's result in memory: a ``tuning.pipeline.Result``
    (its identification and kept registers) or an identification itself (``.motor``,
    ``.mechanics``; then ``registers`` gives the setup, default none)."""
    ident = getattr(result, "ident", result)
    if registers is None and hasattr(result, "chosen"):
        registers = result.chosen.registers
    try:
        mech, name = ident.mechanics, ident.motor.name
        rows = {key: (float(getattr(mech, attr)), *map(float, mech.ci[attr]))
                for key, attr in (("inertia", "J"), ("viscous", "viscous"),
                                  ("coulomb", "coulomb"))}
    except (AttributeError, KeyError, TypeError) as exc:
        raise IdentificationError(f"not an identification of the tuning toolkit: {exc}") \
            from None
    checked = {k: _triple("result", k, *v) for k, v in rows.items()}
    if checked["inertia"][0] <= 0.0:
        raise IdentificationError(f"result: the identified J is {checked['inertia'][0]:g}; an "
                                  "env needs an inertia above 0")
    return Identified(name, checked["inertia"], checked["viscous"], checked["coulomb"],
                      registers={k: float(v) for k, v in (registers or {}).items()})


# ----------------------------------------------------------------------------- the env
def _nonnegative(lo: float, hi: float, scale: float = 1.0) -> tuple[float, float]:
    return max(lo * scale, 0.0), max(hi * scale, 0.0)


def env_kwargs_from_identification(source: Identified | Any | str | os.PathLike[str],
                                   env_id: str) -> dict[str, Any]:
    """Keyword arguments of ``env_id`` for the motor ``source`` identified (module docstring).

    Parameters
    ----------
    source : Identified, path or toolkit result
        An :class:`Identified`, the output of ``jvl-tune autotune --out DIR``
        (:func:`read_identification`), or the toolkit's result in memory
        (:func:`identification_of`).
    env_id : str
        A registered env id whose task runs on the motor's family and randomises the load's
        inertia (``inertia_ratio``).

    Returns
    -------
    dict
        ``motor_type``, ``randomization`` and ``setup`` (for ``gymnasium.make``,
        ``make_link_vec``, ``jvl-gym train --identified``).

    Raises
    ------
    IdentificationError
        A bad file or result, or an env that does not run on the motor's family or has no
        load inertia to randomise.
    """
    from ..families import family_of_motor
    from ..families.config import load_setup
    from .registration import ENV_IDS, vector_class

    if isinstance(source, Identified):
        ident = source
    elif isinstance(source, (str, os.PathLike)):
        ident = read_identification(source)
    else:
        ident = identification_of(source)
    if env_id not in ENV_IDS:
        raise IdentificationError(f"unknown env {env_id!r}; known: {', '.join(ENV_IDS)}")
    cls = vector_class(env_id)
    fam = family_of_motor(ident.motor_type)
    if fam.key not in cls.supported_families():
        raise IdentificationError(f"{env_id} does not run on the {fam.title} "
                                  f"({ident.motor_type}, {ident.source}); it runs on: "
                                  f"{', '.join(cls.supported_families())}")
    if "inertia_ratio" not in cls.default_ranges:
        raise IdentificationError(f"{env_id} randomises no load inertia (inertia_ratio); an "
                                  "identified motor has nothing to set in it")
    cfg = fam.array_class.load_motor(ident.motor_type)
    j_m = float(cfg.rotor_inertia)
    ranges: dict[str, tuple[float, float]] = {
        "inertia_ratio": _nonnegative(ident.inertia[1] - j_m, ident.inertia[2] - j_m, 1 / j_m)}
    if "viscous_friction" in cls.default_ranges:
        ranges["viscous_friction"] = _nonnegative(ident.viscous[1], ident.viscous[2])
    if "coulomb_ratio" in cls.default_ranges:
        ranges["coulomb_ratio"] = _nonnegative(ident.coulomb[1], ident.coulomb[2],
                                               1 / float(cfg.rated_torque))
    if ident.resonance is not None:
        ranges["resonance_hz"] = _nonnegative(ident.resonance[1], ident.resonance[2])
        ranges["coupling_damping_ratio"] = (ident.damping_ratio, ident.damping_ratio)
    default = load_setup(fam.config.setup_path(cfg.setup)).registers
    registers = {**default, **ident.registers}
    return {"motor_type": ident.motor_type, "randomization": ranges,
            "setup": {"motor": ident.motor_type, "registers": registers}}

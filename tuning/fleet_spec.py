"""The fleet: a fleet file (``configs/fleets/*.yml``) or a folder of recorded CSVs.

Fleet file (every key but ``motors`` optional)::

    seed: 0                 # draws and simulator noise
    noise: true             # 1 % current and position noise, as jvl-tune autotune
    structure: pi           # speed loop structure (pi or ip)
    n_coil: 64              # TESTU samples
    n_mech: 64              # TESTA samples per level
    move: {distance: 20000, v_soll: 2000, seconds: 2.0}   # settle-time move [counts, 1/16
                                                          # count/sample, s]
    motors:
      - type: MAC140
        count: 4
        load_ratio: {uniform: [0, 10]}          # J_load / J_m  (or load_inertia [kg m^2])
        viscous: {uniform: [0, 1.0e-5]}         # [N m s/rad]
        coulomb: {uniform: [0, 0.015]}          # [N m]

Each of ``load_ratio`` / ``load_inertia``, ``viscous`` and ``coulomb`` is a number or a
distribution (:mod:`jvl_gym.scale.distributions`); missing ones are 0.

Records folder: one subfolder per motor holding its TESTU and TESTA record CSVs (anywhere below
it; the layout of :mod:`tuning.records`, ``# motor:`` naming the type), optionally a
``motor.yaml`` with ``type:`` and ``truth:`` (``J`` [kg m^2], ``viscous``, ``coulomb``, …) for
the error columns of the report (``jvl-tune fleet --save-records`` writes such folders).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from jvl_gym.scale.distributions import parse_distribution
from jvl_gym.scale.errors import UserError, file_flag, file_mapping, file_number, read_yaml

__all__ = ["FleetMotor", "FleetSpec", "load_fleet", "parse_fleet", "fleet_from_records"]

_KEYS = {"seed", "noise", "structure", "n_coil", "n_mech", "move", "motors"}
_GROUP = {"type", "count", "load_ratio", "load_inertia", "viscous", "coulomb"}
_MOVE = {"distance", "v_soll", "seconds"}


@dataclass
class FleetMotor:
    """One motor of the fleet.

    Attributes
    ----------
    motor_id : str
        ``m<index>-<type>`` (simulated) or the subfolder's name (records).
    type : str
        Motor type, e.g. ``"MAC140"``.
    seed : int
        Simulator seed (simulated motors).
    load_inertia, viscous, coulomb : float
        Simulated load [kg m^2], viscous [N m s/rad] and Coulomb friction [N m].
    initial_angle : float
        Rotor angle at power-on [rad] (simulated motors).
    records : list of Path
        Record CSVs (records folder); empty for a simulated motor.
    record_data : dict
        File name -> contents of the record CSVs, filled by the driver before the motor is
        sent to a Ray task (so the task needs no access to the folder).
    truth : dict
        Known true values (``J``, ``viscous``, ``coulomb``, ``R_line``, ``L_line_mH``);
        empty when unknown.
    """

    motor_id: str
    type: str
    seed: int = 0
    load_inertia: float = 0.0
    viscous: float = 0.0
    coulomb: float = 0.0
    initial_angle: float = 0.0
    records: list[Path] = field(default_factory=list)
    truth: dict[str, float] = field(default_factory=dict)
    record_data: dict[str, bytes] = field(default_factory=dict, repr=False)

    @property
    def simulated(self) -> bool:
        """The motor is simulated (no records)."""
        return not self.records


@dataclass
class FleetSpec:
    """A parsed fleet.

    Attributes
    ----------
    source : Path or None
        Fleet file or records folder.
    motors : list of FleetMotor
        The motors.
    noise : bool
        Simulator measurement noise.
    structure : str
        Speed-loop structure.
    n_coil, n_mech : int
        TESTU samples, TESTA samples per level.
    move : dict
        Settle-time move: ``distance`` [counts], ``v_soll`` [1/16 count/sample], ``seconds``.
    """

    source: Path | None
    motors: list[FleetMotor]
    noise: bool = True
    structure: str = "pi"
    n_coil: int = 64
    n_mech: int = 64
    move: dict[str, float] = field(default_factory=lambda: {
        "distance": 20000, "v_soll": 2000, "seconds": 2.0})


def _motor_types() -> list[str]:
    """The motor types a fleet may hold: those of the families with the TESTU/TESTA test modes
    the fleet's identification records (:attr:`~jvl_gym.families.Capability.TEST_MODES`)."""
    from jvl_gym.families import Capability, families, family

    return [t for k in families() if family(k).supports(Capability.TEST_MODES)
            for t in family(k).motor_types()]


def _int(value: Any, where: str, low: int = 1) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise UserError(f"{where}: expected an integer >= {low}, got {value!r}")
    return value


def parse_fleet(data: Any, path: Path | None = None) -> FleetSpec:
    """Validate a fleet mapping (module docstring) and draw its motors.

    Raises
    ------
    UserError
        On any malformed entry; the message names the file and the key.
    """
    from .models import MotorData

    where = str(path) if path is not None else "fleet"
    if data is None:
        raise UserError(f"{where}: expected a mapping with keys {sorted(_KEYS)}")
    data = file_mapping(data, where, _KEYS)
    groups = data.get("motors")
    if not isinstance(groups, list) or not groups:
        raise UserError(f"{where}: motors: expected a list of groups "
                        "({type: MAC140, count: 4, load_ratio: ..., viscous: ..., coulomb: ...})")
    seed = _int(data.get("seed", 0), f"{where}: seed", 0)
    structure = data.get("structure", "pi")
    if structure not in ("pi", "ip"):
        raise UserError(f"{where}: structure: {structure!r} is not 'pi' or 'ip'")
    move_raw = data.get("move") or {}
    if not isinstance(move_raw, dict) or set(move_raw) - _MOVE:
        raise UserError(f"{where}: move: expected a mapping with keys {sorted(_MOVE)}")
    move = {k: file_number(v, f"{where}: move.{k}", positive=True) for k, v in
            {"distance": 20000, "v_soll": 2000, "seconds": 2.0, **move_raw}.items()}
    types = _motor_types()
    rng = np.random.default_rng(seed)
    motors: list[FleetMotor] = []
    for g, group in enumerate(groups):
        gw = f"{where}: motors[{g}]"
        if group is None:
            raise UserError(f"{gw}: expected a mapping with keys {sorted(_GROUP)}")
        group = file_mapping(group, gw, _GROUP)
        mtype = group.get("type")
        if mtype not in types:
            raise UserError(f"{gw}: type: {mtype!r} is not a motor type; use one of "
                            f"{', '.join(types)}")
        count = _int(group.get("count", 1), f"{gw}: count")
        if "load_ratio" in group and "load_inertia" in group:
            raise UserError(f"{gw}: give load_ratio or load_inertia, not both")
        jm = MotorData.from_config(mtype).J_m
        draws = {}
        for key in ("load_ratio", "load_inertia", "viscous", "coulomb"):
            dist = parse_distribution(group.get(key, 0.0), f"{gw}: {key}", numeric=True)
            values = dist.sample(rng, count)
            if any(v < 0 or not math.isfinite(v) for v in values):
                raise UserError(f"{gw}: {key}: values must be finite numbers >= 0 (the "
                                "distribution reaches below 0: narrow it or use truncnormal)")
            draws[key] = values
        angles = rng.uniform(0, 2 * np.pi, count)
        for i in range(count):
            load = (draws["load_ratio"][i] * jm if "load_ratio" in group
                    else draws["load_inertia"][i])
            idx = len(motors)
            m = FleetMotor(f"m{idx:03d}-{mtype}", mtype, seed=seed * 100_003 + idx,
                           load_inertia=float(load), viscous=float(draws["viscous"][i]),
                           coulomb=float(draws["coulomb"][i]), initial_angle=float(angles[i]))
            m.truth = {"J": jm + m.load_inertia, "viscous": m.viscous, "coulomb": m.coulomb}
            motors.append(m)
    return FleetSpec(path, motors, noise=file_flag(data.get("noise", True), f"{where}: noise"),
                     structure=structure,
                     n_coil=_int(data.get("n_coil", 64), f"{where}: n_coil", 11),
                     n_mech=_int(data.get("n_mech", 64), f"{where}: n_mech", 11),
                     move=move)


def fleet_from_records(folder: Path, structure: str = "pi") -> FleetSpec:
    """A fleet from a folder with one subfolder of record CSVs per motor.

    Raises
    ------
    UserError
        No subfolders with CSVs, a subfolder without TESTU or TESTA records, records of
        different motor types, or an unknown type.
    """
    from .records import RecordError, load_csv

    subdirs = sorted(p for p in folder.iterdir() if p.is_dir() and any(p.rglob("*.csv")))
    if not subdirs:
        raise UserError(f"{folder}: no subfolders with record CSVs; put each motor's TESTU and "
                        "TESTA CSVs in a subfolder of its own")
    types = _motor_types()
    motors = []
    for sub in subdirs:
        files = sorted(sub.rglob("*.csv"))
        meta: dict[str, Any] = {}
        if (sub / "motor.yaml").is_file():
            try:
                meta = yaml.safe_load((sub / "motor.yaml").read_text()) or {}
            except yaml.YAMLError:
                raise UserError(f"{sub / 'motor.yaml'}: not valid YAML; fix or remove it") \
                    from None
        kinds: dict[str, int] = {"TESTU": 0, "TESTA": 0}
        found: set[str] = set()
        for f in files:
            try:
                rec = load_csv(f, meta.get("type"))
            except RecordError as exc:
                raise UserError(f"{exc}; fix or remove the file") from None
            kinds[rec.kind] += 1
            if rec.motor:
                found.add(rec.motor)
        if not kinds["TESTU"] or not kinds["TESTA"]:
            raise UserError(f"{sub}: needs TESTU and TESTA record CSVs, found "
                            f"{kinds['TESTU']} TESTU and {kinds['TESTA']} TESTA")
        mtype = meta.get("type") or (found.pop() if len(found) == 1 else None)
        if mtype is None:
            raise UserError(f"{sub}: the records name {sorted(found) or 'no'} motor type(s); "
                            "add motor.yaml with 'type: MAC140'")
        if mtype not in types:
            raise UserError(f"{sub}: motor type {mtype!r} is not one of {', '.join(types)}")
        truth = {k: float(v) for k, v in (meta.get("truth") or {}).items()}
        motors.append(FleetMotor(sub.name, mtype, records=files, truth=truth,
                                 load_inertia=float(meta.get("load_inertia", 0.0))))
    return FleetSpec(folder, motors, structure=structure)


def load_fleet(path: str | Path) -> FleetSpec:
    """A fleet file or a records folder (module docstring).

    Raises
    ------
    UserError
        Missing path, YAML syntax error, or a malformed entry.
    """
    path = Path(path)
    if path.is_dir():
        return fleet_from_records(path)
    if not path.is_file():
        raise UserError(f"{path}: no such fleet file or records folder; give a YAML file such "
                        "as configs/fleets/example.yml or a folder with one subfolder per motor")
    data = read_yaml(path)
    return parse_fleet(data, path)

"""``jvl-tune fleet``: every motor of a fleet autotuned as a Ray task, then the fleet report.

One Ray task per motor (:func:`tuning.fleet_motor.tune_motor`, one CPU each); a recorded
motor's CSVs are read here and sent with its task. The driver writes each motor's files under
``<out>/motors/<motor_id>/`` as its task finishes (the tasks return the files' bytes, so on a
cluster nothing needs a shared filesystem) and prints one line per motor; at the end it writes
the fleet report (:mod:`tuning.fleet_report`).
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import typer

from jvl_gym.scale.commands import out_dir, say
from jvl_gym.scale.errors import UserError, run_cli
from jvl_gym.scale.extra import require_ray
from jvl_gym.scale.ray_session import connect

from .fleet_report import write_fleet_report
from .fleet_spec import FleetMotor, FleetSpec

__all__ = ["run_fleet", "fleet_command"]

Progress = Callable[[str], None]


def _task(motor: Any, spec: Any, save_records: bool) -> dict[str, Any]:
    from .fleet_motor import tune_motor

    return tune_motor(motor, spec, save_records)


def _with_data(motor: FleetMotor) -> FleetMotor:
    """A recorded motor with its CSVs' contents (read here, on the driver)."""
    if not motor.records:
        return motor
    data = {f"{k:03d}-{Path(p).name}": Path(p).read_bytes()
            for k, p in enumerate(motor.records)}
    return dataclasses.replace(motor, record_data=data)


def _ms(value: float, spec: FleetSpec) -> str:
    return f"{1e3 * value:.0f}" if math.isfinite(value) else f">{1e3 * spec.move['seconds']:.0f}"


def run_fleet(spec: FleetSpec, out: str | Path, address: str | None = None,
              num_cpus: int | None = None, save_records: bool = False,
              progress: Progress = print, verbose: bool = False) -> list[dict[str, Any]]:
    """Autotune every motor of ``spec`` on Ray and write the per-motor files and the report.

    Parameters
    ----------
    spec : FleetSpec
        The fleet.
    out : path
        Output directory: ``motors/<id>/`` (``setup.yaml`` = the register set,
        ``report.txt``, plots, ``motor.yaml``), ``fleet.csv``, ``fleet.md``, ``fleet.png``.
    address : str, optional
        Ray cluster (``None``: local Ray).
    num_cpus : int, optional
        CPUs of the local Ray (default all).
    save_records : bool
        Also write each motor's TESTU/TESTA records (``motors/<id>/records/``), so
        ``<out>/motors`` can be run again as a records folder.
    progress : callable
        Receives the progress lines.
    verbose : bool
        Forward the workers' logs.

    Returns
    -------
    list of dict
        The report rows, in fleet order.
    """
    out = Path(out).resolve()
    ray = connect(address, num_cpus, log_to_driver=verbose)
    remote = ray.remote(num_cpus=1)(_task)
    spec_ref = ray.put(spec)
    pending = {remote.remote(_with_data(m), spec_ref, save_records): m for m in spec.motors}
    n = len(pending)
    progress(f"{n} motors as Ray tasks on {int(ray.cluster_resources().get('CPU', 0))} CPUs")
    rows: dict[str, dict[str, Any]] = {}
    while pending:
        ready, _ = ray.wait(list(pending), num_returns=1)
        motor = pending.pop(ready[0])
        try:
            res = ray.get(ready[0])
        except Exception as exc:  # noqa: BLE001  (a failed task is one motor's result)
            res = {"row": {"motor": motor.motor_id, "type": motor.type, "credible": False,
                           "reasons": f"task failed: {type(exc).__name__}: {exc}"},
                   "files": {}}
        row = res["row"]
        mdir = out / "motors" / motor.motor_id
        for name, data in res["files"].items():
            path = mdir / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
        mdir.mkdir(parents=True, exist_ok=True)
        (mdir / "result.json").write_text(json.dumps(row, indent=1, default=float))
        rows[motor.motor_id] = row
        err = f", J error {100 * row['J_err']:+.2f} %" if "J_err" in row else ""
        settle = ""
        if "settle_tuned_s" in row:
            settle = (f", settle {_ms(row['settle_default_s'], spec)} -> "
                      f"{_ms(row['settle_tuned_s'], spec)} ms")
        flag = "" if row.get("credible") else f"  NOT CREDIBLE: {row.get('reasons')}"
        jtext = f"J {row['J']:.4g} kg m^2" if "J" in row else "no J"
        progress(f"[{len(rows)}/{n}] {motor.motor_id}: {jtext}{err}{settle}, checks "
                 f"{row.get('checks', '-')}, {row.get('wall_s', float('nan')):.0f} s{flag}")
    ordered = [rows[m.motor_id] for m in spec.motors]
    files = write_fleet_report(spec, ordered, out)
    progress(f"fleet report: {', '.join(str(f) for f in files)}")
    return ordered


def fleet_command(spec_path: Path, out: Path, address: str | None = None,
                  num_cpus: int | None = None, save_records: bool = False,
                  structure: str | None = None, verbose: bool = False) -> None:
    """``jvl-tune fleet``: autotune a fleet file or records folder; exit 1 if a motor has no
    design or its design fails the checks (non-credible identifications are listed in the
    report).

    Parameters
    ----------
    spec_path : Path
        Fleet file or records folder (:mod:`tuning.fleet_spec`).
    out : Path
        Output directory.
    address, num_cpus, save_records, verbose
        See :func:`run_fleet`.
    structure : str, optional
        Speed-loop structure (overrides the file's).
    """
    def body() -> None:
        require_ray()
        from .fleet_spec import load_fleet

        spec = load_fleet(spec_path)
        if structure is not None:
            if structure not in ("pi", "ip"):
                raise UserError(f"--structure {structure!r}: use pi or ip")
            spec.structure = structure
        if num_cpus is not None and num_cpus < 1:
            raise UserError(f"--num-cpus {num_cpus}: give a positive integer")
        rows = run_fleet(spec, out_dir(out), address, num_cpus, save_records,
                         progress=say("fleet"), verbose=verbose)
        if not all(r.get("checks") == "ok" for r in rows):
            raise typer.Exit(1)

    run_cli(body)

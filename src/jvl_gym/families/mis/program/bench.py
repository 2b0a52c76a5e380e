"""A test bench for a stored program: the motor's surroundings over time (an I/O script), the
program run on a simulated motor, and its trace as CSV and a plot.

I/O script (YAML or a dict), every key optional::

    registers: {A_SOLL: 20000}        # written before the program starts (user units)
    inputs:                           # input levels from a time on [s]
      - {t: 0.0, set: {1: low, 2: high}}
      - {t: 1.5, set: {2: low}}
    sensors:                          # an input that is high while the rotor is in a window
      - {input: 3, from: 204800, to: 245760}   # motor counts from power-on
    load: 0.05                        # load torque [N·m], or steps: [{t: 0, torque: 0.05}, …]
    load_inertia: 1.0e-5              # [kg·m²]

The trace has one row per outer sample (1 ms): time, program line and state, the registers of
:data:`TRACE_REGISTERS` (raw), and the rotor position in counts.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ....registers.errors import echo
from ..units import COUNTS_PER_REV
from .executor import STATE_NAMES

if TYPE_CHECKING:
    from ..motors import MisMotorArray

__all__ = ["IoScript", "IoScriptError", "load_io_script", "run_bench", "write_csv",
           "plot_trace", "TRACE_REGISTERS"]

#: registers in every trace (raw values)
TRACE_REGISTERS = ("P_IST", "P_SOLL", "V_IST", "V_SOLL", "MODE_REG", "INPUTS", "OUTPUTS",
                   "STATUSBITS", "ERR_BITS")
_LEVELS = {"high": 1, "low": 0, 1: 1, 0: 0}  # YAML true/false are 1/0 too


class IoScriptError(ValueError):
    """The I/O script is malformed (the message names the entry)."""


@dataclass
class IoScript:
    """A checked I/O script (module docstring)."""

    registers: dict[str, float] = field(default_factory=dict)
    inputs: list[tuple[float, dict[int, int]]] = field(default_factory=list)
    sensors: list[tuple[int, float, float]] = field(default_factory=list)
    load: list[tuple[float, float]] = field(default_factory=list)
    load_inertia: float | None = None


def _number(value: Any, where: str, lo: float = -math.inf) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(
            value) or value < lo:
        raise IoScriptError(f"{where}: {echo(value)} is not a finite number"
                            + (f" >= {lo:g}" if lo > -math.inf else ""))
    return float(value)


def _input(value: Any, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 8:
        raise IoScriptError(f"{where}: input {echo(value)} is not 1 … 8")
    return value


def load_io_script(source: str | Path | Mapping[str, Any] | None) -> IoScript:
    """Read and check an I/O script (a YAML path or a mapping; None: nothing happens).

    Raises
    ------
    IoScriptError
        An unknown key or a malformed entry (named), or an unreadable file.
    """
    if source is None:
        return IoScript()
    if isinstance(source, (str, Path)):
        import yaml

        try:
            data = yaml.safe_load(Path(source).read_text(encoding="utf-8"))
        except (OSError, yaml.YAMLError) as exc:
            raise IoScriptError(f"io script {source}: {exc}") from None
    else:
        data = source
    data = {} if data is None else data
    if not isinstance(data, Mapping):
        raise IoScriptError("io script: the top level is a mapping (registers, inputs, "
                            "sensors, load, load_inertia)")
    unknown = set(data) - {"registers", "inputs", "sensors", "load", "load_inertia"}
    if unknown:
        raise IoScriptError(f"io script: unknown key {echo(sorted(unknown)[0])}; the keys are "
                            "registers, inputs, sensors, load, load_inertia")
    out = IoScript()
    regs = data.get("registers") or {}
    if not isinstance(regs, Mapping):
        raise IoScriptError("io script: registers is a mapping NAME: value")
    out.registers = {str(k): _number(v, f"registers.{k}") for k, v in regs.items()}
    for k, row in enumerate(data.get("inputs") or []):
        where = f"inputs[{k}]"
        if not isinstance(row, Mapping) or set(row) != {"t", "set"} or not isinstance(
                row["set"], Mapping):
            raise IoScriptError(f"{where}: an entry is {{t: seconds, set: {{input: level}}}}")
        levels = {}
        for name, level in row["set"].items():
            if level not in _LEVELS or isinstance(level, float):
                raise IoScriptError(f"{where}: level {echo(level)} of input {name} is not high/low")
            levels[_input(name, where)] = _LEVELS[level]
        out.inputs.append((_number(row["t"], f"{where}.t", 0.0), levels))
    out.inputs.sort(key=lambda r: r[0])
    for k, row in enumerate(data.get("sensors") or []):
        where = f"sensors[{k}]"
        if not isinstance(row, Mapping) or set(row) != {"input", "from", "to"}:
            raise IoScriptError(f"{where}: an entry is {{input: N, from: counts, to: counts}}")
        lo, hi = _number(row["from"], f"{where}.from"), _number(row["to"], f"{where}.to")
        if hi < lo:
            raise IoScriptError(f"{where}: from {lo:g} is past to {hi:g}")
        out.sensors.append((_input(row["input"], where), lo, hi))
    load = data.get("load")
    if isinstance(load, (int, float)) and not isinstance(load, bool):
        out.load = [(0.0, _number(load, "load"))]
    elif load is not None:
        if not isinstance(load, Sequence) or isinstance(load, str):
            raise IoScriptError("load: a torque [N·m] or a list of {t: s, torque: N·m}")
        for k, row in enumerate(load):
            if not isinstance(row, Mapping) or set(row) != {"t", "torque"}:
                raise IoScriptError(f"load[{k}]: an entry is {{t: seconds, torque: N·m}}")
            out.load.append((_number(row["t"], f"load[{k}].t", 0.0),
                             _number(row["torque"], f"load[{k}].torque")))
        out.load.sort(key=lambda r: r[0])
    if data.get("load_inertia") is not None:
        out.load_inertia = _number(data["load_inertia"], "load_inertia", 0.0)
    return out


def _level_at(rows: list[tuple[float, Any]], t: float, initial: Any) -> Any:
    value = initial
    for start, v in rows:
        if start <= t + 1e-12:
            value = v
        else:
            break
    return value


def run_bench(m: MisMotorArray, seconds: float, script: IoScript | None = None,
              extra: Sequence[str] = ()) -> dict[str, np.ndarray]:
    """Run motor 0's stored program for ``seconds`` with the surroundings of ``script``.

    The motor is powered on (with the script's load inertia, if any): it takes its start mode
    and the stored program starts from line 1 in position mode, as at every power-on
    (:meth:`~.api.ProgramMixin._program_power_on`, MIS manual §9.1) unless SETUP_BITS bit 1
    says not to; the script's registers are written after the power-on, before the program's
    first line runs. Before each outer sample the inputs and the load torque the script gives
    for that time are applied.

    Parameters
    ----------
    m : MisMotorArray
        The motor (index 0) with a stored program.
    seconds : float
        Duration [s] (whole outer samples of 1 ms).
    script : IoScript, optional
        Surroundings (default none).
    extra : sequence of str
        More registers to trace.

    Returns
    -------
    dict of str to ndarray
        ``t`` [s], ``line``, ``state``, every register of :data:`TRACE_REGISTERS` and
        ``extra`` (raw), ``rotor`` [counts], each (T,).
    """
    script = script or IoScript()
    names = list(dict.fromkeys([*TRACE_REGISTERS, *extra]))
    for name in names:
        m._lookup(name)
    load = {} if script.load_inertia is None else {"load_inertia": script.load_inertia}
    m.reset(0, **load)  # the power-on: the start mode, the program from line 1
    if script.registers:
        m.write_many(script.registers, index=0)
    n = int(round(seconds * m.OUTER_HZ))
    dt = 1.0 / m.OUTER_HZ
    cols: dict[str, list[float]] = {k: [] for k in ("t", "line", "state", *names, "rotor")}
    base = int(m.inputs[0, m.INPUTS["digital_inputs"]])
    scripted = {k: (base >> (k - 1)) & 1 for k in range(1, 9)}
    events = list(script.inputs)
    torque = None
    t0 = float(m.time[0])
    for k in range(n):
        t = k * dt
        while events and events[0][0] <= t + 1e-12:
            scripted.update(events.pop(0)[1])
        word = sum(v << (j - 1) for j, v in scripted.items())
        rotor = float(m.rotor_counts[0])
        for inp, lo, hi in script.sensors:
            if lo <= rotor <= hi:
                word |= 1 << (inp - 1)
        load = _level_at(script.load, t, 0.0) if script.load else None
        if word != int(m.inputs[0, m.INPUTS["digital_inputs"]]):
            m.set_input(0, digital_inputs=word)
        if load is not None and load != torque:
            m.set_input(0, load_torque=load)
            torque = load
        m.step(1)
        s = m.program_status(0)
        cols["t"].append(float(m.time[0]) - t0)
        cols["line"].append(s.line)
        cols["state"].append(s.state)
        for name in names:
            cols[name].append(float(m.read_raw(name)[0]))
        cols["rotor"].append(float(m.rotor_counts[0]))
    return {k: np.asarray(v) for k, v in cols.items()}


def write_csv(trace: Mapping[str, np.ndarray], path: str | Path) -> None:
    """The trace as CSV: a header of column names (units in brackets), one row per sample."""
    units = {"t": "t [s]", "rotor": "rotor [counts]", "state": "state (§18.2.10)"}
    keys = list(trace)
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow([units.get(k, k) for k in keys])
        for row in zip(*(trace[k] for k in keys)):
            w.writerow([f"{v:.3f}" if k == "t" else (f"{v:.1f}" if k == "rotor" else int(v))
                        for k, v in zip(keys, row)])


def plot_trace(trace: Mapping[str, np.ndarray], path: str | Path, title: str = "") -> None:
    """Position, velocity, I/O and program line over time, in one PNG."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    t = trace["t"]
    fig = Figure(figsize=(9, 8))
    FigureCanvasAgg(fig)
    ax = fig.subplots(4, 1, sharex=True)
    ax[0].plot(t, trace["P_SOLL"] / COUNTS_PER_REV, label="P_SOLL", color="0.6")
    ax[0].plot(t, trace["P_IST"] / COUNTS_PER_REV, label="P_IST")
    ax[0].set_ylabel("position [rev]")
    ax[0].legend(loc="best", fontsize=8)
    ax[1].plot(t, trace["V_IST"] / 100.0)
    ax[1].set_ylabel("V_IST [RPM]")
    for k in range(8):
        ins = (trace["INPUTS"].astype(np.int64) >> k) & 1
        outs = (trace["OUTPUTS"].astype(np.int64) >> k) & 1
        if ins.any():
            ax[2].step(t, ins * 0.8 + k, where="post", label=f"IN{k + 1}")
        if outs.any():
            ax[2].step(t, outs * 0.8 + k, where="post", linestyle="--", label=f"OUT{k + 1}")
    ax[2].set_ylabel("I/O (level + index)")
    if ax[2].lines:
        ax[2].legend(loc="best", fontsize=7, ncol=4)
    ax[3].step(t, trace["line"], where="post")
    ax[3].set_ylabel("program line")
    ax[3].set_xlabel("time [s]")
    states = sorted({int(s) for s in trace["state"]})
    ax[3].set_title("states: " + ", ".join(STATE_NAMES[s] for s in states), fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)

"""``make demo``: a MAC140 through TESTU, TESTA, a position move and a velocity profile.

Writes ``<out>/scope.png`` (a four-channel scope plot of the run) and ``<out>/summary.txt``.
Run with ``python -m jvl_gym.cli.demo --out DIR``.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..families import family_of_motor
from ..motor.array import MotorArray
from .app import writable_dir_arg

#: the motor the demo runs, and its family's constants (modes, units)
MOTOR = "MAC140"
c = family_of_motor(MOTOR).constants


def _trace(m: MotorArray, n: int, log: dict[str, list[float]], phase: str) -> None:
    for _ in range(n):
        m.step()
        log["t"].append(float(m.time[0]))
        log["rpm"].append(float(m.speed_rpm[0]))
        log["profile_rpm"].append(c.v_soll_to_rpm(float(m.read("FNC_OUT")[0])))
        log["p_ist"].append(float(m.read("P_IST")[0]))
        log["vf_out"].append(float(m.read("VF_OUT")[0]))
        log["i_a"].append(float(m.phase_currents[0, 0]))
        log["i_abs"].append(float(np.sqrt(np.sum(m.phase_currents[0] ** 2) / 1.5)))
        log["phase"].append(phase)


def run_demo(out: Path) -> str:
    """Run the demo sequence, write the plot and the summary, return the summary text."""
    out.mkdir(parents=True, exist_ok=True)
    m = MotorArray(MOTOR, n=1, seed=0, load_inertia=30e-6, viscous_friction=2e-6)
    cfg = m.motor_configs[0]
    lines = [f"jvl_gym demo: {m!r}, load inertia 30e-6 kg·m² "
             f"(KVOUT ideal {(cfg.rotor_inertia + 30e-6) / cfg.rotor_inertia:.2f})"]
    log: dict[str, list] = {k: [] for k in ("t", "rpm", "profile_rpm", "p_ist", "vf_out", "i_a",
                                            "i_abs", "phase")}

    # TESTU: coil step response (manual 4.4.9)
    m.write("UMEAS", 60)
    m.write("MODE_REG", c.TESTU_MODE)
    _trace(m, 3, log, "TESTU")
    buf = m.sample_buffer()
    ic = buf["IC_IST"][0]
    lines.append(f"TESTU  UMEAS=60: IC_IST = {ic.astype(int).tolist()}")

    # TESTA: torque ramp, then BREAK and INIT (4.4.10)
    m.write("T_SOLL", 150)
    m.set_record_length(30)
    m.write("MODE_REG", c.TESTA_MODE)
    _trace(m, 200, log, "TESTA")
    v = m.sample_buffer()["V_IST"][0]
    slope = np.polyfit(np.arange(5, v.size), v[5:], 1)[0]
    acc = slope * 2 * math.pi / c.COUNTS_PER_REV / c.OUTER_DT**2
    torque = 150 / 1023 * cfg.peak_torque
    lines.append(f"TESTA  T_SOLL=150: V_IST slope {slope:.3f} counts/sample² → J ≈ "
                 f"{torque / acc:.3e} kg·m² (true {cfg.rotor_inertia + 30e-6:.3e}); "
                 f"mode now {m.mode_name()}")

    # Position move (P_MODE, 4.4.3)
    m.write("KVOUT", round((cfg.rotor_inertia + 30e-6) / cfg.rotor_inertia, 2))
    m.write("T_SOLL", 1023)
    m.write("A_SOLL", 60)
    m.write("V_SOLL", 4000)
    m.write("P_SOLL", int(m.read("P_IST")[0]) + 50000)
    m.write("MODE_REG", c.P_MODE)
    _trace(m, 600, log, "P_MODE")
    err = int(m.read("P_SOLL")[0] - m.read("P_IST")[0])
    lines.append(f"P_MODE 50000-count move: final error {err} counts, IN_POS "
                 f"{bool(int(m.read('ERR_STAT')[0]) & c.IN_POS)}, "
                 f"FNCERR {int(m.read('FNCERR')[0])}")

    # Velocity profile (V_MODE, 4.4.2)
    m.write("A_SOLL", 20)
    m.write("MODE_REG", c.V_MODE)
    for v_soll in (3000, -2000, 0):
        m.write("V_SOLL", v_soll)
        _trace(m, 300, log, "V_MODE")
        lines.append(f"V_MODE V_SOLL={v_soll:5d} ({c.v_soll_to_rpm(v_soll):7.1f} rpm): "
                     f"shaft {m.speed_rpm[0]:7.1f} rpm")
    m.write("MODE_REG", c.INIT_MODE)
    _trace(m, 100, log, "STOP/INIT")
    e = m.energy
    lines.append(f"energy: electrical {e['electrical'][0]:.3f} J, copper {e['copper'][0]:.3f} J, "
                 f"friction {e['friction'][0]:.3f} J, I2T {int(m.read('I2T')[0])}")

    _plot(log, out / "scope.png")
    summary = "\n".join(lines)
    (out / "summary.txt").write_text(summary + "\n")
    return summary


def _figure(log: dict[str, list]) -> Any:
    """The scope figure of a demo ``log``: speed, position, VF_OUT and the current magnitude
    over time, the phases (TESTU, TESTA, …) named on a top axis between dashed boundaries."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.asarray(log["t"])
    fig, ax = plt.subplots(4, 1, figsize=(10, 9), sharex=True)
    ax[0].plot(t, log["profile_rpm"], label="profile (FNC_OUT)", lw=1)
    ax[0].plot(t, log["rpm"], label="shaft", lw=1)
    ax[0].set_ylabel("speed [rpm]")
    ax[0].legend(loc="lower left", fontsize=8)
    ax[1].plot(t, log["p_ist"], lw=1)
    ax[1].set_ylabel("P_IST [counts]")
    ax[2].plot(t, log["vf_out"], lw=1)
    ax[2].set_ylabel("VF_OUT")
    ax[3].plot(t, log["i_abs"], lw=1)  # the phase currents alternate too fast to read here
    ax[3].set_ylabel("current |i| [A]")
    ax[3].set_xlabel("time [s]")
    phases = list(log["phase"])
    starts = [k for k in range(len(phases)) if k == 0 or phases[k] != phases[k - 1]]
    ends = [*starts[1:], len(phases)]
    for k in starts[1:]:
        for a in ax:
            a.axvline(t[k], color="grey", lw=0.5, ls="--")
    top = ax[0].secondary_xaxis("top")
    top.set_xticks([0.5 * (t[a] + t[b - 1]) for a, b in zip(starts, ends)],
                   [phases[a] for a in starts], fontsize=8)
    top.tick_params(length=0)
    fig.suptitle("jvl_gym demo: MAC140 scope")
    fig.tight_layout()
    return fig


def _plot(log: dict[str, list], path: Path) -> None:
    import matplotlib.pyplot as plt

    fig = _figure(log)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    """``python -m jvl_gym.cli.demo [--out DIR]`` (``argv`` default: the command line)."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", default="demo_out", type=writable_dir_arg,
                        help="output directory (made if missing; checked writable first)")
    args = parser.parse_args(argv)
    print(run_demo(args.out))
    print(f"wrote {args.out / 'scope.png'} and {args.out / 'summary.txt'}")


if __name__ == "__main__":
    main()

# ruff: noqa: B008  (typer declares options as argument defaults)
"""``jvl-tune``: identify, synthesize, verify, autotune (and regenerate the default setups).

Every command works against the simulator (``jvl_gym.MotorArray``) or on record CSV files;
``autotune --port`` runs the same procedure on a motor behind a serial port or a pyserial URL
(a real MAC motor, or the digital twin ``jvl-gym serve``) through the MacTalk client.

Examples
--------
``jvl-tune autotune --motor MAC140 --load-inertia 5e-5 --out DIR``
``jvl-tune autotune --motor MAC800 --load-inertia 6e-4 --out DIR``  (the MAC800 family,
:mod:`tuning.autotune_sixth_order`; the family comes from the motor type, :mod:`tuning.family`)
``jvl-tune autotune --motor MAC140 --port socket://127.0.0.1:5000 --address 19 --write``
``jvl-tune identify --motor MAC140 --testu u.csv --testa a1.csv --testa a2.csv``
``jvl-tune synthesize --motor MAC140 --inertia 6.7e-5 --out setup.yaml``
``jvl-tune verify --setup setup.yaml --inertia 6.7e-5``  (the motor named in setup.yaml)
``jvl-tune defaults``
``jvl-tune fleet configs/fleets/example.yml --out DIR``  (Ray: the ``scale`` extra)

Errors are one line on stderr with a non-zero exit status; ``--debug`` shows the traceback
(:class:`jvl_gym.cli_app.App`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import typer
import yaml

from jvl_gym.cli_app import App

from .acceptance import autotune_designs
from .autotune import (
    RECOMMENDED_COIL_SAMPLES,
    RECOMMENDED_MECH_SAMPLES,
    identify_motors,
    synthesize,
    verify_design,
)
from .identify_coil import identify_coil
from .identify_mechanics import coil_uncertainty, identify_mechanics
from .models import MotorData
from .records import load_csv, record_registers
from .report import text_table, write_report
from .verify import verify_current_loop, verify_speed_loop

app = App(prog="jvl-tune",
          help="JVL MAC50-141 and MAC800 tuning toolkit (identification, synthesis, verification)",
          no_args_is_help=True)


def _say(msg: str) -> None:
    typer.echo(f"[jvl-tune] {msg}", err=True)


def _finite(value: float | None) -> float | None:
    """Option callback: a finite number (or not given)."""
    if value is not None and not math.isfinite(value):
        raise typer.BadParameter(f"must be a finite number, got {value}")
    return value


def _nonnegative(value: float | None) -> float | None:
    """Option callback: a finite number >= 0 (or not given)."""
    if _finite(value) is not None and value < 0:
        raise typer.BadParameter(f"must be >= 0, got {value}")
    return value


def _writable_dir(value: Path) -> Path:
    """Option callback: a directory that exists and is writable, or that can be created in a
    writable directory (checked before any work starts; nothing is created here)."""
    import tempfile

    probe = value.absolute()
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    if probe == value.absolute() and not probe.is_dir():
        raise typer.BadParameter(f"{value} exists and is not a directory; give a directory")
    try:
        if not probe.is_dir():
            raise OSError(f"{probe} is not a directory")
        tempfile.TemporaryFile(dir=probe).close()  # what the run would do: make a file there
    except OSError as exc:
        raise typer.BadParameter(f"{value} cannot be written ({exc.strerror or exc} in "
                                 f"{probe}); give a writable directory") from None
    return value


def _positive(value: float | None) -> float | None:
    """Option callback: a finite number > 0 (or not given)."""
    if _finite(value) is not None and value <= 0:
        raise typer.BadParameter(f"must be > 0, got {value}")
    return value


def _write_setup(path: Path, motor: str, regs: dict[str, float], note: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    clean = {k: (float(v) if isinstance(v, (float, np.floating)) else v) for k, v in regs.items()}
    text = "".join(f"# {ln}\n" for ln in note.splitlines())
    text += yaml.safe_dump({"motor": motor, "provenance": "jvl-tune", "registers": clean},
                           sort_keys=False)
    path.write_text(text)


@app.command()
def identify(motor: str = typer.Option(..., help="motor type, e.g. MAC140"),
             testu: list[Path] = typer.Option([], help="TESTU record CSV (repeatable)"),
             testa: list[Path] = typer.Option([], help="TESTA record CSV (repeatable)"),
             no_coulomb: bool = typer.Option(False, help="assume no Coulomb friction"),
             setup: Path = typer.Option(None, help="setup YAML with the current-loop registers "
                                        "(KIFX2..KIB0, PHASE_COMP, AMPLITUDE) the TESTA records "
                                        "were taken with, for CSVs without a '# registers:' "
                                        "line"),
             accept: bool = typer.Option(False, help="exit 0 even when an estimate is not "
                                         "credible (tuning.credibility)")) -> None:
    """Identify the coil (TESTU) and the mechanics (TESTA) from record CSV files.

    TESTA uses the electrical model (current loop, back-EMF) when the records carry the
    registers they were taken with (``# registers:``, written by ``acquire_testa``) or
    ``--setup`` gives them; otherwise the rigid model (docs/tuning.md).

    Estimates that are not credible (``tuning.credibility``: outside physical bounds or the
    register format, an interval including zero, a poor fit) are listed on stderr and the exit
    status is 1 unless ``--accept``.
    """
    from .credibility import friction_text, problems

    if _family_key(motor) == "mac800":
        raise typer.BadParameter("the MAC800 family has no TESTU/TESTA records; `jvl-tune "
                                 "autotune --motor MAC800` records torque steps with the sample "
                                 "buffer", param_hint="'--motor'")
    if not testu and not testa:
        raise typer.BadParameter("give --testu and/or --testa record files",
                                 param_hint="'--testu' / '--testa'")
    md = MotorData.from_config(motor)
    bad: list[str] = []
    if testu:
        c = identify_coil([load_csv(p) for p in testu], md)
        typer.echo(f"R_line {c.R_line:.5g} ohm {c.ci['R_line']}, L_line {c.L_line:.5g} H "
                   f"{c.ci['L_line']}, delay {c.delay}, fit {c.nrmse_fit:.2f} %")
        bad += problems(md, coil=c)
        md = c.motor(md)
    if testa:
        recs = [load_csv(p) for p in testa]
        cur = pc = None
        if setup is not None:
            from jvl_gym.families.mac050_141.config import load_setup

            regs = load_setup(setup).registers
            keys = ("KIFX2", "KIFX1", "KIFY1", "KIFY0", "KIB1", "KIB0")
            missing = [k for k in keys if k not in regs]
            if missing:
                raise typer.BadParameter(f"{setup} lacks {', '.join(missing)}", param_hint="setup")
            cur = {k: float(regs[k]) for k in keys}
            pc = float(regs.get("PHASE_COMP", 5.0))
            md = md.with_(amplitude=float(regs.get("AMPLITUDE", md.amplitude)))
        m = identify_mechanics(recs, md, coulomb=not no_coulomb, current_regs=cur,
                               phase_comp=pc, coil_sd=coil_uncertainty(c) if testu else None)
        carried = record_registers(recs) or {}
        model = "electrical" if cur is not None or "KIFX2" in carried else "rigid"
        b_txt = friction_text("b", m.viscous, "N m s/rad", m.detected.get("viscous"),
                              m.raw.get("viscous"))
        tc_txt = friction_text("Tc", m.coulomb, "N m", m.detected.get("coulomb"),
                               m.raw.get("coulomb"))
        typer.echo(f"J {m.J!r} kg m^2 {m.ci['J']}, KVOUT {m.kvout:.3f}, {b_txt}, {tc_txt}, "
                   f"fit {m.nrmse_fit:.2f} % "
                   f"({model} model)")
        bad += problems(md, mech=m)
    if bad:
        what = "accepted (--accept)" if accept else "give consistent records, or --accept"
        _say(f"NOT CREDIBLE: {'; '.join(bad)}: {what}")
        if not accept:
            raise typer.Exit(1)


@app.command("synthesize")
def synthesize_cmd(motor: str = typer.Option(...), inertia: float = typer.Option(
        ..., help="total inertia J [kg m^2]", callback=_positive),
        resistance: float = typer.Option(None, help="phase R [ohm] (default: motor config)",
                                         callback=_positive),
        inductance: float = typer.Option(None, help="phase L [H] (default: motor config)",
                                         callback=_positive),
        current_bw: float = typer.Option(None, help="current-loop bandwidth [Hz]",
                                         callback=_positive),
        speed_bw: float = typer.Option(None, help="speed-loop bandwidth [Hz]",
                                       callback=_positive),
        structure: str = typer.Option("ip", help="ip or pi"),
        coulomb: float = typer.Option(0.0, help="identified Coulomb friction [N m] (pi: adds a "
                                      "position integral when its dead band exceeds 5 counts)",
                                      callback=_nonnegative),
        out: Path = typer.Option(Path("setup.yaml"))) -> None:
    """Design and quantise all filters for given motor data; write a setup YAML."""
    if _family_key(motor) == "mac800":
        given = {"--current-bw": current_bw is not None, "--speed-bw": speed_bw is not None,
                 "--structure": structure != "ip", "--coulomb": coulomb > 0}
        bad = [k for k, v in given.items() if v]
        if bad:
            raise typer.BadParameter(f"not available for the MAC800 family: {', '.join(bad)}",
                                     param_hint="'--motor'")
        _synthesize_sixth_order(motor, inertia, resistance, inductance, out)
        return
    md = MotorData.from_config(motor)
    if resistance:
        md = md.with_(R_phase=resistance)
    if inductance:
        md = md.with_(L_phase=inductance)
    d = synthesize(md, inertia, coulomb, current_bw, speed_bw, structure)
    _write_setup(out, motor, d.registers, "jvl-tune synthesize")
    typer.echo(text_table(None, d))
    bad = verify_design(d)
    if bad:
        typer.echo("FAILED: " + "; ".join(bad))
        raise typer.Exit(1)


def _setup_registers(motor: str | None, setup: Path) -> tuple[str, dict[str, float]]:
    """The motor type and the complete register set a motor runs with after ``setup`` is
    written to it: the setup validated as the simulator validates it (names, ranges,
    read-only registers, write rules), registers it does not give from the motor type's
    defaults (ROM and the family's ``configs/setups``), as a motor keeps them.

    Raises
    ------
    typer.BadParameter
        No motor named (``--motor`` nor the setup's ``motor:``) or the two disagree.
    """
    from jvl_gym import MotorArray
    from jvl_gym.families.mac050_141.config import canonical_motor_name, load_motor, load_setup

    cfg = load_setup(setup)
    named = cfg.motor
    if motor is None and named is None:
        raise typer.BadParameter(f"{setup} names no motor (no 'motor:' key): give --motor",
                                 param_hint="'--motor'")
    if motor is not None and named is not None and (
            canonical_motor_name(motor) != canonical_motor_name(named)):
        raise typer.BadParameter(f"{setup} is a setup for {named}, not {motor}",
                                 param_hint="'--motor'")
    name = load_motor(motor if motor is not None else named).name
    m = MotorArray(name, n=1)  # the motor type's defaults
    defaults = {reg.name: float(m.read(reg.name)[0]) for reg in m.table
                if reg.access.value == "rw" and reg.format.value != "LongIntHigh"}
    MotorArray(name, n=1, setup=setup)  # validates the setup, naming it in the error
    missing = sorted(set(defaults) - set(cfg.registers))
    regs = {**defaults, **{k: float(v) for k, v in cfg.registers.items()}}
    loop = ("KIFX2", "KIFX1", "KIFY1", "KIFY0", "KIB1", "KIB0", "KVFX4", "KVFX3", "KVFX2",
            "KVFX1", "KVFY3", "KVFY2", "KVFY1", "KVFY0", "KVOUT")
    from_defaults = [k for k in loop if k in missing]
    if from_defaults:
        _say(f"{setup} lacks {', '.join(from_defaults)}: verified with the {name} defaults "
             "(what the motor keeps when the setup is written)")
    return name, regs


@app.command()
def verify(motor: str = typer.Option(None, help="motor type (default: the setup's motor:)"),
           setup: Path = typer.Option(...),
           inertia: float = typer.Option(None, help="total inertia [kg m^2] (default KVOUT*J_m)",
                                         callback=_positive)
           ) -> None:
    """Margins, bandwidths, pole radii and robustness of a setup file's filters."""
    if _family_key(motor if motor is not None else _setup_motor(setup)) == "mac800":
        _verify_sixth_order(motor, setup, inertia)
        return
    motor, regs = _setup_registers(motor, setup)
    md = MotorData.from_config(motor)
    J = inertia if inertia else regs.get("KVOUT", 1.0) * md.J_m
    cr = verify_current_loop(md, regs)
    sr = verify_speed_loop(md, regs, J)
    for name, rep in (("current", cr), ("speed", sr)):
        n = rep.nominal
        typer.echo(f"{name}: PM {n.pm_deg:.1f} deg, GM {n.gm_db:.1f} dB, BW "
                   f"{n.bandwidth_hz:.1f} Hz, |z|max {n.pole_radius:.4f}, worst robust PM "
                   f"{rep.worst_robust_pm:.1f} deg, all stable {rep.all_stable}")
    if not (cr.all_stable and sr.all_stable):
        raise typer.Exit(1)


@app.command()
def autotune(motor: str = typer.Option("MAC140"),
             load_inertia: float = typer.Option(0.0, help="simulated load inertia [kg m^2]",
                                                callback=_nonnegative),
             viscous: float = typer.Option(0.0, help="simulated viscous friction [N m s/rad]",
                                           callback=_nonnegative),
             coulomb: float = typer.Option(0.0, help="simulated Coulomb friction [N m]",
                                           callback=_nonnegative),
             coupling_stiffness: float = typer.Option(
                 0.0, help="simulated: the load behind an elastic coupling of this stiffness "
                 "[N m/rad] (0: rigid)", callback=_nonnegative),
             coupling_damping: float = typer.Option(
                 0.0, help="simulated: the coupling's damping [N m s/rad]",
                 callback=_nonnegative),
             resonance: bool = typer.Option(False, help="identify a two-mass resonance and "
                                            "offer a notch/low-pass design (tuning."
                                            "resonance_design)"),
             noise: bool = typer.Option(True, help="1 % measurement noise in the simulator"),
             seed: int = typer.Option(0),
             n_coil: int = typer.Option(None, help="TESTU samples per record (default: "
                                        f"{RECOMMENDED_COIL_SAMPLES}; with --port the "
                                        "firmware's 11, several records combined)"),
             n_mech: int = typer.Option(None, help="TESTA samples per record (default: "
                                        f"{RECOMMENDED_MECH_SAMPLES}; with --port 11)"),
             structure: str = typer.Option("pi", help="speed loop structure: pi or ip"),
             out: Path = typer.Option(Path("autotune_out"), callback=_writable_dir,
                                      help="output directory of setup.yaml, the report and "
                                      "the plots (also with --port)"),
             port: str = typer.Option(None, help="serial device or pyserial URL of a real motor "
                                      "or of `jvl-gym serve` (default: the simulator)"),
             address: int = typer.Option(1, help="MacTalk unit address (MYADDR) with --port"),
             time_scale: float = typer.Option(1.0, help="with --port: the twin's --speed",
                                              callback=_positive),
             write: bool = typer.Option(False, help="with --port: write the design to the motor"),
             accept: bool = typer.Option(False, help="exit 0 even when an identified value is "
                                         "not credible (tuning.credibility)"),
             notch_hz: float = typer.Option(None, help="MAC800 family: a known resonance [Hz] "
                                            "the sixth-order filter's extra orders notch",
                                            callback=_positive)
             ) -> None:
    """Identify, synthesise, verify (simulator or --port); write OUT/setup.yaml and a report.

    Identified values that are not credible (``tuning.credibility``) are listed on stderr and
    the exit status is 1 unless ``--accept``.
    """
    from jvl_gym import MotorArray

    if _family_key(motor) == "mac800":
        given = {"--port": port is not None, "--resonance": resonance,
                 "--coupling-stiffness": coupling_stiffness > 0,
                 "--coupling-damping": coupling_damping > 0, "--n-coil": n_coil is not None,
                 "--n-mech": n_mech is not None, "--structure": structure != "pi"}
        bad = [k for k, v in given.items() if v]
        if bad:
            raise typer.BadParameter(f"not available for the MAC800 family: {', '.join(bad)}",
                                     param_hint="'--motor'")
        _autotune_sixth_order(motor, load_inertia, viscous, coulomb, noise, seed, out, notch_hz)
        return
    if notch_hz is not None:
        raise typer.BadParameter("--notch-hz is for the MAC800 family; the MAC050-141 use "
                                 "--resonance", param_hint="'--notch-hz'")

    if port is not None:
        from jvl_gym.families.mac050_141.constants import TEST_RECORD_SAMPLES

        from .serial_source import autotune_over_serial

        sections: list[tuple[str, Path]] = []
        step = ((lambda sm, i, dd: sections.append(_two_mass_step(sm, i, dd, out)))
                if resonance else None)
        ident, d = autotune_over_serial(port, motor, address, time_scale,
                                        n_coil or TEST_RECORD_SAMPLES,
                                        n_mech or TEST_RECORD_SAMPLES, structure, write,
                                        progress=_say, two_mass=step)
        setup = out / "setup.yaml"
        _write_setup(setup, motor, d.registers,
                     f"jvl-tune autotune --port {port}: identified J = {ident.mechanics.J:.4g}")
        files = write_report(out, ident, d, ident.motor, ident.mechanics.J)
        for text, _path in sections:
            with files[0].open("a") as fh:
                fh.write("\n" + text)
        typer.echo(files[0].read_text())
        bad = verify_design(d)
        typer.echo(f"wrote {setup}" + (" and the motor's registers" if write and not bad else ""))
        if bad:
            typer.echo("FAILED: " + "; ".join(bad))
            raise typer.Exit(1)
        _check_credible(ident, accept)
        return

    from .verify import velocity_step

    params = {"load_inertia": load_inertia, "viscous_friction": viscous,
              "coulomb_friction": coulomb, "coupling_stiffness": coupling_stiffness,
              "coupling_damping": coupling_damping}
    if noise:
        params.update(current_noise=2.0, position_noise=0.85)
    m = MotorArray(motor, n=1, seed=seed, **params)
    ident = identify_motors(m, n_coil or RECOMMENDED_COIL_SAMPLES,
                            n_mech or RECOMMENDED_MECH_SAMPLES, progress=_say)[0]
    _say("synthesis, verification and the acceptance step (candidates simulated on the "
         "identified motor)")
    d = autotune_designs([ident], structure)[0].chosen.design
    two_mass = _two_mass_step(m, ident, d, out) if resonance else None
    setup = out / "setup.yaml"
    _write_setup(setup, motor, d.registers,
                 f"jvl-tune autotune: {motor}, identified J = {ident.mechanics.J:.4g} kg m^2")
    _say("time simulation on the MotorArray")
    sim = MotorArray(motor, n=1, seed=seed, **params)
    sim.load_setup(setup)
    v = velocity_step(sim, 800)
    truth = {"J": m.motor_configs[0].rotor_inertia + load_inertia,
             "kvout": 1 + load_inertia / m.motor_configs[0].rotor_inertia,
             "viscous": viscous, "coulomb": coulomb,
             "R_line": 2 * m.motor_configs[0].phase_resistance,
             "L_line_mH": 2e3 * m.motor_configs[0].phase_inductance}
    files = write_report(out, ident, d, ident.motor, ident.mechanics.J, truth, v, 800)
    if two_mass is not None:
        with files[0].open("a") as fh:
            fh.write("\n" + two_mass[0])
        files.append(two_mass[1])
    typer.echo(files[0].read_text())
    bad = verify_design(d)
    typer.echo(f"wrote {setup} and {', '.join(str(f) for f in files)}")
    if bad:
        typer.echo("FAILED: " + "; ".join(bad))
        raise typer.Exit(1)
    if not math.isfinite(ident.mechanics.J):
        raise typer.Exit(1)
    _check_credible(ident, accept)


def _family_key(motor: str | None) -> str | None:
    """The tuning family of a motor type (:func:`tuning.family.tuning_family`), None if no
    motor is named."""
    from .family import tuning_family

    if motor is None:
        return None
    try:
        return tuning_family(motor).key
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="'--motor'") from exc


def _setup_motor(setup: Path) -> str | None:
    """The ``motor:`` of a setup file (None when it has none or cannot be read: the family's
    loader then says what is wrong)."""
    try:
        data = yaml.safe_load(setup.read_text())
    except (OSError, yaml.YAMLError):
        return None
    name = data.get("motor") if isinstance(data, dict) else None
    return name if isinstance(name, str) else None


def _autotune_sixth_order(motor: str, load_inertia: float, viscous: float, coulomb: float,
                          noise: bool, seed: int, out: Path, notch_hz: float | None) -> None:
    """``autotune`` of a MAC800-family motor on the simulator
    (:mod:`tuning.autotune_sixth_order`): OUT/setup.yaml (the family's setup format) and
    OUT/report.txt."""
    from jvl_gym import MotorArray

    from .autotune_sixth_order import autotune_report, autotune_sixth_order, write_setup

    params = {"load_inertia": load_inertia, "viscous_friction": viscous,
              "coulomb_friction": coulomb}
    if noise:
        params["position_noise"] = 0.85
    m = MotorArray(motor, n=1, seed=seed, **params)
    res = autotune_sixth_order(m, notch_hz=notch_hz, seed=seed, progress=_say)[0]
    setup = write_setup(out / "setup.yaml", res)
    MotorArray(motor, n=1, setup=setup)  # the family loads it
    j_true = m.motor_configs[0].rotor_inertia + load_inertia
    text = autotune_report(res) + (f"Simulated truth: J {j_true:.5g} kg m^2 (identified "
                                   f"{100 * (res.ident.mechanics.J / j_true - 1):+.2f} %), "
                                   f"Tc {coulomb:g} N m, b {viscous:g} N m s/rad\n")
    (out / "report.txt").write_text(text)
    typer.echo(text)
    typer.echo(f"wrote {setup} and {out / 'report.txt'}")
    design = res.chosen.design
    if design is not None:
        from .design_sixth_order import check_sixth_order

        bad = check_sixth_order(design.verification)
        if bad:
            typer.echo("FAILED: " + "; ".join(bad))
            raise typer.Exit(1)


def _synthesize_sixth_order(motor: str, inertia: float, resistance: float | None,
                            inductance: float | None, out: Path) -> None:
    """``synthesize`` for a MAC800-family motor: the sixth-order design with the low-pass
    (:func:`tuning.design_sixth_order.synthesize_sixth_order`) written in the family's setup
    format."""
    from .autotune_sixth_order import setup_text
    from .design_sixth_order import check_sixth_order, synthesize_sixth_order

    md = MotorData.from_config(motor)
    if resistance:
        md = md.with_(R_phase=resistance)
    if inductance:
        md = md.with_(L_phase=inductance)
    d = synthesize_sixth_order(md, inertia)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(setup_text(md.name, d.registers, f"jvl-tune synthesize: {d.name}"))
    v = d.verification
    typer.echo(f"{d.name}: speed PM {v.speed.pm_deg:.1f} deg, GM {v.speed.gm_db:.1f} dB, "
               f"crossover {v.speed.crossover_hz:.1f} Hz, |z|max {v.speed.pole_radius:.4f}, "
               f"worst robust PM {v.worst_robust_pm:.1f} deg; current PM "
               f"{v.current.pm_deg:.1f} deg, GM {v.current.gm_db:.1f} dB")
    bad = check_sixth_order(v)
    if bad:
        typer.echo("FAILED: " + "; ".join(bad))
        raise typer.Exit(1)


def _verify_sixth_order(motor: str | None, setup: Path, inertia: float | None) -> None:
    """``verify`` of a MAC800-family setup: validated by the family's loader, then the loops'
    margins (:func:`tuning.autotune_sixth_order.verify_setup`)."""
    from jvl_gym import MotorArray

    from .autotune_sixth_order import verify_setup

    named = _setup_motor(setup)
    if motor is not None and named is not None and motor != named:
        raise typer.BadParameter(f"{setup} is a setup for {named}, not {motor}",
                                 param_hint="'--motor'")
    name = motor if motor is not None else named
    MotorArray(name, n=1, setup=setup)  # validates the setup, naming it in the error
    regs = yaml.safe_load(setup.read_text()).get("registers") or {}
    v, bad = verify_setup(name, {k: float(x) for k, x in regs.items()}, inertia)
    for label, n, worst in (("current", v.current, math.inf), ("speed", v.speed,
                                                               v.worst_robust_pm)):
        typer.echo(f"{label}: PM {n.pm_deg:.1f} deg, GM {n.gm_db:.1f} dB, BW "
                   f"{n.bandwidth_hz:.1f} Hz, |z|max {n.pole_radius:.4f}"
                   + (f", worst robust PM {worst:.1f} deg" if math.isfinite(worst) else "")
                   + f", all stable {v.all_stable}")
    if bad:
        typer.echo("checks: " + "; ".join(bad))
    if not v.all_stable:
        raise typer.Exit(1)


def _two_mass_step(m: object, ident: object, d: object, out: Path) -> tuple[str, Path]:
    """The two-mass step of ``autotune --resonance``: the resonance from AT_MODE step records
    on ``m``, the notch/low-pass candidates of the plain PI, the choice by simulation on the
    identified two-mass motor (``d.registers`` becomes the kept candidate's), and the Bode
    plot ``out/bode_two_mass.png``. Returns the report's section and the plot's path."""
    import matplotlib.pyplot as plt

    from .acceptance import move_acceleration, simulation_parameters
    from .autotune import synthesize
    from .identify_resonance import identify_resonance
    from .report import two_mass_bode_figure
    from .resonance_design import choose, coupling_of, resonance_designs

    _say("two-mass load: AT_MODE torque steps recorded at 7812.5 Hz, the resonance, the "
         "notch/low-pass candidates and their simulation")
    est = identify_resonance(m, [ident])[0]
    md, mech = ident.motor, ident.mechanics  # type: ignore[attr-defined]
    lines = ["Two-mass load (tuning.identify_resonance, tuning.resonance_design)",
             f"  resonance {est.f_res:.1f} Hz (95 % {est.ci['f_res'][0]:.1f} .. "
             f"{est.ci['f_res'][1]:.1f}), anti-resonance {est.f_anti:.1f} Hz, load ratio "
             f"J_l/J_m {est.load_ratio:.2f}, damping ratio {est.zeta:.3f}, "
             f"detected {est.detected}",
             f"  as recorded under the current loop: {est.f_seen:.1f} Hz, damping ratio "
             f"{est.zeta_seen:.3f}"]
    out.mkdir(parents=True, exist_ok=True)
    path = out / "bode_two_mass.png"
    if not est.detected or est.load_ratio <= 0.0:
        lines.append("  no resonance detected: the rigid design is kept")
        return "\n".join(lines) + "\n", path
    plain = synthesize(md, mech.J, mech.coulomb, structure="pi", position_integral=False)
    cands = resonance_designs(md, plain.registers, est.f_res, est.load_ratio, est.zeta,
                              max(mech.viscous, 0.0), est.ci)
    coupling = coupling_of(md.J_m, est.load_ratio, est.f_res, est.zeta)
    params = simulation_parameters(ident)  # type: ignore[arg-type]
    params.update(rotor_inertia=md.J_m, load_inertia=coupling[0],
                  coupling_stiffness=coupling[1], coupling_damping=coupling[2])
    ch = choose(md.name, params, plain.registers, cands, move_acceleration(ident))
    lines.append("  " + ch.reason)
    for name, t in ch.settle_s.items():
        when = f"{1e3 * t:.0f} ms" if math.isfinite(t) else "never"
        lines.append(f"    {name}: settles {when}, oscillation {ch.oscillation[name]:.0f} "
                     "counts p-p")
    loops = [("plain design", plain.registers)]
    if ch.chosen is not None:
        d.registers = ch.chosen.registers  # type: ignore[attr-defined]
        d.notes.append(ch.reason)  # type: ignore[attr-defined]
        loops.append((ch.chosen.name, ch.chosen.registers))
    fig = two_mass_bode_figure(md, loops, coupling, est.f_res, est.f_anti)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return "\n".join(lines) + "\n", path


def _check_credible(ident: object, accept: bool) -> None:
    """Say on stderr what is not credible in an identification; exit 1 unless ``accept``."""
    from .credibility import problems

    bad = problems(ident.motor, mech=ident.mechanics, coil=ident.coil)  # type: ignore[attr-defined]
    if bad:
        what = "accepted (--accept)" if accept else "check the records, or --accept"
        _say(f"NOT CREDIBLE: {'; '.join(bad)}: {what}")
        if not accept:
            raise typer.Exit(1)


@app.command()
def fleet(spec: Path = typer.Argument(..., help="fleet file (configs/fleets/*.yml) or a folder "
                                      "with one subfolder of record CSVs per motor"),
          out: Path = typer.Option(Path("fleet_out"), help="output directory",
                                   callback=_writable_dir),
          address: str = typer.Option(None, help="Ray cluster: auto, HOST:PORT or "
                                      "ray://HOST:10001 (default: local Ray)"),
          num_cpus: int = typer.Option(None, help="CPUs of the local Ray"),
          save_records: bool = typer.Option(False, help="also write each motor's records"),
          structure: str = typer.Option(None, help="speed loop structure pi or ip (overrides "
                                        "the file)"),
          verbose: bool = typer.Option(False, help="forward the Ray workers' logs")
          ) -> None:
    """Autotune a fleet of motors as Ray tasks; per-motor register sets and a fleet report."""
    from jvl_gym.scale.commands import fleet_command

    fleet_command(spec, out, address, num_cpus, save_records, structure, verbose)


@app.command()
def defaults(out: Path = typer.Option(
        None, help="directory (default: the family's configs/setups)")) -> None:
    """Regenerate the default setups (the family's configs/setups/<TYPE>.yaml) from the motor
    configs."""
    from .defaults import write_default_setups

    for p in write_default_setups(out):
        typer.echo(f"wrote {p}")


if __name__ == "__main__":
    app()

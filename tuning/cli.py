# ruff: noqa: B008  (typer declares options as argument defaults)
"""``jvl-tune``: identify, synthesize, verify, autotune (and regenerate the default setups).

Every command works against the simulator (``jvl_gym.MotorArray``) or on record CSV files;
``autotune --port`` runs the same procedure on a motor behind a serial port or a pyserial URL
(a real MAC motor, or the digital twin ``jvl-gym serve``) through the MacTalk client.

Examples
--------
``jvl-tune autotune --motor MAC140 --load-inertia 5e-5 --out DIR``
``jvl-tune autotune --motor MAC800 --load-inertia 6e-4 --out DIR``  (every command takes the
family's tuning strategy from the motor type, :func:`tuning.strategy.strategy_of`)
``jvl-tune autotune --motor MAC140 --port socket://127.0.0.1:5000 --address 19 --write``
``jvl-tune identify --motor MAC140 --testu u.csv --testa a1.csv --testa a2.csv``
``jvl-tune synthesize --motor MAC140 --inertia 6.7e-5 --out setup.yaml``
``jvl-tune verify --setup setup.yaml --inertia 6.7e-5``  (the motor named in setup.yaml)
``jvl-tune defaults``
``jvl-tune fleet configs/fleets/example.yml --out DIR``  (Ray: the ``scale`` extra)

Errors are one line on stderr with a non-zero exit status; ``--debug`` shows the traceback
(:class:`jvl_gym.cli.app.App`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from jvl_gym.cli.app import App, one_line, writable_dir, writable_file

from .record_lengths import RECOMMENDED_COIL_SAMPLES, RECOMMENDED_MECH_SAMPLES

if TYPE_CHECKING:  # pragma: no cover
    from .pipeline import Result
    from .strategy import Strategy

# The modules of the commands (numerics, the simulator, plotting) are imported by the command
# that needs them, so that ``--help`` and a usage error answer at once.

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


def _samples(value: int | None) -> int | None:
    """Option callback: a record length, 1 or more samples (or not given: the default)."""
    if value is not None and value < 1:
        raise typer.BadParameter(f"a record holds 1 or more samples, got {value}; leave the "
                                 "option out for the default")
    return value


def _positive(value: float | None) -> float | None:
    """Option callback: a finite number > 0 (or not given)."""
    if _finite(value) is not None and value <= 0:
        raise typer.BadParameter(f"must be > 0, got {value}")
    return value


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
    from jvl_gym.families import Capability

    from .credibility import friction_text, problems
    from .identify_coil import identify_coil
    from .identify_mechanics import coil_uncertainty, identify_mechanics
    from .models import MotorData
    from .records import load_csv, record_registers

    fam = _strategy(motor).family
    if not fam.supports(Capability.TEST_MODES):
        raise typer.BadParameter(f"no TESTU/TESTA records on the {fam.title}; `jvl-tune "
                                 f"autotune --motor {motor}` identifies them on the motor",
                                 param_hint="'--motor'")
    if not testu and not testa:
        raise typer.BadParameter("give --testu and/or --testa record files",
                                 param_hint="'--testu' / '--testa'")
    md = MotorData.from_config(motor)
    bad: list[str] = []
    if testu:
        c = identify_coil([load_csv(p, motor) for p in testu], md)
        typer.echo(f"R_line {c.R_line:.5g} ohm {c.ci['R_line']}, L_line {c.L_line:.5g} H "
                   f"{c.ci['L_line']}, delay {c.delay}, fit {c.nrmse_fit:.2f} %")
        bad += problems(md, coil=c)
        md = c.motor(md)
    if testa:
        recs = [load_csv(p, motor) for p in testa]
        cur = pc = None
        if setup is not None:
            from jvl_gym.families.config import load_setup

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
        out: Path = typer.Option(Path("setup.yaml"), callback=writable_file)) -> None:
    """Design and quantise all filters for given motor data; write a setup YAML."""
    from .pipeline import write_setup
    from .report import design_table

    strategy = _strategy(motor)
    _refuse(strategy, {"structure": structure != "ip", "current_bw": current_bw is not None,
                       "speed_bw": speed_bw is not None, "coulomb": coulomb > 0})
    cand, md = strategy.synthesize(motor, inertia, {
        "structure": structure, "current_bw": current_bw, "speed_bw": speed_bw,
        "coulomb": coulomb, "resistance": resistance, "inductance": inductance})
    write_setup(out, md.name, cand.registers, f"jvl-tune synthesize: {cand.name}")
    typer.echo(f"design: {cand.name}")
    typer.echo("\n".join(design_table(strategy, cand, md, inertia)))
    bad = strategy.failures(cand)
    if bad:
        typer.echo("FAILED: " + "; ".join(bad))
        raise typer.Exit(1)


@app.command()
def verify(motor: str = typer.Option(None, help="motor type (default: the setup's motor:)"),
           setup: Path = typer.Option(...),
           inertia: float = typer.Option(None, help="total inertia [kg m^2] (default KVOUT*J_m)",
                                         callback=_positive)
           ) -> None:
    """Margins, bandwidths, pole radii and robustness of a setup file's filters."""
    from jvl_gym.families.config import ConfigError, load_setup

    try:  # the project's setup loader: the file, its YAML, its keys and values checked
        named = load_setup(setup).motor
    except ConfigError as exc:
        raise typer.BadParameter(one_line(exc), param_hint="'--setup'") from None
    strategy = _strategy(motor if motor is not None else named)
    notes, lines, stable = strategy.verify_setup(motor, setup, inertia)
    for note in notes:
        _say(note)
    for line in lines:
        typer.echo(line)
    if not stable:
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
             seed: int = typer.Option(0, help="noise seed of the simulated motor and of the "
                                      "acceptance step's simulation (another seed: another "
                                      "draw of the measurement noise)"),
             n_coil: int = typer.Option(None, help="TESTU samples per record (default: "
                                        f"{RECOMMENDED_COIL_SAMPLES}; with --port the "
                                        "firmware's 11, several records combined)",
                                        callback=_samples),
             n_mech: int = typer.Option(None, help="TESTA samples per record (default: "
                                        f"{RECOMMENDED_MECH_SAMPLES}; with --port 11)",
                                        callback=_samples),
             structure: str = typer.Option("pi", help="speed loop structure: pi or ip"),
             out: Path = typer.Option(Path("autotune_out"), callback=writable_dir,
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

    from .pipeline import autotune as run_autotune
    from .pipeline import write_setup
    from .report import write_report

    strategy = _strategy(motor)
    _refuse(strategy, {"port": port is not None, "resonance": resonance,
                       "coupling_stiffness": coupling_stiffness > 0,
                       "coupling_damping": coupling_damping > 0, "n_coil": n_coil is not None,
                       "n_mech": n_mech is not None, "structure": structure != "pi",
                       "notch_hz": notch_hz is not None})
    settings = {"structure": structure, "n_coil": n_coil, "n_mech": n_mech,
                "notch_hz": notch_hz, "coupling_stiffness": coupling_stiffness,
                "coupling_damping": coupling_damping}
    sections: list[tuple[str, Path]] = []
    if port is not None:
        from .serial_source import autotune_over_serial

        two_mass = ((lambda sm, res: sections.append(_two_mass_step(sm, res, out)))
                    if resonance else None)
        ident, res = autotune_over_serial(port, motor, address, time_scale,
                                          n_coil, n_mech, structure, write,
                                          progress=_say, two_mass=two_mass)
        truth, step, note = None, (None, None), f"jvl-tune autotune --port {port}: " \
            f"identified J = {ident.mechanics.J:.4g}"
    else:
        params = strategy.simulator(motor, load_inertia, viscous, coulomb, noise, settings)
        m = MotorArray(motor, n=1, seed=seed, **params)
        res = run_autotune(m, strategy, settings, seed=seed, progress=_say)[0]
        ident = res.ident
        if resonance:
            sections.append(_two_mass_step(m, res, out))
        note = strategy.setup_note(res)
        truth = strategy.truth(m, load_inertia, viscous, coulomb)
    setup = write_setup(out / "setup.yaml", ident.motor.name, res.chosen.registers, note)
    if port is None:
        _say("time simulation on the MotorArray")
        sim = MotorArray(motor, n=1, seed=seed, **params)
        sim.load_setup(setup)  # the family loads the setup written
        step = strategy.speed_step(sim)
    files = write_report(out, strategy, res, truth, *step)
    for text, path in sections:
        with files[0].open("a") as fh:
            fh.write("\n" + text)
        if path.is_file():
            files.append(path)
    typer.echo(files[0].read_text())
    bad = strategy.failures(res.chosen)
    if port is not None:
        typer.echo(f"wrote {setup}" + (" and the motor's registers" if write and not bad else ""))
    else:
        typer.echo(f"wrote {setup} and {', '.join(str(f) for f in files)}")
    if bad:
        typer.echo("FAILED: " + "; ".join(bad))
        raise typer.Exit(1)
    if not math.isfinite(ident.mechanics.J):
        raise typer.Exit(1)
    _check_credible(strategy, ident, accept)


def _strategy(motor: str | None) -> Strategy:
    """The tuning strategy of a motor type's family (:func:`tuning.strategy.strategy_of`)."""
    from jvl_gym.families.config import ConfigError

    from .strategy import strategy_of

    if motor is None:
        raise typer.BadParameter("no motor type: give --motor (or a setup with a motor: line)",
                                 param_hint="'--motor'")
    try:
        return strategy_of(motor)
    except ConfigError:
        raise  # an unknown motor type: the loader's error, one line unless --debug
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="'--motor'") from exc


def _refuse(strategy: Strategy, given: dict[str, bool]) -> None:
    """Refuse the options given (``given``: option name → whether it was given) that the
    strategy does not take (:attr:`tuning.strategy.Strategy.options`)."""
    bad = [f"--{k.replace('_', '-')}" for k, v in given.items()
           if v and k not in strategy.options]
    if bad:
        raise typer.BadParameter(f"not available for the {strategy.family.title}: "
                                 f"{', '.join(bad)}", param_hint="'--motor'")


def _two_mass_step(m: object, res: Result, out: Path) -> tuple[str, Path]:
    """The two-mass step of ``autotune --resonance``: the resonance from AT_MODE step records
    on ``m``, the notch/low-pass candidates of the plain PI, the choice by simulation on the
    identified two-mass motor (the kept candidate's registers become ``res.chosen``'s), and the
    Bode plot ``out/bode_two_mass.png``. Returns the report's section and the plot's path."""
    import matplotlib.pyplot as plt

    from .autotune import synthesize
    from .identify_resonance import identify_resonance
    from .report import two_mass_bode_figure
    from .resonance_design import choose, coupling_of, resonance_designs
    from .strategies.testu_pi import move_acceleration, simulation_parameters

    _say("two-mass load: AT_MODE torque steps recorded at 7812.5 Hz, the resonance, the "
         "notch/low-pass candidates and their simulation")
    ident = res.ident
    est = identify_resonance(m, [ident])[0]
    md, mech = ident.motor, ident.mechanics
    lines = ["Two-mass load (tuning.identify_resonance, tuning.resonance_design)",
             f"  resonance {est.f_res:.1f} Hz (95 % {est.ci['f_res'][0]:.1f} .. "
             f"{est.ci['f_res'][1]:.1f}), anti-resonance {est.f_anti:.1f} Hz, load ratio "
             f"J_l/J_m {est.load_ratio:.2f}, damping ratio {est.zeta:.3f}, "
             f"detected {est.detected}",
             f"  as recorded under the current loop: {est.f_seen:.1f} Hz, damping ratio "
             f"{est.zeta_seen:.3f}", *(f"  {note}" for note in est.notes)]
    out.mkdir(parents=True, exist_ok=True)
    path = out / "bode_two_mass.png"
    if not est.detected or est.load_ratio <= 0.0:
        lines.append("  no resonance detected: the rigid design is kept")
        return "\n".join(lines) + "\n", path
    plain = synthesize(md, mech.J, mech.coulomb, structure="pi", position_integral=False)
    cands = resonance_designs(md, plain.registers, est.f_res, est.load_ratio, est.zeta,
                              max(mech.viscous, 0.0), est.ci)
    coupling = coupling_of(md.J_m, est.load_ratio, est.f_res, est.zeta)
    params = simulation_parameters(ident)
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
        res.chosen.registers = ch.chosen.registers
        if res.chosen.design is not None:
            res.chosen.design.registers = ch.chosen.registers
            res.chosen.design.notes.append(ch.reason)
        loops.append((ch.chosen.name, ch.chosen.registers))
    fig = two_mass_bode_figure(md, loops, coupling, est.f_res, est.f_anti)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return "\n".join(lines) + "\n", path


def _check_credible(strategy: Strategy, ident: object, accept: bool) -> None:
    """Say on stderr what is not credible in an identification; exit 1 unless ``accept``."""
    bad = strategy.problems(ident)
    if bad:
        what = "accepted (--accept)" if accept else "check the records, or --accept"
        _say(f"NOT CREDIBLE: {'; '.join(bad)}: {what}")
        if not accept:
            raise typer.Exit(1)


@app.command()
def fleet(spec: Path = typer.Argument(..., help="fleet file (configs/fleets/*.yml) or a folder "
                                      "with one subfolder of record CSVs per motor"),
          out: Path = typer.Option(Path("fleet_out"), help="output directory",
                                   callback=writable_dir),
          address: str = typer.Option(None, help="Ray cluster: auto, HOST:PORT or "
                                      "ray://HOST:10001 (default: local Ray)"),
          num_cpus: int = typer.Option(None, help="CPUs of the local Ray"),
          save_records: bool = typer.Option(False, help="also write each motor's records"),
          structure: str = typer.Option(None, help="speed loop structure pi or ip (overrides "
                                        "the file)"),
          verbose: bool = typer.Option(False, help="forward the Ray workers' logs")
          ) -> None:
    """Autotune a fleet of motors as Ray tasks; per-motor register sets and a fleet report."""
    from .fleet import fleet_command

    fleet_command(spec, out, address, num_cpus, save_records, structure, verbose)


@app.command()
def defaults(out: Path = typer.Option(
        None, help="directory (default: the family's configs/setups)", callback=writable_dir),
             family_key: str = typer.Option(
        None, "--family", help="family key (default: every family with TESTU/TESTA test "
        "modes)")) -> None:
    """Regenerate the default setups (the family's configs/setups/<TYPE>.yaml) from the motor
    configs."""
    from jvl_gym.families import Capability, UnsupportedOperation, families_with, family

    from .defaults import write_default_setups

    try:
        fams = [family(family_key)] if family_key else list(families_with(Capability.TEST_MODES))
        for fam in fams:
            for p in write_default_setups(fam, out):
                typer.echo(f"wrote {p}")
    except (KeyError, UnsupportedOperation) as exc:
        raise typer.BadParameter(str(exc).strip("'\""), param_hint="'--family'") from None


if __name__ == "__main__":
    app()

"""A setup file as the motor runs it: validated as the simulator validates it, completed with
the motor type's defaults (``jvl-tune verify``)."""

from __future__ import annotations

from pathlib import Path

import typer

from jvl_gym.families.config import load_setup

from .family import tuned_family

__all__ = ["complete_setup"]


def complete_setup(motor: str | None, setup: Path, loop_keys: tuple[str, ...]
                   ) -> tuple[str, dict[str, float], list[str]]:
    """The motor type and the complete register set a motor runs with after ``setup`` is
    written to it: the setup validated as the simulator validates it (names, ranges,
    read-only registers, write rules), the registers it does not give from the motor type's
    defaults (ROM and the family's ``configs/setups``), as a motor keeps them.

    Parameters
    ----------
    motor : str or None
        The motor type asked for (None: the setup's ``motor:``).
    setup : Path
        The setup file.
    loop_keys : tuple of str
        The loop registers worth a note when they come from the defaults.

    Returns
    -------
    (str, dict, list of str)
        The motor type, register name → value, and the lines to print (which loop registers
        came from the defaults).

    Raises
    ------
    typer.BadParameter
        No motor named (``--motor`` nor the setup's ``motor:``) or the two disagree.
    """
    from jvl_gym import MotorArray

    cfg = load_setup(setup)
    named = cfg.motor
    if motor is None and named is None:
        raise typer.BadParameter(f"{setup} names no motor (no 'motor:' key): give --motor",
                                 param_hint="'--motor'")
    fam = tuned_family(motor if motor is not None else named)
    if motor is not None and named is not None and (
            fam.canonical_name(motor) != fam.canonical_name(named)):
        raise typer.BadParameter(f"{setup} is a setup for {named}, not {motor}",
                                 param_hint="'--motor'")
    name = fam.load_motor(motor if motor is not None else named).name
    m = MotorArray(name, n=1)  # the motor type's defaults
    defaults = {reg.name: float(m.read(reg.name)[0]) for reg in m.table
                if reg.access.value == "rw" and reg.format.value != "LongIntHigh"}
    MotorArray(name, n=1, setup=setup)  # validates the setup, naming it in the error
    missing = sorted(set(defaults) - set(cfg.registers))
    regs = {**defaults, **{k: float(v) for k, v in cfg.registers.items()}}
    from_defaults = [k for k in loop_keys if k in missing]
    lines = []
    if from_defaults:
        lines.append(f"{setup} lacks {', '.join(from_defaults)}: verified with the {name} "
                     "defaults (what the motor keeps when the setup is written)")
    return name, regs, lines

"""The tuning toolkit's access to a motor family: the family contract's :class:`TuningSpec`.

Every fact the toolkit uses of a family comes from the family's
:class:`~jvl_gym.families.Family` record (``jvl_gym.families.family_of_motor``): the sample
times, counts per revolution, PWM and AMPLITUDE scales and filter taps of ``Family.tuning``,
the register table (formats and ranges for the quantisation), the motor configs and default
setups of ``Family.config``, and what the firmware supports (``Family.supports``). A family
without a tuning procedure has ``tuning = None``.
"""

from __future__ import annotations

from typing import Any

import yaml

from jvl_gym.families import Family, TuningSpec, families, family, family_of_motor

__all__ = ["tuned_family", "tuning_spec", "setup_registers", "default_filters"]


def tuned_family(motor: Any) -> Family:
    """The family of ``motor`` (a motor type name, config path or config) if it has a tuning
    procedure.

    Raises
    ------
    ValueError
        The family has none (``Family.tuning`` is None); the message names the families that
        have one.
    """
    fam = family_of_motor(motor)
    if fam.tuning is None:
        tuned = sorted(k for k in families() if family(k).tuning is not None)
        raise ValueError(f"jvl-tune has no tuning procedure for the {fam.key} family of "
                         f"{motor!r}; it tunes the {' and '.join(tuned)} families")
    return fam


def tuning_spec(motor: Any) -> TuningSpec:
    """The :class:`TuningSpec` of ``motor``'s family (:func:`tuned_family`)."""
    spec = tuned_family(motor).tuning
    assert spec is not None
    return spec


def setup_registers(fam: Family, cfg: Any) -> dict[str, float]:
    """The registers of motor config ``cfg``'s default setup (the family's ``configs/setups``);
    empty where the family has no default setups or the file is missing."""
    if fam.config.SETUPS_DIR is None:
        return {}
    path = fam.config.setup_path(cfg.setup)
    if not path.is_file():
        return {}
    regs = (yaml.safe_load(path.read_text()) or {}).get("registers") or {}
    return {k: float(v) for k, v in regs.items()}


def default_filters(motor_type: str, keys: tuple[str, ...]) -> dict[str, float]:
    """The registers ``keys`` of the motor type's default setup, those it leaves out at their
    ROM defaults (the family's register table), in the order of ``keys``."""
    fam = tuned_family(motor_type)
    regs = setup_registers(fam, fam.load_motor(motor_type))
    return {k: float(regs[k]) if k in regs else float(fam.table.lookup(k).default)
            for k in keys}

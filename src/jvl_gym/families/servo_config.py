"""The motor data every PMSM servo family's config holds, bounded by the family's own limits.

:class:`ServoMotorData` declares the fields once (type and unit); a servo family states the
interval of each numeric field (physically plausible for its motor class and inside the
region where its simulation's integration is stable) and its defaults as data, in
``configs/limits.yaml`` of its folder, and :func:`bounded_servo_data` makes the model with
those bounds as pydantic constraints (each a field's ``metadata``, reported by name when a
config breaks it). The family's config class derives from that model and adds its own fields::

    rotor_inertia: {ge: 5.0e-6, lt: 1.0}    # bounds: gt, ge, lt, le
    pole_pairs: {default: 2, ge: 1, le: 16}  # a default makes the field optional
"""

from __future__ import annotations

import math
import typing
from pathlib import Path
from typing import Any

from pydantic import Field, create_model

from .config import ConfigError, MotorData, Real, Text, Whole, bounded_by, read_config_file

__all__ = ["ServoMotorData", "bounded_servo_data"]

_LIMIT_KEYS = ("gt", "ge", "lt", "le", "default")


class ServoMotorData(MotorData):
    """Physical data of one PMSM servo motor type (SI units); the bounds are the family's."""

    name: Text
    motor_type_code: Whole = Field(description="MOTOR_TYPE register")
    rated_torque: Real = Field(description="N·m, continuous")
    peak_torque: Real = Field(description="N·m at T_SOLL = 1023, >= rated")
    rated_speed_rpm: Real = Field(description="RPM")
    rotor_inertia: Real = Field(description="J_m, kg·m²")
    flux_linkage: Real = Field(description="λ, V·s (peak, per phase)")
    phase_resistance: Real = Field(description="Ω per phase")
    phase_inductance: Real = Field(description="H per phase")
    amps_per_count: Real = Field(description="A per ADC count")
    pole_pairs: Whole = Field(description="pole pairs")
    supply_voltage: Real = Field(description="V, nominal DC supply")
    pwm_delay_samples: Whole = Field(description="0 or 1 current-loop samples")
    thermal_time_constant: Real = Field(description="s, I2T filter")
    regen_time_constant: Real = Field(description="s, UIT filter")
    bus_capacitance: Real = Field(description="F")
    supply_resistance: Real = Field(description="Ω")
    dump_voltage: Real = Field(description="V, above supply_voltage")
    dump_resistance: Real = Field(description="Ω")
    setup: Text

    _peak_at_least_rated = bounded_by("peak_torque", "rated_torque")
    _dump_above_supply = bounded_by("dump_voltage", "supply_voltage", strict=True, unit="V",
                                    why="the power dump would burn the supply's power")


def _bounded_fields() -> list[str]:
    """The numeric fields of :class:`ServoMotorData`, each of which a family bounds."""
    return [n for n, f in ServoMotorData.model_fields.items() if f.annotation in (int, float)]


def bounded_servo_data(limits: Path, name: str) -> type[ServoMotorData]:
    """:class:`ServoMotorData` with the bounds and defaults of a family's ``limits`` file.

    Parameters
    ----------
    limits : pathlib.Path
        The family's ``configs/limits.yaml``: numeric field → mapping of ``gt``, ``ge``,
        ``lt``, ``le`` (finite numbers) and optionally ``default``; every numeric field has
        an entry with at least one bound.
    name : str
        The model's name (in validation messages).

    Returns
    -------
    type
        A subclass of :class:`ServoMotorData`.

    Raises
    ------
    ConfigError
        The file is missing or malformed (names the file and the entry).
    """
    data = read_config_file(limits)
    hints = typing.get_type_hints(ServoMotorData, include_extras=True)
    wanted = _bounded_fields()
    unknown = sorted(set(data) - set(wanted))
    if unknown:
        raise ConfigError(f"{limits}: no servo motor-data field {unknown}; known: "
                          f"{', '.join(wanted)}")
    fields: dict[str, Any] = {}
    for field in wanted:
        entry = data.get(field)
        if not isinstance(entry, dict) or set(entry) - set(_LIMIT_KEYS):
            raise ConfigError(f"{limits}: {field}: expected a mapping of {', '.join(_LIMIT_KEYS)}"
                              f", got {entry!r}")
        bounds = {k: v for k, v in entry.items() if k != "default"}
        if not bounds or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                 and math.isfinite(v) for v in bounds.values()):
            raise ConfigError(f"{limits}: {field}: at least one bound (gt, ge, lt, le), each a "
                              f"finite number, is required; got {entry!r}")
        info = ServoMotorData.model_fields[field]
        default = entry.get("default", ...)
        fields[field] = (hints[field], Field(default, description=info.description, **bounds))
    model: type[ServoMotorData] = create_model(name, __base__=ServoMotorData,
                                               __module__=__name__, **fields)
    return model

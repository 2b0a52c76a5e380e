"""A PMSM servo's motor data in the parameter columns of a family's layout.

The servo families' plants (the PMSM coil, the rotor and end stops, the DC bus of
:mod:`jvl_gym.physics`) read the same motor data from parameter columns of the same names in
each family's ``layout`` module; this module copies a motor config into them once per motor
type. A family adds the columns that are its own (monitor filter gains, thermal
model) to the row it returns.
"""

from __future__ import annotations

import math
from types import ModuleType
from typing import Any

import numpy as np

__all__ = ["SERVO_CONFIG_COLUMNS", "servo_parameters"]


#: layout column → the motor config field it holds (SI units)
SERVO_CONFIG_COLUMNS: dict[str, str] = {
    "P_J_MOTOR": "rotor_inertia",  # kg·m²
    "P_R": "phase_resistance",  # Ω per phase
    "P_L": "phase_inductance",  # H per phase
    "P_LAMBDA": "flux_linkage",  # V·s
    "P_AMPS_PER_COUNT": "amps_per_count",  # A per ADC count
    "P_POLE_PAIRS": "pole_pairs",
    "P_PWM_DELAY": "pwm_delay_samples",  # 0 or 1 inner samples
    "P_C_BUS": "bus_capacitance",  # F
    "P_R_SUPPLY": "supply_resistance",  # Ω
    "P_U_DUMP": "dump_voltage",  # V
    "P_R_DUMP": "dump_resistance",  # Ω
}


def servo_parameters(layout: ModuleType, cfg: Any, stop_stiffness: float,
                     stop_damping: float) -> np.ndarray:
    """The parameter row (``layout.N_PARAM``,) of a servo motor type before reset keywords.

    Parameters
    ----------
    layout : module
        The family's layout: ``N_PARAM``, the columns of :data:`SERVO_CONFIG_COLUMNS` and
        ``P_STOP_LO``, ``P_STOP_HI``, ``P_STOP_K``, ``P_STOP_D``, ``P_HOME_POS``.
    cfg : motor config
        The fields named in :data:`SERVO_CONFIG_COLUMNS`.
    stop_stiffness, stop_damping : float
        The mechanical end stops' stiffness [N·m/rad] and damping [N·m·s/rad].

    Returns
    -------
    numpy.ndarray
        float64: the motor data, the end stops inactive (lower above upper) and no home
        sensor (at infinity); every other column 0.
    """
    p = np.zeros(layout.N_PARAM)
    for column, field in SERVO_CONFIG_COLUMNS.items():
        p[getattr(layout, column)] = getattr(cfg, field)
    p[layout.P_STOP_LO] = 1.0
    p[layout.P_STOP_HI] = -1.0
    p[layout.P_STOP_K] = stop_stiffness
    p[layout.P_STOP_D] = stop_damping
    p[layout.P_HOME_POS] = math.inf
    return p

"""The parameter columns every servo family's ``layout`` starts with: the PMSM motor and its
load, as the coil, rotor and bus of :mod:`jvl_gym.physics` read them and
:mod:`.servo_data` fills them from a motor config. A servo layout imports them all and numbers
its own columns from ``N_SERVO_PARAM`` on.
"""

from __future__ import annotations

__all__ = ["P_J_MOTOR", "P_J_LOAD", "P_VISCOUS", "P_COULOMB", "P_R", "P_L", "P_LAMBDA",
           "P_AMPS_PER_COUNT", "P_POLE_PAIRS", "P_PWM_DELAY", "N_SERVO_PARAM"]

(
    P_J_MOTOR,  # rotor inertia [kg·m²]
    P_J_LOAD,  # load inertia [kg·m²] (behind the coupling, in a family whose layout has one)
    P_VISCOUS,  # viscous friction [N·m·s/rad]
    P_COULOMB,  # Coulomb friction [N·m]
    P_R,  # phase resistance [Ω]
    P_L,  # phase inductance [H]
    P_LAMBDA,  # flux linkage [V·s]
    P_AMPS_PER_COUNT,  # [A per ADC count]
    P_POLE_PAIRS,
    P_PWM_DELAY,  # 0 or 1 inner samples
    N_SERVO_PARAM,
) = range(11)

"""Current regulator at 7812.5 Hz: commutation and three per-phase loops (manual 4.3).

Commutation: ``I_NOM = |VF_OUT|``, ``PHI_SOLL = ELDEG_IST ± 90° + V_ELDEG·PHASE_COMP`` (the sign of
the torque selects ±90°, 512 units; 3.2.126), and

    IA_SOLL = I_NOM·AMPLITUDE·sin(PHI_SOLL),  IB_SOLL = …sin(PHI_SOLL + 120°),  IC_SOLL = …+ 240°.

Per phase: ``e = I_SOLL − IB(I_IST)`` with ``IB(z) = KIB1 + KIB0 z⁻¹`` (Fixed8, 3.2.110) and
``U = IF(e)``, ``IF(z) = (KIFX2 + KIFX1 z⁻¹) / (1 − KIFY1 z⁻¹ − KIFY0 z⁻²)`` (Fixed4, 3.2.106),
rounded and saturated to ±1023 PWM counts; the IF recursion uses the stored (saturated) outputs.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ....engine.jit import LANE_KERNEL
from ....physics.fixed import clamp, fx8, rnd
from ....physics.trig import fma, sincos
from .. import constants as c
from . import regs as R

_HALF_SQRT3 = 0.5 * math.sqrt(3.0)
_PER_TURN = 1.0 / c.ELDEG_PER_TURN  #: exact (a power of two)
#: radians per electrical angle unit (2048 per electrical turn, 3.2.143)
RAD_PER_UNIT = 2.0 * math.pi / c.ELDEG_PER_TURN


@njit(**LANE_KERNEL, forceinline=True)
def references(vf: float, eldeg: float, v_eldeg: float, phase_comp: float, amplitude: float
               ) -> tuple[float, float, float, float, float]:
    """Commutation (4.3.1, 3.2.126): ``(I_NOM, PHI_SOLL, IA_SOLL, IB_SOLL, IC_SOLL)`` from
    VF_OUT, ELDEG_IST, V_ELDEG and the raw PHASE_COMP (Fixed8) and AMPLITUDE (Fixed8) registers.

    Pure arithmetic on floats holding the registers' integers (the angle's ``mod 2048`` by
    ``floor``, exact), so that :mod:`mac050_141.inner` can run it for several motors in SIMD lanes.
    """
    i_nom = abs(vf)
    quarter = 512.0 if vf >= 0.0 else -512.0
    phi = eldeg + quarter + rnd(v_eldeg * fx8(phase_comp))
    phi -= c.ELDEG_PER_TURN * np.floor(phi * _PER_TURN)
    ia, ib, ic = phase_references(i_nom * fx8(amplitude), phi)
    return i_nom, phi, ia, ib, ic


@njit(**LANE_KERNEL, forceinline=True)
def phase_references(amp: float, phi: float) -> tuple[float, float, float]:
    """IA/IB/IC_SOLL = amp·sin(PHI + k·120°) for ``phi`` in 0..2047, stored in −850..850 (3.2.133).

    The firmware's sine table holds sin and cos of the 2048 angle units; they are computed
    here (:func:`jvl_gym.physics.trig.sincos` of ``phi·2π/2048``, within an ulp of the exact
    values) rather than looked up: a table lookup needs an integer index, which made the
    compiler step the whole angle computation lane by lane instead of in SIMD registers
    (``jvl_gym.families.mac050_141.inner``). Then ``sin(φ + 120°) = −sin φ/2 + (√3/2)·cos φ`` and
    ``sin(φ + 240°) = −sin φ/2 − (√3/2)·cos φ``. ``+ 0.0`` makes a zero +0.0, as the integer
    registers hold it (:func:`phase_step`).
    """
    sa, ca = sincos(phi * RAD_PER_UNIT)
    return (clamp(rnd(amp * sa), -850.0, 850.0) + 0.0,
            clamp(rnd(amp * (-0.5 * sa + _HALF_SQRT3 * ca)), -850.0, 850.0) + 0.0,
            clamp(rnd(amp * (-0.5 * sa - _HALF_SQRT3 * ca)), -850.0, 850.0) + 0.0)


@njit(**LANE_KERNEL, forceinline=True)
def store_references(r: np.ndarray, i_nom: float, phi: float, ia: float, ib: float,
                     ic: float) -> None:
    """Store I_NOM, PHI_SOLL and IA/IB/IC_SOLL (consecutive registers, 3.2.133)."""
    r[R.I_NOM] = int(i_nom)
    r[R.PHI_SOLL] = int(phi)
    r[R.IA_SOLL] = int(ia)
    r[R.IB_SOLL] = int(ib)
    r[R.IC_SOLL] = int(ic)


@njit(**LANE_KERNEL, forceinline=True)
def phase_step(i_soll: float, i_ist: float, e1: float, u1: float, u2: float, i_ist1: float,
               kib1: float, kib0: float, kifx2: float, kifx1: float, kify1: float,
               kify0: float) -> tuple[float, float]:
    """One phase's loop (4.3.1): ``(U, e)`` from IX_SOLL, IX_IST, the histories ``e(k−1)``,
    ``U(k−1)``, ``U(k−2)``, ``I_IST(k−1)`` and the coefficients (Fixed8 KIB, Fixed4 KIF values).

    ``U`` is an integer; ``+ 0.0`` makes a rounded −0.0 the +0.0 that UX_VAL holds: the inner
    sample (``mac050_141.inner``) applies ``U`` without reading it back from the register.
    """
    e = i_soll - fma(kib1, i_ist, kib0 * i_ist1)
    u = fma(kifx2, e, fma(kifx1, e1, fma(kify1, u1, kify0 * u2)))
    return clamp(rnd(u), -1023.0, 1023.0) + 0.0, e


@njit(**LANE_KERNEL, forceinline=True)
def manual_references(man_i_nom: float, man_alpha: int, amplitude: float
                      ) -> tuple[float, float, float]:
    """IA/IB/IC_SOLL of MANI_MODE (3.2.128): a stator field of MAN_I_NOM at the angle
    MAN_ALPHA (mod 2048), scaled by the raw AMPLITUDE (Fixed8) register."""
    return phase_references(man_i_nom * fx8(amplitude), float(man_alpha % c.ELDEG_PER_TURN))

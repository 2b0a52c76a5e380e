"""The plant of a two-phase hybrid step motor with its chopper, in SIMD lanes (MIS manual
§1.1.1, §5.1, §5.3; the motor data: ``configs/motors/*.yaml``).

**Motor.** 50 rotor teeth (200 full steps, 4 full steps per electrical turn, 8192 counts per
electrical turn). Two phases a, b with resistance R and inductance L; the rotor flux gives the
back-EMF ``e = j·Kt·ω·e^{jθe}`` (``θe = 50·θ``) and the torque ``T = Kt·Im(i·e^{−jθe})`` with
``i = ia + j·ib`` (``Kt``: N·m per A of current amplitude = V·s/rad). The detent torque is
``−Td·sin(4·θe)``. With the current at its amplitude ``I`` along the commanded electrical angle
``θc`` the torque is ``Kt·I·sin(θc − θe)``: the torque–angle curve whose peak ``Kt·I`` (at one
full step of lag) is the pull-out torque; a load beyond it (or an acceleration needing more)
lets the rotor fall back by whole electrical turns — steps are lost in fours, as the manual's
"the motor can only stall in multiples of a 1/50 shaft revolution" (§5.8.1).

**Chopper.** The firmware sets the amplitude (RUN_CURRENT, STANDBY_CURRENT, the closed-loop
scale) and the commanded position (P_IST's microsteps, moving linearly over the outer sample).
The currents are integrated in the frame of the commanded electrical angle: there the
reference is constant and ``L·di/dt = v − (R + jωc·L)·i − e`` is linear with constant
coefficients over an inner sample, so it is discretised exactly (``i' = a·i + b·(v − e)``,
``a = e^{−(R/L + jωc)·h}``, ``b = (1 − a)/(R + jωc·L)``), stable for any step and speed. The
chopper applies the voltage that brings the current to the reference in one inner sample,
limited to the supply voltage in magnitude (each phase's full bridge gives ±U; the circle is
what it gives at every angle — a decision). At speed the back-EMF and ``ωc·L`` take the
voltage, the current falls short of the reference and lags it, and the torque falls: the
speed–torque curve follows from the electrical data. Passive mode switches the bridge off (the
currents are taken to vanish within the inner sample: the flyback diodes return the coil energy
to the supply).

**Step.** 10 inner samples per 1 ms outer sample (100 µs). In the commanded frame the currents
need no finer step; the finer limit is the rotor: the stiffness ``50·Kt·I`` with the rotor
inertia gives natural frequencies of 120–310 Hz for the configured types, ``ω_n·h ≤ 0.2``,
integrated by semi-implicit (symplectic) Euler with viscous friction implicit and Coulomb
friction as a clamp towards standstill (stable and without chatter). The detent torque varies
four times per electrical turn, up to 10 kHz at 3000 RPM — the inner rate itself; it is applied
as its mean over the inner sample (``sin`` at the midpoint times the sinc of half the angle
step), so it does not alias into a steady torque at speed.

**Damping.** Iron and eddy-current losses damp the rotor's motion relative to the stator
field: a torque ``D·(ωc − ω)`` against the slip between the rotor and the commanded field speed,
with ``D = 2·ζ·√(50·Kt·I·J)`` — the damping ratio ``ζ`` of the config (``damping_ratio``) at
the present current amplitude ``I`` and total inertia ``J``. Without it the deadbeat chopper
(which cancels the back-EMF) would leave the rotor's oscillation about the field undamped;
a viscous friction on the absolute speed of that size would take most of the torque at speed.
It is integrated implicitly with the viscous friction.

**End stops** (for the torque zero search, §6.5.7): optional hard stops below and above
given rotor angles, a spring–damper whose stiffness makes ``ω·h = √0.1`` against the rotor
inertia (stiff, and stable in the explicit step) with a damping ratio of 0.7.

**Closed loop** (§5.3): the currents are commutated to a field position that follows the
commanded position at no more than the speed the firmware allows (V_SOLL, or more by
CL_CATCH_UP's overspeed, ``firmware.closed_loop``) and is kept within one full step (2048
counts, 90° electrical) of the encoder's rotor position, so the current never leads the rotor
by more than the torque peak and a lagging rotor is pulled at full torque up to that speed.

Lanes: field ``f`` of lane ``j`` is ``scratch[f·LANES + j]``; the outer sample writes the
sample's constants (:func:`prepare_lane`), :func:`inner_block` steps the block's motors in lanes
(the same arithmetic for 1 or ``LANES`` motors: bit-identical).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ....engine.apart import apart
from ....engine.jit import LANE_KERNEL, widest_vectors
from ....physics.trig import sincos
from .. import constants as c
from .. import layout as L
from ..units import COUNTS_PER_REV

#: motors per block
LANES = 8

(
    F_THETA, F_OMEGA, F_ID, F_IQ, F_ECOP, F_ELOAD, F_FIELD,  # state copied in and out
    F_CMD0, F_DCMD, F_IREF, F_BRIDGE, F_ARE, F_AIM, F_BRE, F_BIM, F_GRE, F_GIM, F_VMAX,
    F_KT, F_TD, F_JINV, F_VISC, F_COUL, F_LOAD, F_R, F_CL, F_QUANT, F_DAMP, F_WC,
    F_FSTEP, F_STOP_LO, F_STOP_HI, F_STOP_K, F_STOP_D, N_FIELDS,
) = range(35)

_H = c.INNER_DT
_N = c.INNER_PER_OUTER
COUNTS_PER_RAD = COUNTS_PER_REV / (2.0 * math.pi)
_ELEC_PER_COUNT = 2.0 * math.pi / c.COUNTS_PER_ELECTRICAL_TURN
_DETENT_PER_COUNT = 2.0 * math.pi / c.COUNTS_PER_FULL_STEP
_DETENT_PER_RAD = 4.0 * c.POLE_PAIRS  # detent angle per rotor radian
#: encoder counts per revolution by ENCODER_TYPE code (0: none)
_CPR = np.array([c.ENCODER_CPR.get(code, 0) for code in range(11)], dtype=np.int64)
#: end stops: stiffness as ``(ω·h)²`` of the rotor against the stop, and its damping ratio
STOP_STIFFNESS = 0.1
STOP_DAMPING = 0.7
#: ``S_BRIDGE`` values: off (passive), on, on with closed-loop commutation
BRIDGE_OFF, BRIDGE_ON, BRIDGE_CLOSED_LOOP = 0.0, 1.0, 2.0


def lane_scratch(n_motors: int) -> np.ndarray:
    """Working memory of the blocks: ``(ceil(n / LANES), N_FIELDS·LANES)`` float64."""
    return np.zeros((-(-int(n_motors) // LANES), N_FIELDS * LANES))


@njit(cache=True)
def prepare_lane(sc, j: int, s, p, u) -> None:  # pragma: no cover - compiled
    """Write motor's outer-sample constants into lane ``j`` of its block's scratch ``sc``."""
    k = LANES
    dcmd = (s[L.S_CMD] - s[L.S_CMD_PREV]) / _N
    sc[F_CMD0 * k + j] = s[L.S_CMD_PREV]
    sc[F_DCMD * k + j] = dcmd
    sc[F_IREF * k + j] = s[L.S_I_AMP]
    r, ind = p[L.P_R], p[L.P_L]
    wc = dcmd / _H * _ELEC_PER_COUNT  # commanded electrical speed [rad/s]
    decay = math.exp(-r / ind * _H)
    sn, cs = sincos(wc * _H)
    a_re, a_im = decay * cs, -decay * sn
    z_re, z_im = r, wc * ind
    one_re, one_im = 1.0 - a_re, -a_im
    den = z_re * z_re + z_im * z_im
    b_re = (one_re * z_re + one_im * z_im) / den
    b_im = (one_im * z_re - one_re * z_im) / den
    den_b = b_re * b_re + b_im * b_im
    sc[F_ARE * k + j], sc[F_AIM * k + j] = a_re, a_im
    sc[F_BRE * k + j], sc[F_BIM * k + j] = b_re, b_im
    sc[F_GRE * k + j], sc[F_GIM * k + j] = b_re / den_b, -b_im / den_b
    sc[F_VMAX * k + j] = max(u[L.I_SUPPLY_VOLTS], 0.0)
    sc[F_KT * k + j] = p[L.P_KT]
    sc[F_TD * k + j] = p[L.P_DETENT]
    inertia = p[L.P_J_MOTOR] + p[L.P_J_LOAD]
    sc[F_JINV * k + j] = 1.0 / inertia
    stiffness = c.POLE_PAIRS * p[L.P_KT] * s[L.S_I_AMP] * min(s[L.S_BRIDGE], 1.0)
    sc[F_DAMP * k + j] = 2.0 * p[L.P_ZETA] * math.sqrt(stiffness * inertia)
    sc[F_WC * k + j] = dcmd / _H / COUNTS_PER_RAD
    sc[F_VISC * k + j] = p[L.P_VISCOUS]
    # a holding brake adds its torque to the friction that holds the shaft (``supervision``)
    sc[F_COUL * k + j] = p[L.P_COULOMB] + s[L.S_BRAKE_HELD] * p[L.P_BRAKE_TORQUE]
    sc[F_LOAD * k + j] = u[L.I_LOAD_TORQUE]
    sc[F_R * k + j] = r
    sc[F_BRIDGE * k + j] = min(s[L.S_BRIDGE], 1.0)
    sc[F_CL * k + j] = 1.0 if s[L.S_BRIDGE] == BRIDGE_CLOSED_LOOP else 0.0
    cpr = _CPR[int(p[L.P_ENCODER])]
    sc[F_QUANT * k + j] = COUNTS_PER_REV // cpr if cpr > 0 else 1.0
    sc[F_FSTEP * k + j] = s[L.S_FIELD_STEP]
    sc[F_STOP_LO * k + j] = p[L.P_STOP_LO]
    sc[F_STOP_HI * k + j] = p[L.P_STOP_HI]
    sc[F_STOP_K * k + j] = STOP_STIFFNESS * inertia / (_H * _H)
    sc[F_STOP_D * k + j] = 2.0 * STOP_DAMPING * STOP_STIFFNESS ** 0.5 * inertia / _H


@apart
@widest_vectors
@njit(**LANE_KERNEL)
def inner_samples(state, i0: int, n: int, sc) -> None:  # pragma: no cover - compiled
    """The inner samples of motors ``i0 … i0 + n − 1`` in lanes (module docstring)."""
    k = LANES
    for j in range(n):
        sc[F_THETA * k + j] = state[i0 + j, L.S_THETA]
        sc[F_OMEGA * k + j] = state[i0 + j, L.S_OMEGA]
        sc[F_ID * k + j] = state[i0 + j, L.S_ID]
        sc[F_IQ * k + j] = state[i0 + j, L.S_IQ]
        sc[F_ECOP * k + j] = state[i0 + j, L.S_E_COPPER]
        sc[F_ELOAD * k + j] = state[i0 + j, L.S_E_LOAD]
        sc[F_FIELD * k + j] = state[i0 + j, L.S_FIELD]
    for step in range(_N):
        for j in range(n):
            _inner(sc, j, step)
    for j in range(n):
        state[i0 + j, L.S_THETA] = sc[F_THETA * k + j]
        state[i0 + j, L.S_OMEGA] = sc[F_OMEGA * k + j]
        state[i0 + j, L.S_ID] = sc[F_ID * k + j]
        state[i0 + j, L.S_IQ] = sc[F_IQ * k + j]
        state[i0 + j, L.S_E_COPPER] = sc[F_ECOP * k + j]
        state[i0 + j, L.S_E_LOAD] = sc[F_ELOAD * k + j]
        state[i0 + j, L.S_FIELD] = sc[F_FIELD * k + j]


@njit(cache=True, inline="always", error_model="numpy")
def _inner(sc, j: int, step: int) -> None:  # pragma: no cover - compiled
    """One inner sample of lane ``j``."""
    k = LANES
    theta = sc[F_THETA * k + j]
    omega = sc[F_OMEGA * k + j]
    i_d = sc[F_ID * k + j]
    i_q = sc[F_IQ * k + j]
    kt = sc[F_KT * k + j]
    cmd = sc[F_CMD0 * k + j] + (step + 1) * sc[F_DCMD * k + j]
    rotor = theta * COUNTS_PER_RAD
    quant = sc[F_QUANT * k + j]
    enc = np.floor(rotor / quant) * quant
    cl = sc[F_CL * k + j]
    field = sc[F_FIELD * k + j]
    fstep = sc[F_FSTEP * k + j]
    field_cl = min(max(field + min(max(cmd - field, -fstep), fstep),
                       enc - c.COUNTS_PER_FULL_STEP), enc + c.COUNTS_PER_FULL_STEP)
    cmd = cl * field_cl + (1.0 - cl) * cmd
    sc[F_FIELD * k + j] = cmd
    lag = rotor - cmd
    lag -= c.COUNTS_PER_ELECTRICAL_TURN * np.floor(lag / c.COUNTS_PER_ELECTRICAL_TURN + 0.5)
    sd, cd = sincos(lag * _ELEC_PER_COUNT)
    e_re = -kt * omega * sd
    e_im = kt * omega * cd
    a_re, a_im = sc[F_ARE * k + j], sc[F_AIM * k + j]
    ai_re = a_re * i_d - a_im * i_q
    ai_im = a_re * i_q + a_im * i_d
    x_re = sc[F_IREF * k + j] - ai_re
    x_im = -ai_im
    g_re, g_im = sc[F_GRE * k + j], sc[F_GIM * k + j]
    v_re = x_re * g_re - x_im * g_im + e_re
    v_im = x_re * g_im + x_im * g_re + e_im
    mag = math.sqrt(v_re * v_re + v_im * v_im + 1e-300)
    lim = min(1.0, sc[F_VMAX * k + j] / mag)
    w_re = v_re * lim - e_re
    w_im = v_im * lim - e_im
    b_re, b_im = sc[F_BRE * k + j], sc[F_BIM * k + j]
    on = sc[F_BRIDGE * k + j]
    n_d = on * (ai_re + b_re * w_re - b_im * w_im)
    n_q = on * (ai_im + b_re * w_im + b_im * w_re)
    m_d = 0.5 * (i_d + n_d)
    m_q = 0.5 * (i_q + n_q)
    torque = kt * (m_q * cd - m_d * sd)
    rc = rotor - c.COUNTS_PER_FULL_STEP * np.floor(rotor / c.COUNTS_PER_FULL_STEP)
    half = 0.5 * omega * _H * _DETENT_PER_RAD
    sp, _ = sincos(rc * _DETENT_PER_COUNT + half)
    sh, _ = sincos(half)
    sinc = sh / half if half != 0.0 else 1.0
    torque -= sc[F_TD * k + j] * sp * sinc
    below = max(sc[F_STOP_LO * k + j] - theta, 0.0)
    above = max(theta - sc[F_STOP_HI * k + j], 0.0)
    touch = 1.0 if below + above > 0.0 else 0.0
    torque += sc[F_STOP_K * k + j] * (below - above) - touch * sc[F_STOP_D * k + j] * omega
    load = sc[F_LOAD * k + j]
    jinv = sc[F_JINV * k + j]
    damp = sc[F_DAMP * k + j]
    w = (omega + _H * jinv * (torque - load + damp * sc[F_WC * k + j])) / (
        1.0 + _H * jinv * (sc[F_VISC * k + j] + damp))
    stop = _H * jinv * sc[F_COUL * k + j]
    w = math.copysign(max(abs(w) - stop, 0.0), w)
    theta_new = theta + _H * w
    sc[F_THETA * k + j] = theta_new
    sc[F_OMEGA * k + j] = w
    sc[F_ID * k + j] = n_d
    sc[F_IQ * k + j] = n_q
    sc[F_ECOP * k + j] += _H * sc[F_R * k + j] * (m_d * m_d + m_q * m_q)
    sc[F_ELOAD * k + j] += load * (theta_new - theta)

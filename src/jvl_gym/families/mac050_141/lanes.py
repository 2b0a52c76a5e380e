"""The inner samples of a block of :data:`LANES` motors (docs/model.md §2, §17).

The engine's driver (``jvl_gym.engine.driver``) advances motors in blocks: the firmware's
outer step of every motor of the block, one motor at a time, then the block's 15 inner samples
in one call of :func:`inner_samples`. It puts the motors that :func:`in_lanes` admits into SIMD
lanes of the block's scratch (:mod:`mac050_141.scratch`) and steps them together, and steps the
others one at a time with every per-motor feature; both are specialisations of the one inner
sample, :func:`mac050_141.inner.inner_sample`, and give the same bits, so an N-motor array is
bit-for-bit equal to N one-motor arrays.

The lanes of a block whose motors all have a rigid shaft run :func:`lane_samples_rigid`, which
leaves the elastic coupling's terms out of the plant (exact zeros for such a motor: the same
bits without their arithmetic); a block with a coupled motor in its lanes runs
:func:`lane_samples_coupled`. Both are one template, :func:`_lane_samples`, compiled once for
each value of ``RIGID`` (:func:`jvl_gym.engine.specialize.specialise`) as functions of their
own. Each calls the one compiled sample, which LLVM inlines into its lane loops and
vectorises there with the caller's constants folded (:mod:`mac050_141.inner`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...engine.apart import apart
from ...engine.jit import LANE_KERNEL, plain_arguments, widest_vectors
from ...engine.specialize import specialise
from . import constants as c
from . import layout as L
from .firmware import regs as R
from .firmware.mode_table import N_MODES
from .firmware.modes import COMMUTATED
from .inner import inner_sample, inner_samples_one
from .scratch import F_MOTOR, LANE_BASE, LANES, gather, lane_scratch, scatter_state, store_registers

__all__ = ["LANES", "in_lanes", "inner_samples", "lane_samples_coupled", "lane_samples_rigid",
           "lane_scratch"]

#: bound per specialisation of :func:`_lane_samples`: True when no motor of the lanes has an
#: elastic coupling
RIGID: bool = False


@njit(cache=True, inline="always")
def in_lanes(r: np.ndarray, p: np.ndarray) -> bool:
    """True when a motor's next inner samples need none of the per-motor features of
    :func:`mac050_141.inner.inner_sample`: a mode with commutation and current loops (not INIT,
    SAFE, TESTU, TESTKI, MANI), commutation aligned (no hall synchronisation), no current or
    torque noise, no inner-rate recording. Such a motor can run in a SIMD lane."""
    mode = r[R.MODE_REG]
    cb = r[R.CNTRL_BITS]
    return (0 <= mode < N_MODES and COMMUTATED[mode] and p[L.P_HALL_START] < 0.5
            and not p[L.P_CURRENT_NOISE] > 0.0 and not p[L.P_TORQUE_NOISE] > 0.0
            and not ((cb & c.RECORDBIT) and (cb & c.RECINNERBIT)))


def _lane_samples(scratch, m, r0, s0, p0, u0, key0, b0, rec, fmt):  # pragma: no cover
    """The 15 inner samples of lanes 0 … ``m`` − 1 of a block's scratch row ``scratch``
    (:func:`mac050_141.inner.inner_sample` without its per-motor features, ``rigid`` =
    ``RIGID``); the rows ``r0`` … ``fmt`` stand in for the arguments the lanes do not read."""
    for k in range(c.INNER_PER_OUTER - 1):
        for j in range(m):
            inner_sample(scratch, j, k, False, False, RIGID, r0, s0, p0, u0, key0, b0, rec, fmt)
    for j in range(m):
        inner_sample(scratch, j, c.INNER_PER_OUTER - 1, True, False, RIGID, r0, s0, p0, u0, key0,
                     b0, rec, fmt)
    if RIGID:  # the load of a rigid shaft is where the motor is (mechanics.mech_step_prepared)
        for j in range(m):
            scratch[LANE_BASE[L.S_LOAD_THETA] + j] = scratch[LANE_BASE[L.S_THETA] + j]
            scratch[LANE_BASE[L.S_LOAD_OMEGA] + j] = scratch[LANE_BASE[L.S_OMEGA] + j]


#: compiled apart: :func:`inner_samples` calls the machine code (``engine.apart``)
_OPTIONS = {"_lane_samples": {**LANE_KERNEL, "apart": True}}
#: :func:`_lane_samples` of lanes whose motors all have a rigid shaft
lane_samples_rigid = plain_arguments(widest_vectors(specialise(
    {"_lane_samples": _lane_samples}, {"RIGID": True}, "rigid", __file__,
    _OPTIONS)["_lane_samples"]))
#: :func:`_lane_samples` of lanes with an elastically coupled motor among them
lane_samples_coupled = plain_arguments(widest_vectors(specialise(
    {"_lane_samples": _lane_samples}, {"RIGID": False}, "coupled", __file__,
    _OPTIONS)["_lane_samples"]))


@apart
@njit(**LANE_KERNEL)
def inner_samples(regs, state, params, inputs, keys, buf, rec, fmt, i0, n, scratch):
    """The 15 inner samples (step 4, ``mac050_141.kernel``) of motors ``i0 .. i0 + n - 1``
    (``n <= LANES``, one block); ``scratch`` is the block's row of :func:`lane_scratch`.

    The motors that :func:`in_lanes` admits are gathered into lanes 0, 1, … of ``scratch``,
    stepped together (:func:`mac050_141.inner.inner_sample` without its per-motor features)
    and scattered back; the others run :func:`mac050_141.inner.inner_samples_one` one at a
    time in lanes n − 1, n − 2, … (so that each motor keeps its lane, and the lane its plant
    factors, while the motors' modes stay). Both give the same bits (tests/test_lanes.py).
    The lanes run :func:`lane_samples_rigid` unless one of their motors has an elastic coupling.
    """
    m = 0
    q = n - 1
    coupled = False
    for i in range(i0, i0 + n):
        r = regs[i]
        s = state[i]
        p = params[i]
        if in_lanes(r, p):
            gather(scratch, m, i, r, s, p, inputs[i])
            coupled = coupled or p[L.P_K_COUPLING] > 0.0
            m += 1
            continue
        inner_samples_one(r, s, p, inputs[i], keys[i], buf[i] if rec else buf[0], rec, fmt,
                          scratch, q)
        q -= 1
    # the lanes' samples read no row: any rows of the right types stand in
    if coupled:
        lane_samples_coupled(scratch, m, regs[i0], state[i0], params[i0], inputs[i0], keys[i0],
                             buf[0], rec, fmt)
    elif m > 0:
        lane_samples_rigid(scratch, m, regs[i0], state[i0], params[i0], inputs[i0], keys[i0],
                           buf[0], rec, fmt)
    for j in range(m):
        i = int(scratch[F_MOTOR * LANES + j])
        scatter_state(scratch, j, state[i])
        store_registers(scratch, j, regs[i])

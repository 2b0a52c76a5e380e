"""Motors advanced in blocks of :data:`LANES`: the drivers of the kernel (MODEL.md §1, §4).

An outer sample of a block is the firmware's outer step of every motor of the block, one motor
at a time (:func:`outer_sample`), then the block's 15 inner samples (:func:`inner_samples`).
The drivers of :class:`jvl_gym.MotorArray` (:func:`run_serial`, :func:`run_parallel`) and the
compiled environment steps (``jvl_gym.envs``) are written over blocks; a block belongs to one
thread, and its motors' arithmetic stays independent of each other, so an N-motor array is
still bit-for-bit equal to N one-motor arrays.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from . import constants as c
from . import layout as L
from .jit import KERNEL, KERNEL_PARALLEL
from .kernel import inner_sample, outer_firmware
from .plant.coil import coil_constants
from .plant.mechanics import mech_constants
from .plant.supply import bus_constants

#: motors per block
LANES = 16
#: scratch values per lane (see :func:`lane_scratch`)
N_FIELDS = 1

_H = c.INNER_DT


def lane_scratch(n_motors: int) -> np.ndarray:
    """Working memory of the blocks: one row of ``N_FIELDS * LANES`` float64 per block,
    shape ``(ceil(n_motors / LANES), N_FIELDS * LANES)``; row ``i // LANES`` is motor ``i``'s."""
    return np.zeros((-(-int(n_motors) // LANES), N_FIELDS * LANES))


@njit(cache=True, inline="always")
def outer_sample(regs, state, params, inputs, keys, buf, rec, fmt, input_plan, i, t):
    """Steps 1–3 of an outer sample (``jvl_gym.kernel``) for motor ``i``; with a non-empty
    ``input_plan`` (shape (n_outer, N, N_INPUT)) its row ``t`` sets the inputs first."""
    if input_plan.shape[0] > 0:
        for k in range(inputs.shape[1]):
            inputs[i, k] = input_plan[t, i, k]
    b = buf[i] if rec else buf[0]
    outer_firmware(regs[i], state[i], params[i], inputs[i], keys[i], b, rec, fmt)


@njit(**KERNEL)
def inner_samples(regs, state, params, inputs, keys, buf, rec, fmt, i0, n, scratch):
    """The 15 inner samples (step 4, ``jvl_gym.kernel``) of motors ``i0 .. i0 + n - 1``
    (``n <= LANES``, one block); ``scratch`` is the block's row of :func:`lane_scratch`."""
    for i in range(i0, i0 + n):
        r = regs[i]
        s = state[i]
        p = params[i]
        u = inputs[i]
        b = buf[i] if rec else buf[0]
        counts_per_amp = 1.0 / p[L.P_AMPS_PER_COUNT]
        k_coil = coil_constants(p[L.P_R], p[L.P_L], p[L.P_LAMBDA], _H)
        k_mech = mech_constants(p[L.P_J_MOTOR] + p[L.P_J_LOAD], p[L.P_VISCOUS], _H)
        k_bus = bus_constants(p[L.P_C_BUS], p[L.P_R_SUPPLY], p[L.P_R_DUMP], _H)
        for _k in range(c.INNER_PER_OUTER):
            inner_sample(r, s, p, u, keys[i], b, rec, fmt, counts_per_amp, k_coil, k_mech,
                         k_bus)


@njit(cache=True, inline="always")
def advance_block(regs, state, params, inputs, keys, buf, rec, fmt, input_plan, i0, n, n_outer,
                  scratch):
    """Advance motors ``i0 .. i0 + n - 1`` (one block) by ``n_outer`` outer samples."""
    for t in range(n_outer):
        for i in range(i0, i0 + n):
            outer_sample(regs, state, params, inputs, keys, buf, rec, fmt, input_plan, i, t)
        inner_samples(regs, state, params, inputs, keys, buf, rec, fmt, i0, n, scratch)


@njit(**KERNEL)
def run_serial(regs, state, params, inputs, keys, buf, rec, fmt, n_outer, input_plan, scratch):
    """Advance every motor by ``n_outer`` outer samples in one thread.

    ``rec`` says whether ``buf`` is an allocated (N, 895, 4) sample buffer. ``input_plan`` is
    either empty (shape (0, N, N_INPUT): inputs held) or holds the inputs of every
    outer sample, shape (n_outer, N, N_INPUT) (world generators). ``scratch`` is
    ``lane_scratch(N)``.
    """
    n_motors = regs.shape[0]
    for blk in range(scratch.shape[0]):
        i0 = blk * LANES
        advance_block(regs, state, params, inputs, keys, buf, rec, fmt, input_plan, i0,
                      min(LANES, n_motors - i0), n_outer, scratch[blk])


@njit(**KERNEL_PARALLEL)
def run_parallel(regs, state, params, inputs, keys, buf, rec, fmt, n_outer, input_plan, scratch):
    """:func:`run_serial` with the blocks spread over threads."""
    n_motors = regs.shape[0]
    for blk in prange(scratch.shape[0]):
        i0 = blk * LANES
        advance_block(regs, state, params, inputs, keys, buf, rec, fmt, input_plan, i0,
                      min(LANES, n_motors - i0), n_outer, scratch[blk])

"""The MAC050–141 family's compiled step, as the engine's driver calls it.

:func:`outer_sample` and :func:`inner_block` are bound into the templates of
:mod:`jvl_gym.engine.driver`; :func:`prepare` compiles the block's inner samples on their own
before a driver that calls them is compiled (compiled inside a caller's compilation, numba
takes several times as long).
"""

from __future__ import annotations

import numpy as np
from numba import njit, typeof, types

from ...engine.view import EngineView, record_rows, take_planned_inputs
from .inner import inner_samples_one
from .kernel import outer_firmware
from .lanes import LANES, inner_samples, lane_samples_coupled, lane_samples_rigid, lane_scratch

__all__ = ["LANES", "outer_sample", "inner_block", "prepare", "scratch"]


@njit(cache=True, inline="always")
def outer_sample(view: EngineView, i: int, t: int) -> None:  # pragma: no cover - compiled
    """Steps 1–3 of an outer sample (``mac050_141.kernel``) for motor ``i``; with a non-empty
    world-input plan its row ``t`` sets the motor's inputs first."""
    take_planned_inputs(view, i, t)
    inputs = view.inputs
    b = record_rows(view, i)
    outer_firmware(view.regs[i], view.state[i], view.params[i], inputs[i], view.keys[i], b,
                   view.rec, view.fmt)


@njit(cache=True, inline="always")
def inner_block(view: EngineView, i0: int, n: int, blk: int) -> None:  # pragma: no cover
    """The 15 inner samples of motors ``i0 .. i0 + n - 1`` (block ``blk``)."""
    inner_samples(view.regs, view.state, view.params, view.inputs, view.keys, view.buf,
                  view.rec, view.fmt, i0, n, view.scratch[blk])


def scratch(n_motors: int) -> np.ndarray:
    """Working memory of the blocks of ``n_motors`` motors (``view.scratch``)."""
    return lane_scratch(n_motors)


_prepared: list[bool] = []


def prepare(arrays: tuple) -> None:
    """Compile (or load from numba's cache) the inner samples for the types of ``arrays``
    (the fields of an :class:`EngineView`, whose types do not vary) on their own, once per
    process, before a driver that calls them is compiled."""
    if _prepared:
        return
    view = EngineView(*arrays)
    rec = types.boolean
    inner_samples_one.compile((typeof(view.regs[0]), typeof(view.state[0]),
                               typeof(view.params[0]), typeof(view.inputs[0]),
                               typeof(view.keys[0]), typeof(view.buf[0]), rec,
                               typeof(view.fmt), typeof(view.scratch[0]), types.int64))
    for lane_samples in (lane_samples_rigid, lane_samples_coupled):
        lane_samples.compile((typeof(view.scratch[0]), types.int64, typeof(view.regs[0]),
                              typeof(view.state[0]), typeof(view.params[0]),
                              typeof(view.inputs[0]), typeof(view.keys[0]),
                              typeof(view.buf[0]), rec, typeof(view.fmt)))
    inner_samples.compile((typeof(view.regs), typeof(view.state), typeof(view.params),
                           typeof(view.inputs), typeof(view.keys), typeof(view.buf), rec,
                           typeof(view.fmt), types.int64, types.int64,
                           typeof(view.scratch[0])))
    _prepared.append(True)

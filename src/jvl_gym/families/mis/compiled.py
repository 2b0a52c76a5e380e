"""The MIS family's compiled step, as the engine's driver calls it.

:func:`outer_sample` (the firmware's 1 ms sample of one motor, then its lane constants) and
:func:`inner_block` (the block's plant samples in lanes) are bound into the templates of
:mod:`jvl_gym.engine.driver`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit, typeof, types

from ...engine.view import EngineView, record_rows, take_planned_inputs
from .kernel import outer_firmware
from .plant.stepper import LANES, inner_samples, lane_scratch, prepare_lane

__all__ = ["LANES", "outer_sample", "inner_block", "compile_split", "scratch"]


@njit(cache=True, inline="always")
def outer_sample(view: EngineView, i: int, t: int) -> None:  # pragma: no cover - compiled
    """The firmware's outer sample of motor ``i``; with a non-empty world-input plan its row
    ``t`` sets the motor's inputs first."""
    take_planned_inputs(view, i, t)
    inputs = view.inputs
    b = record_rows(view, i)
    outer_firmware(view.regs[i], view.state[i], view.params[i], inputs[i], b, view.rec)
    blk = i // LANES
    prepare_lane(view.scratch[blk], i - blk * LANES, view.state[i], view.params[i], inputs[i])


@njit(cache=True, inline="always")
def inner_block(view: EngineView, i0: int, n: int, blk: int) -> None:  # pragma: no cover
    """The inner samples of motors ``i0 .. i0 + n - 1`` (block ``blk``)."""
    inner_samples(view.state, i0, n, view.scratch[blk])


def scratch(n_motors: int) -> np.ndarray:
    """Working memory of the blocks of ``n_motors`` motors (``view.scratch``)."""
    return lane_scratch(n_motors)


def compile_split(arrays: tuple) -> tuple[list[tuple[Any, tuple]], list[tuple[Any, tuple]]]:
    """The large compiled functions a driver calls, with their argument types for ``arrays``
    (the fields of an :class:`EngineView`), in two independent lists: the plant's inner
    samples and the firmware (``jvl_gym.engine.two_cores``)."""
    view = EngineView(*arrays)
    inner = [(inner_samples, (typeof(view.state), types.int64, types.int64,
                              typeof(view.scratch[0])))]
    outer = [(outer_firmware, (typeof(view.regs[0]), typeof(view.state[0]),
                               typeof(view.params[0]), typeof(view.inputs[0]),
                               typeof(view.buf[0]), types.boolean))]
    return inner, outer


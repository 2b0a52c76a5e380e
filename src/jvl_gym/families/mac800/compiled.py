"""The MAC800 family's compiled step, as the engine's driver calls it
(:mod:`jvl_gym.engine.driver`): ``outer_sample`` per motor, ``inner_block`` per block of
:data:`LANES` motors."""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit, typeof, types

from ...engine.view import EngineView, record_rows, take_planned_inputs
from .inner import LANES, inner_samples, lane_scratch
from .kernel import outer_firmware

__all__ = ["LANES", "outer_sample", "inner_block", "compile_split", "scratch"]


@njit(cache=True, inline="always")
def outer_sample(view: EngineView, i: int, t: int) -> None:  # pragma: no cover - compiled
    """Steps 1–3 of a servo sample (``mac800.kernel``) of motor ``i``; a non-empty world-input
    plan's row ``t`` sets the motor's inputs first."""
    take_planned_inputs(view, i, t)
    inputs = view.inputs
    b = record_rows(view, i)
    outer_firmware(view.regs[i], view.state[i], view.params[i], inputs[i], view.keys[i], b,
                   view.rec)


@njit(cache=True, inline="always")
def inner_block(view: EngineView, i0: int, n: int, blk: int) -> None:  # pragma: no cover
    """The fifteen current-loop samples of motors ``i0 … i0 + n − 1`` (block ``blk``)."""
    inner_samples(view.regs, view.state, view.params, view.inputs, view.buf, view.rec, i0, n,
                  view.scratch[blk])


def scratch(n_motors: int) -> np.ndarray:
    """Working memory of the blocks of ``n_motors`` motors (``view.scratch``)."""
    return lane_scratch(n_motors)


def compile_split(arrays: tuple) -> tuple[list[tuple[Any, tuple]], list[tuple[Any, tuple]]]:
    """The large compiled functions a driver calls, with their argument types for ``arrays``
    (the fields of an :class:`EngineView`), in two independent lists: the current-loop samples
    and the servo sample's firmware (``jvl_gym.engine.two_cores``)."""
    view = EngineView(*arrays)
    inner = [(inner_samples, (typeof(view.regs), typeof(view.state), typeof(view.params),
                              typeof(view.inputs), typeof(view.buf), types.boolean, types.int64,
                              types.int64, typeof(view.scratch[0])))]
    outer = [(outer_firmware, (typeof(view.regs[0]), typeof(view.state[0]),
                               typeof(view.params[0]), typeof(view.inputs[0]),
                               typeof(view.keys[0]), typeof(view.buf[0]), types.boolean))]
    return inner, outer


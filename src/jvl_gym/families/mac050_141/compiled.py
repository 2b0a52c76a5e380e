"""The MAC050–141 family's compiled step, as the engine's driver calls it.

:func:`outer_sample` and :func:`inner_block` are bound into the templates of
:mod:`jvl_gym.engine.driver`; :func:`compile_split` lists the block's inner samples and the
outer firmware, which the engine compiles on their own before a driver that calls them is
compiled (compiled inside a caller's compilation, numba takes several times as long), the two
halves on two cores on a cold start (``jvl_gym.engine.two_cores``). The inner half also holds
the compiled register store of a batched write (``store.store_rows`` and the conversion
``raws_of_rows``), which an env's first reset needs: the second process has time for it while
this one compiles the outer firmware.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit, typeof, types

from ...engine.view import EngineView, record_rows, take_planned_inputs
from ...registers.formats import raws_of_rows
from .inner import inner_samples_one
from .kernel import outer_firmware
from .lanes import LANES, inner_samples, lane_samples_coupled, lane_samples_rigid, lane_scratch
from .store import store_rows

__all__ = ["LANES", "outer_sample", "inner_block", "compile_split", "scratch"]


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


def compile_split(arrays: tuple) -> tuple[list[tuple[Any, tuple]], list[tuple[Any, tuple]]]:
    """The large compiled functions a driver calls, with their argument types for ``arrays``
    (the fields of an :class:`EngineView`), in two independent lists ``(inner, outer)``: the
    inner samples (the one-motor path, the two lane loops, the block's samples, in the order
    they are compiled) and the register store of a batched write (module docstring), and the
    outer firmware (``jvl_gym.engine.two_cores``)."""
    view = EngineView(*arrays)
    rec = types.boolean
    regs, state, params = typeof(view.regs[0]), typeof(view.state[0]), typeof(view.params[0])
    inputs, key, buf, fmt = (typeof(view.inputs[0]), typeof(view.keys[0]),
                             typeof(view.buf[0]), typeof(view.fmt))
    row = typeof(view.scratch[0])
    inner = [(inner_samples_one, (regs, state, params, inputs, key, buf, rec, fmt, row,
                                  types.int64)),
             *[(lanes, (row, types.int64, regs, state, params, inputs, key, buf, rec, fmt))
               for lanes in (lane_samples_rigid, lane_samples_coupled)],
             (inner_samples, (typeof(view.regs), typeof(view.state), typeof(view.params),
                              typeof(view.inputs), typeof(view.keys), typeof(view.buf), rec,
                              fmt, types.int64, types.int64, row)),
             *_store_functions(view)]
    return inner, [(outer_firmware, (regs, state, params, inputs, key, buf, rec, fmt))]


def _store_functions(view: EngineView) -> list[tuple[Any, tuple]]:
    """The compiled register store of ``MotorArray.write_many`` with its argument types: the
    conversion of (K, M) values and the store of (K, M) integers into motor rows ``idx``."""
    index, flags = typeof(np.empty(1, dtype=np.int64)), typeof(np.empty(1, dtype=np.bool_))
    table, raws = typeof(np.empty((1, 1))), typeof(np.empty((1, 1), dtype=np.int64))
    return [(raws_of_rows, (table, table, raws)),
            (store_rows, (typeof(view.regs), typeof(view.state), index, index, flags, raws))]

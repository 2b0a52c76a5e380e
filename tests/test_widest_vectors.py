"""``engine.jit.widest_vectors``: a lane loop vectorised with the machine's widest registers,
the same bits as without."""

import numpy as np
import pytest
from llvmlite import binding as ll
from numba import njit

from jvl_gym.engine.jit import LANE_KERNEL, WIDEST_VECTOR_BITS, widest_vectors

ATTRIBUTE = f'"prefer-vector-width"="{WIDEST_VECTOR_BITS}"'


def _lanes_wide(x, y, a):  # pragma: no cover - compiled
    for j in range(x.shape[0]):
        y[j] = a * x[j] + y[j] / (1.0 + x[j] * x[j])


def _lanes_default(x, y, a):  # pragma: no cover - compiled
    for j in range(x.shape[0]):
        y[j] = a * x[j] + y[j] / (1.0 + x[j] * x[j])


OPTIONS = {**LANE_KERNEL, "cache": False}
wide = widest_vectors(njit(**OPTIONS)(_lanes_wide))
default = njit(**OPTIONS)(_lanes_default)


def _run(fn, seed):
    rng = np.random.default_rng(seed)
    x = rng.normal(0.0, 1e3, 37)
    y = rng.normal(0.0, 1.0, 37)
    fn(x, y, 0.1 + seed)
    return y


def test_only_the_decorated_function_gets_the_width_attribute():
    _run(wide, 0)
    _run(default, 0)
    assert ATTRIBUTE in next(iter(wide.inspect_llvm().values()))
    assert "prefer-vector-width" not in next(iter(default.inspect_llvm().values()))


@pytest.mark.parametrize("seed", range(4))
def test_the_same_bits_as_the_default_width(seed):
    assert _run(wide, seed).tobytes() == _run(default, seed).tobytes()


@pytest.mark.skipif(not ll.get_host_cpu_features().get("avx512f", False),
                    reason="the machine has no 512-bit registers")
def test_the_loop_runs_in_512_bit_registers():
    _run(wide, 0)
    assert "zmm" in next(iter(wide.inspect_asm().values()))


def test_a_compiled_function_is_refused():
    fn = njit(**OPTIONS)(lambda x: x + 1.0)
    fn(1.0)
    with pytest.raises(ValueError, match="compiled already"):
        widest_vectors(fn)

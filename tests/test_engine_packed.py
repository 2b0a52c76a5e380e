"""Arguments packed once for compiled code (``jvl_gym.engine.packed``): inside compiled code
:func:`unpack` gives back arrays of the numba types the originals had, reading and writing the
originals' memory, and integers and bools as their values; the packing refuses what it cannot
pack, works through the machine code's own entry, and is what an env's compiled step takes,
packed once and packed anew for new arrays or an unpickled env."""

from __future__ import annotations

import math
import pickle
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit, typeof
from numba.core import types
from numba.extending import intrinsic

import jvl_gym  # noqa: F401  (registers the envs)
from jvl_gym.engine.entry import entry_point
from jvl_gym.engine.packed import PackedArguments, PackedType, unpack

#: the numba types :func:`_type_id` was compiled for, by the ids it returns
_SEEN: list[types.Type] = []


@intrinsic
def _type_id(typingctx: Any, value: types.Type) -> Any:  # pragma: no cover - compiled
    """The index in :data:`_SEEN` of the numba type compiled code has for ``value``."""

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        kind = signature.args[0]
        if kind not in _SEEN:
            _SEEN.append(kind)
        return context.get_constant(types.int64, _SEEN.index(kind))

    return types.int64(value), codegen


@njit(cache=False, _nrt=False)
def _round_trip(packed: PackedArguments) -> tuple:  # pragma: no cover - compiled
    """Types and values of ``(a, b, flag, n, (c, d))`` unpacked, after writes through them:
    ``a`` 3d, ``b`` 2d, ``c`` records with fields ``p``, ``q``, ``d`` 1d (read only)."""
    a, b, flag, n, (c, d) = unpack(packed)
    ids = (_type_id(a), _type_id(b), _type_id(flag), _type_id(n), _type_id(c), _type_id(d))
    reads = (a[1, 2, 3], b[4, 2], c[2].q, d[1])
    a[0, 1, 2] = n
    b[1, 1] = 100.5
    c[0].p = 2.5
    if flag:
        c[1].q = -1.0
    return ids, reads, flag, n


@njit(cache=False, _nrt=False)
def _total_last_and_copy(packed: PackedArguments, write: bool) -> tuple:  # pragma: no cover
    """Type id, shape, strides and item size, sum (float, in C order) and last element of
    ``x`` in ``(x, (y,))`` unpacked, and ``y``; with ``write`` the first element of ``x`` is
    set to its second."""
    x, (y,) = unpack(packed)
    total = 0.0
    last = x.flat[0]
    for v in x.flat:
        total += v
        last = v
    if write:
        x.flat[0] = x.flat[1]
    return _type_id(x), (x.shape, x.strides, x.itemsize), total, last, y


@njit(cache=False, _nrt=False)
def _scalars(packed: PackedArguments) -> tuple:  # pragma: no cover - compiled
    return unpack(packed)


@njit(cache=False, _nrt=False)
def _weighted(packed: PackedArguments, k: float) -> float:  # pragma: no cover - compiled
    """``k * scale * sum(x)`` for ``(x, scale)`` unpacked, after adding 1 to ``x[0]``."""
    x, scale = unpack(packed)
    x[0] += 1.0
    total = 0.0
    for v in x:
        total += v
    return k * scale * total


@njit(cache=False, _nrt=False)
def _copy_into(packed: PackedArguments, out: np.ndarray) -> int:  # pragma: no cover - compiled
    """Copy the one array of ``packed`` element by element into ``out`` (C-contiguous, of its
    shape); the type id of the unpacked array."""
    (x,) = unpack(packed)
    for i, v in enumerate(x.flat):
        out.flat[i] = v
    return _type_id(x)


def _record(n: int) -> np.ndarray:
    rec = np.zeros(n, dtype=np.dtype([("p", "f8"), ("q", "f8")]))
    rec["p"] = np.arange(n) + 0.25
    rec["q"] = -np.arange(n) - 0.5
    return rec


def _readonly(x: np.ndarray) -> np.ndarray:
    x.setflags(write=False)
    return x


def test_unpacked_arrays_have_the_original_types_read_their_values_and_write_their_memory() -> None:
    """Inside compiled code the members of ``(a, b, flag, n, (c, d))`` have the numba types of
    the originals (a 3d C array, a strided 2d slice, a bool, an int, a record array, a read-only
    int8 array), read the originals' values, and writes through them change the originals."""
    a = np.arange(24.0).reshape(2, 3, 4)
    base = np.arange(30.0).reshape(5, 6)
    b = base[:, ::2]
    c = _record(3)
    d = _readonly(np.array([5, -7, 9], dtype=np.int8))
    args = (a, b, True, -3, (c, d))
    expected_a, expected_base, expected_c = a.copy(), base.copy(), c.copy()

    ids, reads, flag, n = _round_trip(PackedArguments(args))

    assert [_SEEN[i] for i in ids] == [typeof(v) for v in (a, b, True, -3, c, d)]
    assert typeof(b).layout == "A" and not typeof(d).mutable and not typeof(c).aligned
    assert reads == (a[1, 2, 3], b[4, 2], c[2]["q"], d[1]) == (23.0, 28.0, -2.5, -7)
    assert flag is True and n == -3
    expected_a[0, 1, 2] = -3
    expected_base[1, 2] = 100.5  # b[1, 1] is the base's column 2
    expected_c[0]["p"] = 2.5
    expected_c[1]["q"] = -1.0
    np.testing.assert_array_equal(a, expected_a)
    np.testing.assert_array_equal(base, expected_base)
    np.testing.assert_array_equal(c, expected_c)
    np.testing.assert_array_equal(d, [5, -7, 9])


_KINDS = {
    "1d": lambda: np.arange(5.0) + 0.5,
    "2d": lambda: np.arange(12.0).reshape(3, 4),
    "3d": lambda: np.arange(24.0).reshape(2, 3, 4) - 7.0,
    "strided": lambda: np.arange(30.0).reshape(5, 6)[:, ::2],
    "fortran": lambda: np.asfortranarray(np.arange(12.0).reshape(3, 4)),
    "record column": lambda: _record(4)["q"],
    "int8": lambda: np.array([-128, 127, -1, 3], dtype=np.int8),
    "uint64": lambda: np.array([7, 2**63 + 5, 2**64 - 1], dtype=np.uint64),
    "bool": lambda: np.array([False, True, True, False]),
}


@pytest.mark.parametrize("kind", sorted(_KINDS))
@pytest.mark.parametrize("readonly", [False, True])
def test_an_unpacked_array_of_each_kind_is_the_original(kind: str, readonly: bool) -> None:
    """Each kind of array (C 1d/2d/3d, strided, Fortran, a record's column, int8, uint64,
    bool; writable or read only) is unpacked with its own numba type, shape, strides and item
    size, reads the original's elements in C order, and a write through it (when writable)
    changes the original; a second member packed after it is unpacked too."""
    x = _KINDS[kind]()
    if readonly:
        _readonly(x)
    before = x.copy()

    tid, geometry, total, last, y = _total_last_and_copy(PackedArguments((x, (41,))),
                                                         not readonly)

    assert _SEEN[tid] == typeof(x)
    assert geometry == (x.shape, x.strides, x.itemsize)
    assert _SEEN[tid].mutable is not readonly
    assert total == sum(float(v) for v in before.flat)  # the same additions in the same order
    assert last == before.flat[-1] and type(last) is type(before.flat[-1].item())
    assert y == 41
    expected = before.copy()
    if not readonly:
        expected.flat[0] = before.flat[1]
    np.testing.assert_array_equal(x, expected)
    assert x.flat[0] != before.flat[0] or readonly


def test_a_record_column_is_written_in_its_record_array() -> None:
    """A write through an unpacked column of a record array lands in the record array."""
    rec = _record(4)
    _total_last_and_copy(PackedArguments((rec["q"], (0,))), True)
    np.testing.assert_array_equal(rec["q"], [-1.5, -1.5, -2.5, -3.5])
    np.testing.assert_array_equal(rec["p"], [0.25, 1.25, 2.25, 3.25])


def test_integers_and_bools_are_packed_as_their_values() -> None:
    """Bools, negative and extreme int64 values, a small int and a uint64 come back unchanged
    (bools as bools)."""
    values = (True, False, -7, 2**63 - 1, -(2**63), np.int8(-3), np.uint64(2**63 - 1),
              np.bool_(True))
    out = _scalars(PackedArguments(values))
    assert out == (True, False, -7, 2**63 - 1, -(2**63), -3, 2**63 - 1, True)
    assert [type(v) for v in out] == [bool, bool, int, int, int, int, int, bool]


def test_integers_are_their_values_when_packed_not_when_called() -> None:
    """An integer is packed as its value at packing: the same packed arguments give the same
    value whatever the variable it came from is bound to later."""
    n = 5
    packed = PackedArguments((n, np.zeros(1)))
    n = 6
    assert _scalars(packed)[0] == 5 and n == 6


@pytest.mark.parametrize(("value", "named"), [
    (1.5, "float64"), ("text", "unicode_type"), ([1, 2], "list"), (None, "none"),
    ((np.zeros(2), (3, 0.5)), "float64"), (object(), "object"), ({}, "dict"),
])
def test_packing_refuses_what_is_not_an_array_integer_bool_or_tuple(value: Any,
                                                                    named: str) -> None:
    """A float, a string, a list, None, a tuple holding a float, or what numba cannot type is
    refused with a TypeError that says what is taken and names the refused type."""
    with pytest.raises(TypeError, match=r"takes arrays, integers, bools and tuples of them, "
                                        rf"not .*{named}"):
        PackedArguments((np.zeros(3), value))


def test_the_numba_type_is_a_packed_type_of_the_arguments_types() -> None:
    """``numba_type`` is a :class:`PackedType` whose members are ``typeof`` of the arguments
    tuple; numba types the object by it; arguments of the same types give an equal type (one
    compilation), of another layout a different one; the arguments are kept, not copied."""
    x, y = np.arange(4.0), np.arange(6.0).reshape(2, 3)
    args = (x, 3, (y, False))
    packed = PackedArguments(args)
    assert isinstance(packed.numba_type, PackedType)
    assert packed.numba_type.members == typeof(args)
    assert typeof(packed) == packed.numba_type
    assert packed.args[0] is x and packed.args[2][0] is y
    same = PackedArguments((np.ones(9), -1, (np.zeros((4, 4)), True)))
    assert same.numba_type == packed.numba_type
    other = PackedArguments((x, 3, (y[:, ::2], False)))
    assert other.numba_type != packed.numba_type


def test_the_machine_code_entry_gives_the_dispatchers_result() -> None:
    """Called through its own entry (``entry_point``), the compiled function gives what the
    dispatcher gives, for the packed arguments it was taken with and for others of the same
    types, and writes the arrays those pack."""
    x, z = np.arange(4.0), np.arange(4.0)
    packed, twin = PackedArguments((x, 3)), PackedArguments((z, 3))
    assert _weighted(packed, 2.0) == _weighted(twin, 2.0) == 2.0 * 3 * 7.0
    entry = entry_point(_weighted, (packed, 2.0))
    assert entry is not _weighted
    assert entry(packed, 2.0) == _weighted(twin, 2.0) == 2.0 * 3 * 8.0
    np.testing.assert_array_equal(x, z)
    y, w = np.full(3, 2.0), np.full(3, 2.0)
    assert entry(PackedArguments((y, -1)), 0.5) == _weighted(PackedArguments((w, -1)),
                                                             0.5) == -3.5
    np.testing.assert_array_equal(y, [3.0, 2.0, 2.0])


@st.composite
def _strided_arrays(draw: Any) -> np.ndarray:
    """An array of 1-3 dimensions of 0-5 elements each, float64, int64 or float32, each
    dimension taken with step 1 or 2 from a larger array."""
    dtype = draw(st.sampled_from([np.float64, np.int64, np.float32]))
    shape = draw(st.lists(st.integers(0, 5), min_size=1, max_size=3))
    steps = draw(st.lists(st.sampled_from([1, 2]), min_size=len(shape), max_size=len(shape)))
    full = [n * k for n, k in zip(shape, steps)]
    base = (np.arange(math.prod(full)) - 17).astype(dtype).reshape(full)
    return base[tuple(slice(None, None, k) for k in steps)]


@settings(max_examples=30, deadline=None)
@given(_strided_arrays())
def test_any_strided_array_is_unpacked_equal_to_the_original(x: np.ndarray) -> None:
    """An array of any shape, steps and dtype is unpacked with its numba type and copied
    element by element into an array passed as a plain argument: the copy equals it."""
    out = np.full(x.shape, 99, dtype=x.dtype)
    tid = _copy_into(PackedArguments((x,)), out)
    assert _SEEN[tid] == typeof(x)
    np.testing.assert_array_equal(out, x)


def _env() -> Any:
    env = gym.make("jvl_gym/Positioning-v0").unwrapped
    env.reset(seed=5)
    return env


def _actions(n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(1)
    return [rng.uniform(-1, 1, 1).astype(np.float32) for _ in range(n)]


def test_an_env_packs_its_step_arguments_once_and_anew_for_new_arrays() -> None:
    """An env's compiled step takes one :class:`PackedArguments` of the motors', episode's and
    task's arrays themselves, the same object step after step (and after a reset); the motors'
    state bound anew is packed anew, and the env steps on as one that kept its arrays."""
    env, ref = _env(), _env()
    actions = _actions(8)
    for a in actions[:2]:
        env.step(a)
        ref.step(a)
    core = env.core
    head = core._step_head
    assert isinstance(head, tuple) and len(head) == 1
    packed = head[0]
    assert isinstance(packed, PackedArguments)
    view = core.motors.engine_view()
    mine = (*view, *core._episode, core._task_args)
    assert len(packed.args) == len(mine)
    assert all(p is m for p, m in zip(packed.args, mine))
    env.step(actions[2])
    ref.step(actions[2])
    assert core._step_head[0] is packed

    old = core.motors.state
    core.motors.state = old.copy()  # bound anew after steps with the old array
    left = old.copy()
    for a in actions[3:]:
        out, want = env.step(a), ref.step(a)
        np.testing.assert_array_equal(out[0], want[0])
        assert out[1:4] == want[1:4]
    assert core._step_head[0] is not packed
    assert core._step_head[0].args[1] is core.motors.state
    np.testing.assert_array_equal(old, left)  # the old array was left behind
    assert not np.array_equal(core.motors.state, left)


def test_an_unpickled_env_packs_its_own_arrays_and_steps_like_the_original() -> None:
    """A pickled and unpickled env starts without packed arguments, packs its own arrays (not
    the original's) at its first step, and steps to the same observations and rewards as the
    original for the same actions."""
    env = _env()
    actions = _actions(10)
    for a in actions[:4]:
        env.step(a)
    clone = pickle.loads(pickle.dumps(env))
    assert clone.core._step_head == ()
    for a in actions[4:]:
        out, want = clone.step(a), env.step(a)
        np.testing.assert_array_equal(out[0], want[0])
        assert out[1:4] == want[1:4]
    mine, theirs = clone.core._step_head[0], env.core._step_head[0]
    assert mine is not theirs
    assert mine.args[1] is clone.core.motors.state
    assert not np.shares_memory(mine.args[1], theirs.args[1])
    np.testing.assert_array_equal(clone.core.motors.state, env.core.motors.state)


@njit(cache=False, _nrt=False)
def _zero_dim_and_unsigned(packed: PackedArguments) -> tuple:  # pragma: no cover - compiled
    x, big, y = unpack(packed)
    x[()] = 7.0
    return big, y[0]


def test_a_zero_dim_array_and_a_full_range_uint64_are_packed() -> None:
    """A 0-d array is unpacked as one (and written in place); a uint64 above the int64 range is
    its value."""
    x, y = np.array(5.0), np.arange(3.0)
    assert _zero_dim_and_unsigned(PackedArguments((x, np.uint64(2**64 - 1), y))) == (
        2**64 - 1, 0.0)
    assert x[()] == 7.0


def test_a_copy_packs_its_own_arrays() -> None:
    """A pickled or copied PackedArguments points at its own arrays, not at the original's."""
    x, y = np.array(5.0), np.arange(3.0)
    packed = PackedArguments((x, np.uint64(1), y))
    copied = pickle.loads(pickle.dumps(packed))
    copied.args[2][0] = 9.0
    assert _zero_dim_and_unsigned(copied) == (1, 9.0)
    assert copied.args[0][()] == 7.0 and x[()] == 5.0 and y[0] == 0.0

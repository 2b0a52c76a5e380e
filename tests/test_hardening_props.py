"""Property-based: any input to the public write/read/index API, to the flash image,
to config and setup loading and to record loading either does exactly what it says or raises a
documented error; after an error every register, the flash and the state are bit-identical to
before. (Small example counts: these run in the normal suite; the kernel is not stepped.)"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from tuning.models import MotorData
from tuning.records import Record, RecordError, load_csv, save_csv, simulate_testu

from jvl_gym import MotorArray
from jvl_gym.families.config import ConfigError
from jvl_gym.families.mac050_141.config import MOTORS_DIR, MotorConfig, load_motor, load_setup
from jvl_gym.families.mac050_141.firmware import write_rules as W
from jvl_gym.families.mac050_141.table import TABLE as MAC050_141
from jvl_gym.registers import Access, Format, RegisterError
from jvl_gym.registers.formats import round_half_away

N = 3


def whole_only(reg) -> bool:
    """The documented rule: a Word/Integer/LongInt register without a unit holds a code."""
    return reg.scale == 1 and not reg.unit

SETTINGS = settings(max_examples=40, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.function_scoped_fixture,
                                           HealthCheck.too_slow])

#: registers whose store is the value itself (no mode change, pointer copy or write rule)
PLAIN = [r for r in MAC050_141 if r.access == Access.RW and r.format != Format.LONGINT_HIGH
         and r.name not in ("MODE_REG", "CNTRL_BITS", "GEARF2", "HOME_MODE", "ERR_STAT")
         and r.number not in W.POINTERS and r.number not in W.COIL_REGS]
ANY_REG = [r for r in MAC050_141 if r.access != Access.RESERVED]

_M = MotorArray("MAC140", n=N, seed=0)


def _fresh() -> MotorArray:
    m = MotorArray.__new__(MotorArray)
    m.__dict__.update({k: (v.copy() if isinstance(v, np.ndarray) else v)
                       for k, v in _M.__dict__.items()})
    m._plans = {}
    return m


def _snapshot(m: MotorArray) -> tuple:
    return (m.regs.copy(), m.state.copy(), m.params.copy(), m.inputs.copy(),
            None if m._flash is None else m._flash.copy(), m._has_flash.copy())


def _identical(m: MotorArray, before: tuple) -> None:
    for a, b in zip(before, _snapshot(m)):
        assert (a is None) == (b is None)
        if a is not None:
            assert a.dtype == b.dtype and a.shape == b.shape
            assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f")


scalars = st.one_of(
    st.none(), st.booleans(), st.integers(-2**70, 2**70), st.floats(allow_nan=True),
    st.complex_numbers(max_magnitude=1e6), st.text(max_size=4), st.binary(max_size=3),
    st.sampled_from([np.uint64(2**64 - 1), np.int8(-3), np.float32(1.5), np.bool_(True),
                     np.complex64(1), 0.5, 1.5, -0.5, 2**63, -(2**63) - 1]))
arrays = hnp.arrays(st.sampled_from([np.int64, np.uint8, np.uint64, np.float64, np.float32,
                                     np.bool_, np.complex128]),
                    st.sampled_from([(), (N,), (1,), (N, 1), (2,)]),
                    elements={"allow_nan": True} if False else None)
values = st.one_of(scalars, arrays, st.lists(st.integers(-5, 70000), min_size=0, max_size=4))
indices = st.one_of(
    st.none(), st.integers(-6, 6), st.booleans(), st.floats(-3, 3), st.text(max_size=2),
    st.lists(st.integers(-4, 4), max_size=4), st.lists(st.booleans(), min_size=N, max_size=N),
    hnp.arrays(st.sampled_from([np.int64, np.uint64, np.float64, np.bool_, np.int8]),
               st.sampled_from([(), (1,), (2,), (N,), (1, 2)])),
    st.builds(slice, st.one_of(st.none(), st.integers(-4, 4)),
              st.one_of(st.none(), st.integers(-4, 4)),
              st.one_of(st.none(), st.sampled_from([1, 2, -1]))),
    st.sampled_from([np.uint64(2**64 - 1), np.int32(1), 1.0, 1 + 0j, [0.5], [None]]))


def _selected(index) -> list[int] | None:
    """The motors a valid ``index`` selects (numpy semantics), None if it is not valid."""
    if index is None:
        return list(range(N))
    if isinstance(index, slice):
        return list(range(N))[index]
    if isinstance(index, (bool, np.bool_, float, complex, str, bytes, np.floating)):
        return None
    if isinstance(index, (int, np.integer)):
        return [int(index) % N] if -N <= int(index) < N else None
    try:
        arr = np.asarray(index)
    except (TypeError, ValueError):
        return None
    if arr.dtype == np.bool_:
        return np.flatnonzero(arr).tolist() if arr.shape == (N,) else None
    if arr.size == 0 and arr.ndim == 1:
        return []
    if arr.dtype.kind not in "iu" or arr.ndim > 1:
        return None
    ks = [int(k) for k in arr.reshape(-1)]
    if any(not -N <= k < N for k in ks):
        return None
    ks = [k % N for k in ks]
    return ks if len(set(ks)) == len(ks) else None


def _expected_raws(reg, value, count: int) -> np.ndarray | None:
    """The stored integers the documented conversion gives, None if the value is refused."""
    if isinstance(value, (bool, np.bool_, str, bytes, complex, np.complexfloating)) or (
            value is None):
        return None
    if type(value) is int and abs(value) >= 2**63:
        return None
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError):
        return None
    if arr.dtype.kind not in "iuf" or arr.ndim > 1 or (arr.ndim == 1 and arr.shape != (count,)):
        return None
    # a scalar is checked as given, also when no motor is selected
    v = arr.astype(np.float64).reshape(-1)
    lo = min(reg.minimum, reg.raw_min / reg.scale)
    hi = max(reg.maximum, reg.raw_max / reg.scale)
    if not np.all(np.isfinite(v)) or np.any(v < lo) or np.any(v > hi):
        return None
    if whole_only(reg) and np.any(v != np.floor(v)):
        return None
    v = np.broadcast_to(v if arr.ndim else v[0], (count,))
    return np.clip(round_half_away(v * reg.scale), reg.raw_min, reg.raw_max).astype(np.int64)


@SETTINGS
@given(reg=st.sampled_from(PLAIN), value=values, index=indices)
def test_write_does_what_it_says_or_changes_nothing(reg, value, index):
    m = _fresh()
    before = _snapshot(m)
    sel = _selected(index)
    want = None if sel is None else _expected_raws(reg, value, len(sel))
    try:
        m.write(reg.name, value, index=index)
    except RegisterError:
        _identical(m, before)
        assert want is None or (sel is not None and len(sel) == 0 and False), (value, index)
        return
    assert sel is not None and want is not None, (reg.name, value, index)
    raw = m.read_raw(reg.number)
    expected = before[0][:, reg.number].copy()
    expected[sel] = want
    assert np.array_equal(raw, expected)
    others = np.ones(m.regs.shape[1], dtype=bool)
    others[reg.number] = False
    assert np.array_equal(m.regs[:, others], before[0][:, others])
    assert np.array_equal(m.state, before[1])


@SETTINGS
@given(reg=st.sampled_from(ANY_REG), value=values, index=indices)
def test_any_register_write_raises_a_register_error_or_stores(reg, value, index):
    m = _fresh()
    before = _snapshot(m)
    try:
        m.write(reg.name, value, index=index)
    except RegisterError:
        _identical(m, before)
        return
    assert _selected(index) is not None
    assert _expected_raws(reg, value, len(_selected(index))) is not None


@SETTINGS
@given(keys=st.lists(st.sampled_from(PLAIN), min_size=1, max_size=4, unique=True),
       data=st.data())
def test_batched_writes_are_all_or_nothing(keys, data):
    m = _fresh()
    before = _snapshot(m)
    vals = {reg.name: data.draw(values) for reg in keys}
    try:
        m.write_many(vals)
    except RegisterError:
        _identical(m, before)
        return
    for reg in keys:
        assert np.array_equal(m.read_raw(reg.number), _expected_raws(reg, vals[reg.name], N))


@SETTINGS
@given(index=indices)
def test_read_and_one_motor_methods_take_integers_only(index):
    m = _fresh()
    before = _snapshot(m)
    one = isinstance(index, (int, np.integer)) and not isinstance(index, (bool, np.bool_))
    valid = one and -N <= int(index) < N
    for method in (m.mode_name, m.flash_image, m.sample_buffer_raw):
        try:
            method(index)
        except RegisterError:
            assert not valid
        else:
            assert valid
    _identical(m, before)


flash_keys = st.one_of(st.sampled_from([r.number for r in ANY_REG]), st.integers(-2, 200),
                       st.text(max_size=3), st.booleans(), st.floats(0, 200))
flash_vals = st.one_of(st.integers(-2**40, 2**40), st.floats(allow_nan=True), st.booleans(),
                       st.text(max_size=2), st.none(), st.integers(-10, 10))


@SETTINGS
@given(index=st.one_of(st.integers(-5, 5), st.floats(-2, 2), st.booleans()),
       image=st.dictionaries(flash_keys, flash_vals, max_size=4), preload=st.booleans())
def test_flash_image_loads_whole_or_not_at_all(index, image, preload):
    m = _fresh()
    if preload:
        m.load_flash_image(0, {13: 1024})
    before = _snapshot(m)
    old = [m.flash_image(i) for i in range(N)]
    try:
        m.load_flash_image(index, image)
    except RegisterError:
        _identical(m, before)
        assert [m.flash_image(i) for i in range(N)] == old
        return
    i = int(index) % N
    assert not isinstance(index, (bool, float))
    got = m.flash_image(i)
    rom = m._rom[m._type_of[i]]
    for num, raw in got.items():
        assert raw == (image[num] if num in image else int(rom[num]))
    assert set(image) <= set(got)
    _identical_regs = np.array_equal(m.regs, before[0]) and np.array_equal(m.state, before[1])
    assert _identical_regs


# ------------------------------------------------------------------ configs and setups
_BASE = yaml.safe_load((MOTORS_DIR / "MAC140.yaml").read_text())
_FIELDS = [k for k in MotorConfig.model_fields if k not in ("provenance",)]
config_values = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.booleans(),
                          st.integers(-10**6, 10**6), st.text(max_size=5), st.none(),
                          st.lists(st.integers(), max_size=2),
                          st.sampled_from(["1e-3", "2.0e-3", ".inf", "nan", "17.3e-6"]))


@SETTINGS
@given(changes=st.dictionaries(st.sampled_from(_FIELDS), config_values, max_size=3))
def test_motor_config_loads_only_finite_typed_values_in_range(changes):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "motor.yaml"
        path.write_text(yaml.safe_dump({**_BASE, **changes}))
        try:
            cfg = load_motor(path)
        except ConfigError as exc:
            assert "motor.yaml" in str(exc)
            return
    for name, field in MotorConfig.model_fields.items():
        value = getattr(cfg, name)
        if field.annotation in (int, float) or name in _FIELDS and isinstance(value, float):
            assert not isinstance(value, bool)
            assert math.isfinite(value)
        for meta in field.metadata:
            for attr, op in (("gt", float.__gt__), ("ge", float.__ge__), ("lt", float.__lt__),
                             ("le", float.__le__)):
                bound = getattr(meta, attr, None)
                if bound is not None:
                    assert op(float(value), float(bound)), (name, value)


setup_values = st.one_of(st.floats(allow_nan=True), st.booleans(), st.integers(-10**6, 10**6),
                         st.text(max_size=4), st.none())
setup_names = st.one_of(st.sampled_from([r.name for r in ANY_REG]), st.text(max_size=6))


@SETTINGS
@given(regs=st.dictionaries(setup_names, setup_values, max_size=3))
def test_setups_load_validated_or_refused(regs):
    try:
        cfg = load_setup(regs)
    except ConfigError:
        return
    assert all(not isinstance(v, bool) and math.isfinite(v) for v in cfg.registers.values())
    try:
        m = MotorArray("MAC140", n=1, setup=regs)
    except RegisterError as exc:
        assert "setup mapping" in str(exc)
        with pytest.raises(RegisterError):
            MotorArray("MAC140", n=1).load_setup(regs)
        return
    ref = MotorArray("MAC140", n=1)
    ref.load_setup(regs)  # the same registers as the constructor's ROM image
    for name in regs:
        assert np.array_equal(m.read_raw(name), ref.read_raw(name))


# ------------------------------------------------------------------ records
_GOOD = simulate_testu(MotorData.from_config("MAC140"), 100, 16)


def _good_lines() -> list[str]:
    with tempfile.TemporaryDirectory() as tmp:
        return save_csv(_GOOD, Path(tmp) / "u.csv").read_text().splitlines()


_LINES = _good_lines()
line_edits = st.lists(st.tuples(st.integers(0, len(_LINES) - 1),
                                st.one_of(st.text(max_size=20),
                                          st.sampled_from(["UA_VAL,UA_VAL,IC_IST",
                                                           "# registers: KIFX2=nan",
                                                           "# registers: X=1", "3,1e400,2",
                                                           "# kind: TESTA", "0,100,0",
                                                           "# rate_hz: nan", "", "1,2"]))),
                      max_size=3)


@SETTINGS
@given(edits=line_edits, reverse=st.booleans(), raw=st.binary(max_size=8))
def test_record_files_load_valid_or_raise_record_error(edits, reverse, raw):
    lines = list(_LINES)
    for k, text in edits:
        lines[k] = text
    if reverse:
        k = lines.index("sample,UA_VAL,IC_IST") + 1 if "sample,UA_VAL,IC_IST" in lines else 0
        lines[k:] = lines[k:][::-1]
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "r.csv"
        path.write_bytes(("\n".join(lines) + "\n").encode("utf-8") + raw)
        try:
            rec = load_csv(path)
        except RecordError as exc:
            assert "r.csv" in str(exc)
            return
    assert isinstance(rec, Record)
    assert np.all(np.isfinite(rec.input)) and np.all(np.isfinite(rec.output))
    assert rec.input.shape == rec.output.shape


@settings(max_examples=30, deadline=None)
@given(motor=st.sampled_from(["MAC140", "MAC800", "MIS232"]),
       value=st.integers(2**63, 2**200) | st.integers(-(2**200), -(2**63) - 1))
def test_an_integer_beyond_64_bits_is_refused_by_its_own_digits(motor: str, value: int) -> None:
    """An int no register can hold is refused with the integer as given (not "inf"), by
    ``write``, ``write_many`` and ``write_raw``; nothing changes."""
    m = _arrays()[motor]
    before = m.read_raw("P_SOLL").copy()
    for write in (lambda: m.write("P_SOLL", value), lambda: m.write_many({"P_SOLL": value}),
                  lambda: m.write_raw("P_SOLL", value)):
        with pytest.raises(RegisterError) as info:
            write()
        assert "inf" not in str(info.value)
    with pytest.raises(RegisterError, match=str(value)):
        m.write("P_SOLL", value)
    np.testing.assert_array_equal(m.read_raw("P_SOLL"), before)


_ARRAYS: dict[str, MotorArray] = {}


def _arrays() -> dict[str, MotorArray]:
    if not _ARRAYS:
        _ARRAYS.update({t: MotorArray(t, n=2, seed=0) for t in ("MAC140", "MAC800", "MIS232")})
    return _ARRAYS

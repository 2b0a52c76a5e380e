"""Behaviour of the register layer: table, lookups, formats (manual 3.1, 3.2)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from jvl_gym.families.mac050_141.table import TABLE as MAC050_141
from jvl_gym.registers import (
    Access,
    Format,
    ReadOnlyRegisterError,
    RegisterError,
    RegisterRangeError,
    RegisterShapeError,
    TableError,
    UnknownRegisterError,
    from_raw,
    from_word16,
    join_longint,
    load_table,
    saturate_raw,
    split_longint,
    to_raw,
    to_word16,
)
from jvl_gym.registers.reference import markdown_reference

T = MAC050_141
HEADER = "number,name,format,min,max,unit,access,default,section,description\n"

# ----------------------------------------------------------------------------- the table


def test_every_number_resolves_to_exactly_one_row():
    assert len(T) == 164
    assert [r.number for r in T] == list(range(1, 165))
    for n in range(1, 165):
        assert T.lookup(n).number == n
        assert n in T


def test_names_unique_and_lookup_round_trip():
    assert len(set(T.names)) == len(T.names) == 164
    for r in T:
        assert T.lookup(r.name) is r
        assert T.lookup(r.name.lower()) is r
        assert T.lookup(r.number) is r


@pytest.mark.parametrize(
    ("name", "number", "fmt"),
    [
        ("MODE_REG", 2, Format.WORD), ("P_SOLL", 3, Format.LONGINT), ("V_SOLL", 5, Format.INTEGER),
        ("A_SOLL", 6, Format.WORD), ("T_SOLL", 7, Format.WORD), ("P_FNC", 8, Format.LONGINT),
        ("P_IST", 10, Format.LONGINT), ("V_IST", 12, Format.INTEGER), ("KVOUT", 13, Format.FIXED8),
        ("GEARF1", 14, Format.INTEGER), ("GEARF2", 15, Format.WORD), ("FLWERR", 20, Format.LONGINT),
        ("FNCERR", 24, Format.LONGINT), ("MAX_P_IST", 30, Format.LONGINT),
        ("ACC_EMERG", 32, Format.WORD), ("ERR_STAT", 35, Format.WORD), ("P1", 49, Format.LONGINT),
        ("P8", 63, Format.LONGINT), ("V1", 65, Format.INTEGER), ("L4", 84, Format.FIXED8),
        ("KFF3", 89, Format.FIXED8), ("KVFX4", 93, Format.FIXED4), ("KVFY0", 100, Format.FIXED4),
        ("GEARB", 101, Format.FIXED8), ("KIFX2", 106, Format.FIXED4), ("KIB0", 111, Format.FIXED8),
        ("SAMPLE1", 112, Format.WORD), ("REC_CNT", 116, Format.WORD),
        ("VF_OUT", 121, Format.INTEGER), ("AMPLITUDE", 127, Format.FIXED8),
        ("IA_SOLL", 133, Format.INTEGER), ("IC_IST", 139, Format.INTEGER),
        ("UA_VAL", 145, Format.INTEGER), ("KIB", 149, Format.WORD), ("U_SUPPLY", 151, Format.WORD),
        ("SERIAL_NMB", 154, Format.LONGINT), ("MYADDR", 156, Format.WORD),
        ("CHKSUM", 158, Format.LONGINT), ("UV_HANDLE", 160, Format.WORD),
        ("INDEX_OFFSET", 162, Format.WORD), ("P_NEW", 163, Format.LONGINT),
    ],
)
@pytest.mark.statements("mac050_141:3.2:1", "mac050_141:3.2.2:35", "mac050_141:3.2.3:4",
                        "mac050_141:3.2.5:14", "mac050_141:3.2.6:15", "mac050_141:3.2.7:17",
                        "mac050_141:3.2.8:11", "mac050_141:3.2.10:5", "mac050_141:3.2.12:5",
                        "mac050_141:3.2.13:2", "mac050_141:3.2.14:4", "mac050_141:3.2.20:6",
                        "mac050_141:3.2.24:7", "mac050_141:3.2.28:4", "mac050_141:3.2.32:3",
                        "mac050_141:3.2.35:19", "mac050_141:3.2.49:2", "mac050_141:3.2.65:2",
                        "mac050_141:3.2.81:2", "mac050_141:3.2.89:2", "mac050_141:3.2.93:3",
                        "mac050_141:3.2.101:2", "mac050_141:3.2.106:3", "mac050_141:3.2.110:2",
                        "mac050_141:3.2.112:3", "mac050_141:3.2.116:4", "mac050_141:3.2.121:3",
                        "mac050_141:3.2.127:4", "mac050_141:3.2.133:2", "mac050_141:3.2.137:2",
                        "mac050_141:3.2.145:2", "mac050_141:3.2.148:3", "mac050_141:3.2.151:2",
                        "mac050_141:3.2.154:2", "mac050_141:3.2.156:3", "mac050_141:3.2.158:2",
                        "mac050_141:3.2.160:4", "mac050_141:3.2.163:4")
def test_manual_numbers_and_formats(name, number, fmt):
    r = T.lookup(name)
    assert (r.number, r.format) == (number, fmt)
    assert r.section == f"3.2.{number}"


@pytest.mark.statements("mac050_141:3.2:2", "mac050_141:3.2.31:1")
def test_longint_rows_are_followed_by_their_high_word():
    for r in T:
        if r.format == Format.LONGINT:
            hi = T.lookup(r.number + 1)
            assert hi.name == f"{r.name}_HI"
            assert hi.format == Format.LONGINT_HIGH
            assert hi.access == r.access
            assert r.words == 2
        else:
            assert r.words == 1
    assert T.lookup(31).name == "MAX_P_IST_HI"  # the manual's "3.2.31 Reserved"


@pytest.mark.statements("mac050_141:3.2.110:2")
def test_kib_is_not_the_filter_coefficient():
    assert T.lookup("KIB").number == 149
    assert T.lookup("KIB1").number == 110
    assert T.lookup("KIB0").number == 111


@pytest.mark.statements("mac050_141:3.2.12:2", "mac050_141:3.2.16:1", "mac050_141:3.2.18:5",
                        "mac050_141:3.2.20:5", "mac050_141:3.2.24:8", "mac050_141:3.2.117:2",
                        "mac050_141:3.2.118:2", "mac050_141:3.2.119:2", "mac050_141:3.2.120:3",
                        "mac050_141:3.2.122:5", "mac050_141:3.2.143:2", "mac050_141:3.2.144:2",
                        "mac050_141:3.2.151:3")
def test_read_only_set():
    ro = {r.name for r in T if r.access == Access.RO and r.format != Format.LONGINT_HIGH}
    expected = {
        "V_IST", "FLWERR", "FNCERR", "I2T", "UIT", "FNC_OUT", "FF_OUT", "VB_OUT", "V_EXT",
        "VF_OUT", "ANINP", "I_NOM", "PHI_SOLL", "IA_SOLL", "IB_SOLL", "IC_SOLL", "IA_IST",
        "IB_IST", "IC_IST", "ELDEG_IST", "V_ELDEG", "UA_VAL", "UB_VAL", "UC_VAL", "U_SUPPLY",
        "MOTOR_TYPE", "SERIAL_NMB", "HW_VERSION", "CHKSUM",
    }
    assert ro == expected
    for name in ("P_IST", "P_FNC", "ERR_STAT", "CNTRL_BITS", "MODE_REG"):
        assert T.lookup(name).access == Access.RW


@pytest.mark.statements("mac050_141:3.2.3:1", "mac050_141:3.2.7:1", "mac050_141:3.2.20:5",
                        "mac050_141:3.2.24:6", "mac050_141:3.2.41:4", "mac050_141:3.2.112:2",
                        "mac050_141:3.2.116:3", "mac050_141:3.2.121:2", "mac050_141:3.2.127:1",
                        "mac050_141:3.2.133:1", "mac050_141:3.2.137:1", "mac050_141:3.2.156:2")
def test_ranges_from_the_manual():
    def rng(name):
        r = T.lookup(name)
        return (r.minimum, r.maximum)

    assert rng("MODE_REG") == (0, 258)
    assert rng("P_SOLL") == (-67e6, 67e6)
    assert rng("FNCERR") == (-134217727, 134217727)
    assert rng("FNCERRMAX") == (0, 134217727)
    assert rng("FLWERRMAX") == (0, 67e6)
    assert rng("T_SOLL") == (0, 1023)
    assert rng("T_HOME") == (-800, 800)
    assert rng("IA_SOLL") == (-850, 850)
    assert rng("IB_IST") == (-1023, 1023)
    assert rng("VF_OUT") == (-1023, 1023)
    assert rng("V_SOLL") == (-32767, 32767)
    assert rng("A_SOLL") == (0, 65535)  # only a "recommended range" in the manual
    assert rng("AMPLITUDE") == (0, 0.83)
    assert rng("SAMPLE3") == (1, 164)
    assert rng("REC_CNT") == (0, 895)
    assert rng("MYADDR") == (1, 254)
    assert rng("P_REG_P") == (0, 8)
    assert rng("Z_REG_P") == (0, 4)
    assert rng("KVOUT") == (-127.996, 127.996)
    assert "1.0..10.0" in T.lookup("KVOUT").description


@pytest.mark.statements("mac050_141:3.2.148:2")
def test_defaults_within_range_and_chosen_values():
    for r in T:
        if r.access != Access.RESERVED:
            assert r.minimum <= r.default <= r.maximum, r.name
            assert r.raw_min <= r.default_raw <= r.raw_max, r.name
    d = {r.name: r.default for r in T}
    assert d["KVOUT"] == 1.0 and d["GEARB"] == 16.0 and d["AMPLITUDE"] == 0.83
    assert d["GEARF1"] == d["GEARF2"] == 1
    assert d["T_SOLL"] == 1023 and d["A_SOLL"] == 160 and d["V_SOLL"] == 0
    assert [d[f"SAMPLE{k}"] for k in range(1, 5)] == [10, 12, 117, 121]
    assert d["KIA"] == d["KIB"] == d["KIC"] == 256
    assert T.lookup("KIFX1").default_raw == -3604  # −0.88·4096 = −3604.48


def test_arrays_indexed_by_number():
    assert T.raw_min_array.shape == T.raw_max_array.shape == T.default_raw_array.shape == (165,)
    assert T.raw_min_array.dtype == np.int64 and T.fmt_code_array.dtype == np.int8
    assert T.raw_max_array[T.lookup("KVOUT").number] == 32767
    assert T.raw_max_array[7] == 1023
    assert T.default_raw_array[13] == 256  # KVOUT 1.0
    assert T.default_raw_array[101] == 4096  # GEARB 16.0
    assert T.raw_min_array[3] == -67_000_000
    assert T.raw_max_array[4] == 0 and T.default_raw_array[4] == 0  # high word rows
    assert list(T.fmt_code_array[:8]) == [0, 1, 1, 3, 4, 2, 1, 1]
    assert T.fmt_code_array[93] == 5 and T.fmt_code_array[89] == 6
    assert T.raw_min_array[0] == T.raw_max_array[0] == 0


def test_register_scale_and_raw_bounds():
    assert T.lookup("KVFX4").scale == 4096
    assert T.lookup("KFF3").scale == 256
    assert T.lookup("V_SOLL").scale == 1
    assert T.lookup("KVFX4").raw_max == 32767 and T.lookup("KVFX4").raw_min == -32767
    assert T.lookup("AMPLITUDE").raw_max == 212  # round(0.83·256 = 212.48)


# ----------------------------------------------------------------------------- lookups


def test_unknown_name_suggests_close_names():
    with pytest.raises(UnknownRegisterError) as info:
        T.lookup("V_SOL")
    msg = str(info.value)
    assert "V_SOL" in msg and "V_SOLL" in msg
    assert isinstance(info.value, KeyError) and isinstance(info.value, ValueError)


@pytest.mark.parametrize("key", [0, 165, 999, -1, "", "NOPE_NOTHING", 3.0, None, True])
def test_unknown_keys(key):
    with pytest.raises(UnknownRegisterError):
        T.lookup(key)
    assert key not in T


def test_lookup_numpy_integer_and_whitespace():
    assert T.lookup(np.int64(12)).name == "V_IST"
    assert T.lookup(" p_soll ").number == 3
    assert "kvout" in T and 164 in T and T.lookup(1) in T


# ----------------------------------------------------------------------------- formats


@pytest.mark.statements("mac050_141:3.1:2", "mac050_141:3.2.93:3")
def test_fixed4_round_trip_extremes():
    r = T.lookup("KVFX4")
    assert int(to_raw(r, 7.999756)) == 32767
    assert int(to_raw(r, -7.999756)) == -32767
    assert float(from_raw(r, 32767)) == pytest.approx(7.999756, abs=1e-6)
    assert float(from_raw(r, -32767)) == pytest.approx(-7.999756, abs=1e-6)
    assert int(to_raw(r, 1 / 4096)) == 1


@pytest.mark.statements("mac050_141:3.1:3", "mac050_141:3.2.89:2")
def test_fixed8_round_trip_and_resolution():
    r = T.lookup("KFF3")
    assert int(to_raw(r, 127.996)) == 32767
    assert int(to_raw(r, -127.996)) == -32767
    assert int(to_raw(r, 32767 / 256)) == 32767  # the exact end, printed "127.996" by the manual
    assert float(from_raw(r, 32767)) == pytest.approx(127.996, abs=1e-3)
    assert int(to_raw(r, 1 / 256)) == 1
    assert float(from_raw(r, 1)) == 1 / 256
    assert from_raw(r, np.array([1, 2])).dtype == np.float64


def test_rounding_half_away_from_zero():
    r = T.lookup("KFF2")
    assert list(to_raw(r, np.array([0.5, -0.5, 1.5, -1.5]) / 256)) == [1, -1, 2, -2]
    v = T.lookup("V_SOLL")
    assert list(to_raw(v, [2.5, -2.5, 2.49])) == [3, -3, 2]
    assert to_raw(v, 5).dtype == np.int64 and from_raw(v, 5).dtype == np.int64


@given(st.integers(-32767, 32767))
def test_fixed_round_trip_is_exact(raw):
    for name in ("KVFY3", "GEARB"):
        r = T.lookup(name)
        assert int(to_raw(r, from_raw(r, raw))) == raw


@given(st.floats(-127.996, 127.996))
def test_fixed8_quantisation_error_is_half_lsb(x):
    r = T.lookup("KVB3")
    assert abs(float(from_raw(r, to_raw(r, x))) - x) <= 0.5 / 256 + 1e-12


def test_small_arrays_convert_like_large_ones():
    """to_raw converts a few values with Python floats, many with numpy: the same integers."""
    from jvl_gym.registers.formats import _SCALAR_MAX, whole_only

    rng = np.random.default_rng(0)
    for r in T:
        if r.access == Access.RESERVED:
            continue
        lo, hi = min(r.minimum, r.raw_min / r.scale), max(r.maximum, r.raw_max / r.scale)
        edges = [lo, hi, 0.0, -0.0, (r.raw_min + 0.5) / r.scale, (r.raw_max - 0.5) / r.scale,
                 np.nextafter(hi, -np.inf), np.nextafter(lo, np.inf)]
        values = np.clip(np.concatenate([edges, rng.uniform(lo, hi, 4 * _SCALAR_MAX),
                                         np.round(rng.uniform(lo, hi, 64)) + 0.5]), lo, hi)
        if whole_only(r):  # codes take whole numbers only
            values = np.clip(np.round(values), lo, hi)
        numpy_path = to_raw(r, values)  # more than _SCALAR_MAX values
        assert values.size > _SCALAR_MAX
        for k in range(0, values.size, _SCALAR_MAX):
            chunk = values[k:k + _SCALAR_MAX]
            assert np.array_equal(to_raw(r, chunk), numpy_path[k:k + _SCALAR_MAX]), r.name
        for x, raw in zip(values[:8], numpy_path[:8]):
            out = to_raw(r, x)
            assert out.shape == () and out.dtype == np.int64 and int(out) == raw, r.name


@pytest.mark.parametrize(
    ("name", "value"),
    [("T_SOLL", 1024), ("T_SOLL", -1), ("KVOUT", 200.0), ("KVFX4", 8.0), ("AMPLITUDE", 0.84),
     ("T_HOME", 801), ("P_SOLL", 67_000_001), ("MYADDR", 0), ("MODE_REG", 259),
     ("V_SOLL", float("nan")), ("V_SOLL", float("inf")), ("KFF0", -math.inf)],
)
@pytest.mark.statements("mac050_141:3.2.127:3")
def test_range_errors_name_register_range_and_section(name, value):
    r = T.lookup(name)
    with pytest.raises(RegisterRangeError) as info:
        to_raw(r, value)
    msg = str(info.value)
    assert r.name in msg and str(r.number) in msg and r.section in msg
    assert "range" in msg and (r.unit in msg)


def test_range_error_for_arrays_and_unit_in_message():
    r = T.lookup("T_SOLL")
    with pytest.raises(RegisterRangeError, match="1/1023 peak torque"):
        to_raw(r, np.array([0, 500, 2000]))
    assert list(to_raw(r, np.array([[0, 1023]]))[0]) == [0, 1023]
    with pytest.raises(RegisterRangeError):
        to_raw(r, "abc")


def test_reserved_and_high_word_rows():
    hi = T.lookup("P_SOLL_HI")
    assert int(to_raw(hi, 0xFFFF)) == 0xFFFF
    with pytest.raises(RegisterRangeError):
        to_raw(hi, 0x10000)


def test_saturate_raw():
    vf = T.lookup("VF_OUT")
    assert list(saturate_raw(vf, [2000.0, -5000.0, 10.5, -10.5, np.nan])) == [1023, -1023, 11,
                                                                                -11, 0]
    assert int(saturate_raw(T.lookup("KVFX1"), 100.0)) == 32767
    assert int(saturate_raw(T.lookup("KVFX1"), -np.inf)) == -32767
    assert int(saturate_raw(T.lookup("FNC_OUT"), 1e12)) == 32767
    assert int(saturate_raw(T.lookup("GEARB"), 16.0)) == 4096
    assert saturate_raw(vf, np.zeros((2, 3))).shape == (2, 3)


@pytest.mark.statements("mac050_141:3.1:1")
def test_split_join_longint():
    assert split_longint(-1) == (0xFFFF, 0xFFFF)
    assert split_longint(0x00054711) == (0x4711, 0x0005)
    assert join_longint(0x4711, 0x0005) == 0x00054711
    assert join_longint(0xFFFF, 0xFFFF) == -1
    assert join_longint(0, 0x8000) == -(2**31)
    assert split_longint(-67_000_000) == ((-67_000_000) & 0xFFFF, ((-67_000_000) >> 16) & 0xFFFF)
    lo, hi = split_longint(np.array([1, -2, 2**31 - 1]))
    np.testing.assert_array_equal(join_longint(lo, hi), [1, -2, 2**31 - 1])
    with pytest.raises(RegisterRangeError):
        split_longint(2**31)
    with pytest.raises(RegisterRangeError):
        join_longint(0x10000, 0)
    with pytest.raises(RegisterShapeError):
        join_longint(np.zeros(2, int), np.zeros(3, int))


@given(st.integers(-(2**31), 2**31 - 1))
def test_split_join_round_trip(x):
    lo, hi = split_longint(x)
    assert 0 <= lo <= 0xFFFF and 0 <= hi <= 0xFFFF
    assert join_longint(lo, hi) == x


@pytest.mark.statements("mac050_141:3.1:1")
def test_word16_mapping():
    v = T.lookup("V_SOLL")
    assert int(to_word16(v, -1)) == 0xFFFF
    assert int(to_word16(v, 0x0547)) == 0x0547
    assert int(from_word16(v, 0xFFFF)) == -1
    f4 = T.lookup("KVFX3")
    assert int(to_word16(f4, -32767)) == 0x8001
    assert int(from_word16(f4, 0x8001)) == -32767
    w = T.lookup("A_SOLL")
    assert int(to_word16(w, 65535)) == 0xFFFF and int(from_word16(w, 0xFFFF)) == 65535
    p = T.lookup("P_SOLL")
    np.testing.assert_array_equal(to_word16(p, 0x00054711), [0x4711, 0x0005])
    np.testing.assert_array_equal(to_word16(p, [-1, 2]), [[0xFFFF, 0xFFFF], [2, 0]])
    assert int(from_word16(p, [0x4711, 0x0005])) == 0x00054711
    with pytest.raises(RegisterShapeError):
        from_word16(p, 0x4711)
    with pytest.raises(RegisterRangeError):
        to_word16(v, 40000)
    with pytest.raises(RegisterRangeError):
        from_word16(v, -1)


@given(st.integers(-32767, 32767))
def test_word16_round_trip_signed(raw):
    r = T.lookup("IA_OFFSET") if raw >= 0 else T.lookup("V_HOME")
    assert int(from_word16(r, to_word16(r, raw))) == raw


# ----------------------------------------------------------------------------- manual examples


@pytest.mark.statements("mac050_141:3.2.13:1")
def test_kvout_worked_example():  # manual 3.2.13: (17.3E-6 + 50E-6)/17.3E-6 = 3.9
    r = T.lookup("KVOUT")
    raw = int(to_raw(r, (17.3e-6 + 50e-6) / 17.3e-6))
    assert raw == 996 and float(from_raw(r, raw)) == pytest.approx(3.9, abs=0.01)


@pytest.mark.statements("mac050_141:4.1.2:8")
def test_p_soll_670_relative_moves():  # manual 4.1.2 with P_SOLL range ±67E6 (3.2.3)
    r = T.lookup("P_SOLL")
    assert int(to_raw(r, 670 * 100_000)) == 67_000_000
    with pytest.raises(RegisterRangeError):
        to_raw(r, 671 * 100_000)


@pytest.mark.statements("mac050_141:3.2.127:1", "mac050_141:3.2.127:2")
def test_amplitude_limits_current_setpoint():  # manual 3.2.127: "1023·0.83 = 850" = IA_SOLL max
    amp = T.lookup("AMPLITUDE")
    assert T.lookup("IA_SOLL").maximum == 850
    assert 1023 * amp.maximum == pytest.approx(850, abs=1)  # the manual rounds 849.09 to 850
    assert 1023 * float(from_raw(amp, amp.default_raw)) <= 850  # stored 212/256 → 847.2


@pytest.mark.statements("mac050_141:3.2.41:4")
def test_t_home_limit():  # manual 3.2.41: 1.25·T_HOME must stay ≤ 1023
    assert 1.25 * T.lookup("T_HOME").maximum <= T.lookup("T_SOLL").maximum


@pytest.mark.statements("mac050_141:3.2.14:5")
def test_gear_example_fits():  # manual 3.2.14: 15500/10000 = 31/20
    assert int(to_raw(T.lookup("GEARF1"), 15500)) == 15500
    assert int(to_raw(T.lookup("GEARF2"), 10000)) == 10000


@pytest.mark.statements("mac050_141:3.2.1:1")
def test_prog_version_example():  # manual 3.2.1: 78 = 4Eh
    assert int(to_word16(T.lookup("PROG_VERSION"), 78)) == 0x4E


# ----------------------------------------------------------------------------- loading


def _write(tmp_path, body: str):
    p = tmp_path / "t.csv"
    p.write_text(HEADER + body)
    return p


GOOD = ("1,MODE,Word,0,10,,rw,0,3.2.1,mode\n"
        "2,POS,LongInt,-100000,100000,counts,rw,-1,3.2.2,pos\n"
        "3,POS_HI,LongIntHigh,0,65535,,rw,65535,3.2.2,high word\n"
        "4,RESERVED_4,Word,,,,reserved,,3.2.4,\n"
        "5,GAIN,Fixed4,-1,1,,ro,0.5,3.2.5,gain\n")


def test_load_small_table_with_reserved_row(tmp_path):
    t = load_table(_write(tmp_path, GOOD))
    assert len(t) == 5 and t.lookup("reserved_4").access == Access.RESERVED
    assert t.fmt_code_array.tolist() == [0, 1, 3, 4, 0, 5]
    assert t.default_raw_array.tolist() == [0, 0, -1, 0, 0, 2048]
    with pytest.raises(ReadOnlyRegisterError, match="reserved"):
        to_raw(t.lookup(4), 0)


@pytest.mark.parametrize(
    ("body", "needle"),
    [
        (GOOD.replace("5,GAIN", "4,GAIN"), "duplicate"),
        (GOOD.replace("5,GAIN", "6,GAIN"), "missing"),
        (GOOD.replace("GAIN,Fixed4", "MODE,Fixed4"), "already used"),
        (GOOD.replace("Fixed4", "Fixed5"), "unknown format"),
        (GOOD.replace("ro,0.5", "rx,0.5"), "unknown access"),
        (GOOD.replace("ro,0.5", "ro,2.5"), "default"),
        (GOOD.replace("3,POS_HI", "3,POSX_HI"), "LongIntHigh"),
        (GOOD.replace("65535,3.2.2,high", "0,3.2.2,high"), "high word"),
        (GOOD.replace("-1,1,,ro", "-9,1,,ro"), "format"),
    ],
)
def test_bad_tables_raise_clear_errors(tmp_path, body, needle):
    with pytest.raises(TableError, match=needle):
        load_table(_write(tmp_path, body))


def test_table_error_is_register_error():
    assert issubclass(TableError, RegisterError)


def test_markdown_reference_lists_every_register():
    md = markdown_reference(T)
    rows = [ln for ln in md.splitlines() if ln.startswith("| ") and ln[2].isdigit()]
    assert len(rows) == 164
    assert "| 13 | KVOUT | Fixed8 |" in md


def test_raws_of_rows_converts_like_to_raw():
    """The compiled conversion of a batch of registers = to_raw row by row; it reports the
    first row with a value out of range or NaN."""
    from jvl_gym.registers.formats import raw_bounds, raws_of_rows

    rng = np.random.default_rng(1)
    regs = [r for r in T if r.access != Access.RESERVED]
    bounds = np.array([raw_bounds(r) for r in regs])
    values = rng.uniform(bounds[:, :1], bounds[:, 1:2], (len(regs), 5))
    values[:, 0], values[:, 1] = bounds[:, 0], bounds[:, 1]
    values[:, 2] = (bounds[:, 4] - 0.5) / bounds[:, 2]  # a half LSB below the top: rounds up
    whole = bounds[:, 5] > 0.5  # codes: whole numbers only
    values[whole] = np.clip(np.round(values[whole]), bounds[whole, :1], bounds[whole, 1:2])
    out = np.empty(values.shape, dtype=np.int64)
    assert raws_of_rows(values, bounds, out) == -1
    for reg, row, raw in zip(regs, values, out):
        np.testing.assert_array_equal(raw, to_raw(reg, row), err_msg=reg.name)
    values[7, 3] = np.nan
    values[4, 1] = bounds[4, 1] + 1.0
    assert raws_of_rows(values, bounds, out) == 4


def test_data_write_limits_cover_only_read_write_registers():
    """What a compiled task may store directly: read-write registers in their raw range; the
    excluded mode register and read-only registers have no range (0, 0)."""
    from jvl_gym.families.mac050_141.table import TABLE

    low, high = TABLE.data_write_limits(TABLE.lookup("MODE_REG").number)
    v_soll, v_ist, mode = (TABLE.lookup(n) for n in ("V_SOLL", "V_IST", "MODE_REG"))
    assert (low[v_soll.number], high[v_soll.number]) == (v_soll.raw_min, v_soll.raw_max)
    assert (low[v_ist.number], high[v_ist.number]) == (0, 0)
    assert (low[mode.number], high[mode.number]) == (0, 0)
    assert low.shape == high.shape == (TABLE.last + 1,)

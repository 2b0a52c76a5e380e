"""Register tables, 32-bit formats and unit scalings of the MAC800 and MIS/SMC families
(MAC800 register overview §1.2; MIS manual §8.2)."""

from __future__ import annotations

import csv
import math
from importlib import resources

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from jvl_gym.families import mac800, mis
from jvl_gym.families.mac050_141.table import TABLE as MAC050_141
from jvl_gym.families.mac800 import units as mu
from jvl_gym.families.mis import units as su
from jvl_gym.registers import (
    Access,
    Format,
    RegisterRangeError,
    RegisterShapeError,
    TableError,
    from_raw,
    from_word16,
    load_table,
    to_raw,
    to_word16,
)
from jvl_gym.registers.formats import join_word32, split_word32
from jvl_gym.registers.table import (
    FORMAT_CODES,
    FORMAT_RAW_RANGE,
    FORMAT_SCALE,
    FORMATS_32_ONE_NUMBER,
    load_packaged_table,
)
from jvl_gym.registers.table import format_value_range as value_range

M8 = mac800.REGISTERS
MIS = mis.REGISTERS
SCHEMA = ["number", "name", "format", "min", "max", "unit", "access", "default", "section",
          "description", "alias", "user"]
WIDE = (Format.INT32, Format.WORD32, Format.FIXED16, Format.FIXED24)

# ----------------------------------------------------------------------------- the tables


@pytest.mark.parametrize(("table", "last"), [(M8, 206), (MIS, 253)])
def test_tables_load_with_every_number_once(table, last):
    assert table.last == last and len(table) == last
    assert [r.number for r in table] == list(range(1, last + 1))
    assert len(set(table.names)) == last
    assert table.raw_min_array.shape == table.fmt_code_array.shape == (last + 1,)
    for r in table:
        assert table.lookup(r.number) is r and table.lookup(r.name.lower()) is r
        if r.access != Access.RESERVED:
            assert r.format in WIDE  # 32 bits at one register number, no LongIntHigh rows
            assert r.numbers == 1 and r.words == 2
            assert r.minimum <= r.default <= r.maximum, r.name


@pytest.mark.parametrize("package", ["families/mac050_141", "families/mac800", "families/mis"])
def test_all_tables_share_one_schema(package):
    path = resources.files("jvl_gym")
    for part in (*package.split("/"), "registers.csv"):
        path = path.joinpath(part)
    text = path.read_text(encoding="utf-8")
    rows = list(csv.reader(text.splitlines()))
    assert rows[0] == SCHEMA
    assert all(len(r) == len(SCHEMA) for r in rows[1:])
    assert {r[-1] for r in rows[1:]} <= {"yes", "no"}


def test_mac050_141_unchanged_by_the_new_columns():
    assert len(MAC050_141) == 164
    assert all(r.alias == "" and r.user for r in MAC050_141)
    assert MAC050_141.lookup("P_SOLL").words == 2 and MAC050_141.lookup("P_SOLL").numbers == 2
    assert MAC050_141.lookup("V_SOLL").words == 1


def test_packaged_tables_name_their_source():
    t = load_packaged_table("jvl_gym.families.mac800")
    assert t.source == "jvl_gym/families/mac800/registers.csv"
    assert [r.name for r in t] == list(M8.names)


# ----------------------------------------------------------------------------- MAC800 rows


@pytest.mark.parametrize(
    ("number", "name", "fmt", "alias"),
    [(1, "PROG_VERSION", Format.INT32, "(status bar)"), (2, "MODE_REG", Format.INT32, "Mode"),
     (3, "P_SOLL", Format.INT32, "Position"), (4, "P_NEW", Format.INT32, ""),
     (5, "V_SOLL", Format.INT32, "Max velocity"), (6, "A_SOLL", Format.INT32, "Acceleration"),
     (7, "T_SOLL", Format.INT32, "Torque"), (8, "P_FUNC", Format.INT32, ""),
     (10, "P_IST", Format.INT32, "Actual position"), (11, "V_IST16", Format.INT32,
                                                       "Actual velocity"),
     (12, "V_IST", Format.INT32, ""), (13, "KVOUT", Format.FIXED16, "Load"),
     (14, "GEARF_1", Format.INT32, "Output"), (15, "GEARF_2", Format.INT32, "Input"),
     (16, "I2T", Format.INT32, "Motor load"), (21, "U_24V", Format.INT32, "Logic supply"),
     (29, "DEGC", Format.INT32, "Temperature"), (35, "ERR_STAT", Format.INT32,
                                                  "(Error monitor)"),
     (49, "POS0", Format.INT32, "P1"), (63, "POS7", Format.INT32, "P8"),
     (65, "VEL0", Format.INT32, "V1"), (70, "VEL5", Format.INT32, "V6"),
     (73, "ACC0", Format.INT32, "A1"), (77, "TQ0", Format.INT32, "T1"),
     (81, "LOAD0", Format.FIXED16, "L1"), (88, "ZERO3", Format.INT32, "Z4"),
     (121, "KFF5", Format.FIXED24, ""), (126, "KFF0", Format.FIXED24, ""),
     (127, "KVFX6", Format.FIXED16, ""), (138, "KVFY0", Format.FIXED16, ""),
     (143, "KVB0", Format.FIXED24, ""), (147, "KIFY0", Format.FIXED16, ""),
     (149, "KIB0", Format.FIXED24, ""), (154, "MODEL_POT", Format.INT32, ""),
     (156, "S_ORDER", Format.INT32, ""), (157, "OUTLOOPDIV", Format.INT32, ""),
     (162, "REC_CNT", Format.INT32, ""), (166, "FNC_OUT", Format.FIXED16, ""),
     (169, "VF_OUT", Format.INT32, "Actual motor torque"), (175, "MAN_I_NOM", Format.FIXED16, ""),
     (198, "U_BUS", Format.INT32, "Bus voltage"), (202, "MY_ADDR", Format.INT32,
                                                    "Motor address"),
     (206, "CHKSUM", Format.INT32, "")],
)
def test_mac800_numbers_formats_and_mactalk_names(number, name, fmt, alias):
    r = M8.lookup(name)
    assert (r.number, r.format, r.alias) == (number, fmt, alias)


def test_mac800_gaps_are_reserved():
    reserved = {r.number for r in M8 if r.access == Access.RESERVED}
    expected = ({25} | set(range(50, 65, 2)) | set(range(89, 121)) | {150, 151, 152, 153, 155})
    assert reserved == expected


def test_mac800_grey_registers_are_not_for_the_normal_user():
    grey = {r.name for r in M8 if not r.user}
    assert {"I2TLIM", "UITLIM", "DEGCMAX", "HW_SETUP", "KFF0", "KVFX1", "KVFY5", "KVB4", "KIFX2",
            "KIB1", "S_ORDER", "OUTLOOPDIV", "MODEL_POT", "AMPLITUDE", "IA_OFFSET", "KIA",
            "EMK_C", "TCO_CV2", "FF_OUT"} <= grey
    for name in ("P_SOLL", "V_SOLL", "A_SOLL", "T_SOLL", "MODE_REG", "ERR_STAT", "U_BUS",
                 "VF_OUT", "ANINP", "POS0", "SAMPLE1", "MY_ADDR"):
        assert M8.lookup(name).user, name
    assert all(r.user for r in MIS)


def test_mac800_ranges_defaults_and_access():
    def rng(name):
        r = M8.lookup(name)
        return r.minimum, r.maximum

    assert rng("MODE_REG") == (0, 21) and rng("START_MODE") == (0, 21)
    assert rng("T_SOLL") == (0, 1023) and M8.lookup("T_SOLL").default == 1023
    assert rng("P_SOLL") == (-(2**31), 2**31 - 1)
    assert rng("ERR_STAT") == (0, 2**18 - 1)  # bits 0-17
    assert rng("KFF0") == value_range(Format.FIXED24)
    assert rng("KVOUT") == value_range(Format.FIXED16) and M8.lookup("KVOUT").default == 1.0
    assert M8.lookup("A_SOLL").default == M8.lookup("ACC_EMERG").default == 360
    for name in ("V_IST", "V_IST16", "FLWERR", "FNCERR", "I2T", "UIT", "DEGC", "U_24V",
                 "U_BUS", "VF_OUT", "ANINP", "IA_IST", "ELDEG_IST", "CHKSUM"):
        assert M8.lookup(name).access == Access.RO, name
    for name in ("P_SOLL", "P_IST", "V_SOLL", "ERR_STAT", "KFF0", "MIN_P_IST", "MAX_P_IST"):
        assert M8.lookup(name).access == Access.RW, name
    assert "negative" in M8.lookup("MIN_P_IST").description.split(";")[0]
    assert "positive" in M8.lookup("MAX_P_IST").description.split(";")[0]


def test_mac800_arrays_hold_32_bit_raws():
    assert M8.fmt_code_array[13] == FORMAT_CODES[Format.FIXED16] == 9
    assert M8.fmt_code_array[121] == FORMAT_CODES[Format.FIXED24] == 10
    assert M8.fmt_code_array[5] == FORMAT_CODES[Format.INT32] == 7
    assert M8.default_raw_array[13] == 65536  # KVOUT 1.0
    assert M8.raw_max_array[121] == 2**31 - 1 and M8.raw_min_array[121] == -(2**31)
    assert M8.raw_min_array[3] == -(2**31) and M8.raw_max_array[3] == 2**31 - 1


# ----------------------------------------------------------------------------- MIS rows


@pytest.mark.parametrize(
    ("number", "name", "lo", "hi", "default", "unit"),
    [(2, "MODE_REG", 0, 15, 0, ""), (3, "P_SOLL", -(2**31), 2**31 - 1, 0, "counts (1/409600 rev)"),
     (5, "V_SOLL", -300000, 300000, 10000, "0.01 RPM"), (6, "A_SOLL", 1, 500000, 1000, "RPM/s"),
     (7, "RUN_CURRENT", 0, 1533, 511, "5.87 mA"), (8, "STANDBY_TIME", 1, 65535, 500, "ms"),
     (9, "STANDBY_CURRENT", 0, 1533, 128, "5.87 mA"), (13, "V_START", 1, 300000, 1000,
                                                         "0.01 RPM"),
     (14, "GEAR1", -(2**31), 2**31 - 1, 409600, ""), (15, "GEAR2", -(2**31), 2**31 - 1, 2048, ""),
     (22, "FLWERRMAX", -(2**31), 2**31 - 1, 0, "counts (1/409600 rev)"),
     (32, "ACC_EMERG", 1, 500000, 10000, "RPM/s"), (33, "IN_POSITION_WINDOW", 0, 2**31 - 1,
                                                     20000, "counts (1/409600 rev)"),
     (34, "IN_POSITION_COUNT", 0, 100, 2, ""), (40, "V_HOME", -300000, 300000, -5000,
                                                 "0.01 RPM"),
     (41, "T_HOME", 0, 2047, 1024, "1/2047 (100 %)"), (65, "V1", -(2**31), 2**31 - 1, 25000,
                                                        "0.01 RPM"),
     (77, "T1", 0, 1533, 511, "5.87 mA"), (97, "BUSVOL", 0, 4095, 0, "26.525 mV"),
     (98, "MIN_BUSVOL", 0, 4095, 565, "26.525 mV"), (105, "AFZUP_FILTER", 1, 64, 64, "1/64"),
     (146, "BAUD_RATE", 0, 7, 1, ""), (150, "MY_ADDR", 0, 254, 254, ""),
     (174, "D_SOLL", 0, 500000, 1000, "RPM/s"), (212, "CUR_SCALE_MAX", 0, 2047, 2047,
                                                  "1/2047 RUN_CURRENT"),
     (218, "CUR_SCALE_INC", 1, 100000, 2000, "1/36 us"), (219, "CUR_SCALE_DEC", 1, 100000, 4000,
                                                          "1/36 us"),
     (253, "V_ENCODER", -300000, 300000, 0, "0.01 RPM")],
)
def test_mis_register_list(number, name, lo, hi, default, unit):
    r = MIS.lookup(name)
    assert (r.number, r.minimum, r.maximum, r.default, r.unit) == (number, lo, hi, default, unit)
    assert r.section.startswith("8.2")


def test_mis_positions_odd_and_high_words_reserved():
    assert [MIS.lookup(f"P{k}").number for k in range(1, 9)] == list(range(49, 64, 2))
    for n in (4, 11, 17, 21, 23, 29, 31, 39, 145, 171, *range(50, 65, 2)):
        assert MIS.lookup(n).access == Access.RESERVED, n
    assert [MIS.lookup(f"V{k}").number for k in range(1, 9)] == list(range(65, 73))
    assert [MIS.lookup(f"ANALOGUE_INPUT{k}").number for k in range(1, 9)] == list(range(89, 97))


def test_mis_access_and_formats():
    for name in ("V_IST", "FLWERR", "STATUSBITS", "TEMP", "INPUTS", "BUSVOL", "MOTORTYPE",
                 "ACTUAL_TORQUE", "V_IST_CALC", "TEMP_LIMITS", "BUF_SIZE"):
        assert MIS.lookup(name).access == Access.RO, name
    for name in ("P_IST", "ERR_BITS", "WARN_BITS", "OUTPUTS", "COMMAND", "CUR_SCALE_MIN",
                 "MOTOR_REV"):  # MOTOR_REV: R/W (§8.2.122)
        assert MIS.lookup(name).access == Access.RW, name
    for name in ("TICKS", "MOTOR_REV", "TURNTABLE_SIZE", "FW_BUILD", "V_HOME_TIMEOUT"):
        r = MIS.lookup(name)
        assert r.format == Format.WORD32 and (r.minimum, r.maximum) == (0, 2**32 - 1), name
    mt = MIS.lookup("MOTORTYPE")
    assert mt.default == su.MOTOR_TYPE_CODES["MIS231"] == 152
    assert all(mt.minimum <= c <= mt.maximum for c in su.MOTOR_TYPE_CODES.values())
    assert len(set(su.MOTOR_TYPE_CODES.values())) == len(su.MOTOR_TYPE_CODES)
    enc = MIS.lookup("ENCODER_TYPE")
    assert all(enc.minimum <= k <= enc.maximum for k in su.ENCODER_TYPES)


def test_mis_table_holds_the_registers_the_modbus_slave_uses():  # MIS manual §12.1
    from jvl_gym.protocol.modbus.server import MIS_REGISTERS

    names = {"setup": "MODBUS_SETUP", "baud": "BAUD_RATE", "timeout": "MODBUS_TIMEOUT",
             "timeout_action": "MODBUS_TIMEOUT_RESPONSE", "frame_delay": "MODBUS_FRAME_DELAY",
             "max_velocity": "V_SOLL", "mode": "MODE_REG"}
    for attr, name in names.items():
        assert MIS.lookup(getattr(MIS_REGISTERS, attr)).name == name
    assert MIS.lookup("MODBUS_SETUP").maximum == 511  # bit 8: Modbus on RS-422
    assert (MIS.lookup(200).minimum, MIS.lookup(200).maximum) == (0, 2)


def test_mis_bitfield_defaults_decode_as_the_manual_describes():
    led1 = int(MIS.lookup("FLEXLEDSETUP1").default)
    assert (led1 & 0x1FF, (led1 >> 9) & 0x1F) == (25, 4)  # L3 = In position
    assert ((led1 >> 16) & 0x1FF, (led1 >> 25) & 0x1F) == (25, 3)  # L2 = At velocity
    led2 = int(MIS.lookup("FLEXLEDSETUP2").default)
    assert led2 & 0xFFFF == 0 and ((led2 >> 16) & 0x1FF, (led2 >> 25) & 0x1F) == (25, 15)
    temp = int(MIS.lookup("TEMP_LIMITS").default)
    assert (temp & 0xFFFF, temp >> 16) == (su.TEMP_WARNING_CELSIUS, su.TEMP_ERROR_CELSIUS)
    catch = int(MIS.lookup("CL_CATCH_UP").default)
    assert (catch & 0xFF, catch >> 8) == (0, 5000)
    enc = int(MIS.lookup("INTERNAL_ENCODER_SETUP").default)
    assert (enc & 3, (enc >> 2) & 7, (enc >> 5) & 1, (enc >> 6) & 1) == (1, 4, 1, 1)
    ssi = int(MIS.lookup("SSI_SETUP1").default)
    assert (ssi & 0x1F, (ssi >> 8) & 0xFF) == (25, 10)  # 25 bit, 10 x 10 kHz


# ----------------------------------------------------------------------------- the formats


def test_exact_format_ranges():
    assert value_range(Format.FIXED16) == (-32768.0, 32767 + 65535 / 65536)
    assert value_range(Format.FIXED24) == (-128.0, 127 + (2**24 - 1) / 2**24)
    assert value_range(Format.FIXED16)[1] == pytest.approx(32767.9999847, abs=1e-7)
    assert value_range(Format.FIXED24)[1] == pytest.approx(127.99999994, abs=1e-8)
    assert value_range(Format.INT32) == (-(2**31), 2**31 - 1)
    assert value_range(Format.WORD32) == (0, 2**32 - 1)
    assert FORMAT_SCALE[Format.FIXED16] == 65536 and FORMAT_SCALE[Format.FIXED24] == 16777216
    assert FORMATS_32_ONE_NUMBER == set(WIDE)
    assert len(set(FORMAT_CODES.values())) == len(FORMAT_CODES) == len(Format)
    for fmt in (Format.INT32, Format.FIXED16, Format.FIXED24):
        assert FORMAT_RAW_RANGE[fmt] == (-(2**31), 2**31 - 1)


def test_fixed16_and_fixed24_conversions():
    f16, f24 = M8.lookup("KVFX1"), M8.lookup("KFF0")
    assert f16.scale == 65536 and f24.scale == 2**24
    assert int(to_raw(f16, 1.0)) == 65536 and int(to_raw(f24, 1.0)) == 2**24
    assert int(to_raw(f16, 1 / 65536)) == 1 and int(to_raw(f24, -1 / 2**24)) == -1
    assert int(to_raw(f16, -32768.0)) == -(2**31) and int(to_raw(f24, -128.0)) == -(2**31)
    assert int(to_raw(f16, value_range(Format.FIXED16)[1])) == 2**31 - 1
    assert int(to_raw(f24, 127.99999994)) == 2**31 - 1  # the overview's printed end
    assert float(from_raw(f24, 2**31 - 1)) == value_range(Format.FIXED24)[1]
    assert from_raw(f16, np.array([1, 2])).dtype == np.float64
    for reg, bad in ((f16, 32768.0), (f16, -32768.1), (f24, 128.0), (f24, math.nan)):
        with pytest.raises(RegisterRangeError, match=reg.name):
            to_raw(reg, bad)


def test_int32_and_word32_conversions():
    p = M8.lookup("P_SOLL")
    assert int(to_raw(p, -(2**31))) == -(2**31) and int(to_raw(p, 2**31 - 1)) == 2**31 - 1
    assert from_raw(p, 5).dtype == np.int64
    with pytest.raises(RegisterRangeError):
        to_raw(p, 2**31)
    t = MIS.lookup("TICKS")
    assert int(to_raw(t, 2**32 - 1)) == 2**32 - 1
    with pytest.raises(RegisterRangeError):
        to_raw(t, -1)
    with pytest.raises(RegisterRangeError, match="V_SOLL"):
        to_raw(MIS.lookup("V_SOLL"), 300001)


def test_word16_mapping_of_32_bit_formats():
    p = M8.lookup("P_SOLL")
    np.testing.assert_array_equal(to_word16(p, -1), [0xFFFF, 0xFFFF])
    np.testing.assert_array_equal(to_word16(p, 230_000), [0x8270, 0x0003])  # quick guide 1.3.2
    np.testing.assert_array_equal(to_word16(p, [1, -2]), [[1, 0], [0xFFFE, 0xFFFF]])
    assert int(from_word16(p, [0x8270, 0x0003])) == 230_000
    assert int(from_word16(p, [0xFFFF, 0xFFFF])) == -1
    t = MIS.lookup("TICKS")
    np.testing.assert_array_equal(to_word16(t, 2**32 - 1), [0xFFFF, 0xFFFF])
    assert int(from_word16(t, [0xFFFF, 0xFFFF])) == 2**32 - 1
    f24 = M8.lookup("KFF0")
    assert int(from_word16(f24, to_word16(f24, -(2**31)))) == -(2**31)
    with pytest.raises(RegisterShapeError):
        from_word16(p, 0x1234)
    with pytest.raises(RegisterRangeError):
        to_word16(p, 2**31)
    with pytest.raises(RegisterRangeError):
        to_word16(t, -1)


def test_split_join_word32_edges():
    assert split_word32(-1) == (0xFFFF, 0xFFFF)
    assert split_word32(0x00054711) == (0x4711, 0x0005)
    assert split_word32(2**32 - 1, signed=False) == (0xFFFF, 0xFFFF)
    assert join_word32(0xFFFF, 0xFFFF) == -1
    assert join_word32(0xFFFF, 0xFFFF, signed=False) == 2**32 - 1
    assert join_word32(0, 0x8000) == -(2**31)
    with pytest.raises(RegisterRangeError):
        split_word32(2**31)
    with pytest.raises(RegisterRangeError):
        split_word32(-1, signed=False)
    with pytest.raises(RegisterRangeError):
        join_word32(0x10000, 0)
    with pytest.raises(RegisterRangeError):
        split_word32(1.5)
    with pytest.raises(RegisterShapeError):
        join_word32(np.zeros(2, int), np.zeros(3, int))


@given(st.integers(-(2**31), 2**31 - 1))
def test_split_join_word32_round_trip_signed(x):
    lo, hi = split_word32(x)
    assert 0 <= lo <= 0xFFFF and 0 <= hi <= 0xFFFF
    assert join_word32(lo, hi) == x


@given(st.integers(0, 2**32 - 1))
def test_split_join_word32_round_trip_unsigned(x):
    lo, hi = split_word32(x, signed=False)
    assert join_word32(lo, hi, signed=False) == x
    assert hi << 16 | lo == x


@given(st.integers(-(2**31), 2**31 - 1))
def test_fixed32_raw_round_trip_is_exact(raw):
    for name in ("KVFX1", "KFF0"):
        r = M8.lookup(name)
        assert int(to_raw(r, from_raw(r, raw))) == raw
        assert int(from_word16(r, to_word16(r, raw))) == raw


@given(st.floats(-128.0, 127.99999994))
def test_fixed24_quantisation_error_is_half_lsb(x):
    r = M8.lookup("KVB0")
    assert abs(float(from_raw(r, to_raw(r, x))) - x) <= 0.5 / 2**24 + 1e-15


@given(st.floats(-32768.0, 32767.99998))
def test_fixed16_quantisation_error_is_half_lsb(x):
    r = M8.lookup("KVOUT")
    assert abs(float(from_raw(r, to_raw(r, x))) - x) <= 0.5 / 65536 + 1e-11


# ----------------------------------------------------------------------------- unit examples


def test_mac800_sample_rate_and_counts_follow_from_the_figures():
    f, n = mu.derive_sample_rate_and_counts()
    assert f == pytest.approx(770.0, abs=0.01) and n == pytest.approx(8000.0, abs=0.1)
    assert (mu.SAMPLE_HZ, mu.COUNTS_PER_REV) == (770.0, 8000)
    # forward: the constants reproduce every printed figure
    assert 16 * mu.COUNTS_PER_REV / (60 * mu.SAMPLE_HZ) == pytest.approx(2.77056, rel=2e-6)
    assert 16 * mu.COUNTS_PER_REV * 1000 / (60 * mu.SAMPLE_HZ**2) == pytest.approx(3.598133,
                                                                                  rel=2e-7)
    assert mu.COUNTS_PER_REV / (60 * mu.SAMPLE_HZ) == pytest.approx(0.17316, rel=2e-6)


def test_mac800_velocity_and_acceleration_examples():
    assert round(mu.rpm_to_v_soll(100)) == 277  # "100 RPM -> 277"
    assert mu.v_soll_to_rpm(277) == pytest.approx(100, rel=0.01)
    assert round(mu.rpm_to_v_soll(1000)) == 2771  # quick guide 1.3.4: 1000 RPM = 2771
    assert round(mu.rpm_per_s_to_a_soll(100_000)) == 360  # "100 000 RPM/s -> 360"
    assert mu.a_soll_to_rpm_per_s(360) == pytest.approx(100_000, rel=0.01)
    assert mu.rpm_to_v_ist(1) == 0.17316
    assert mu.rpm_to_v_ist(100) == pytest.approx(mu.rpm_to_v_soll(100) / 16, rel=1e-5)
    assert mu.v_ist_to_rpm(mu.rpm_to_v_ist(1234.5)) == pytest.approx(1234.5)
    assert int(to_raw(M8.lookup("V_SOLL"), mu.rpm_to_v_soll(100))) == 277


def test_mac800_measurement_scalings():
    assert mu.u_bus_to_volts(366) == pytest.approx(325, abs=0.5)  # "U_BUS = 366 is 325VDC"
    assert mu.volts_to_u_bus(mu.OVERVOLTAGE_VOLTS) == pytest.approx(506.3, abs=0.1)
    assert mu.u_24v_to_volts(1) == pytest.approx(1 / 74.4713, rel=1e-5)
    assert mu.degc_to_celsius(M8.lookup("DEGCMAX").default) == pytest.approx(90, abs=0.1)
    assert mu.celsius_to_degc(90) == pytest.approx(737.3, abs=0.1)
    assert mu.aninp_to_volts(2048) == pytest.approx(10.0, abs=1e-3)  # ANINP range end
    assert mu.t_soll_to_percent_of_nominal(1023) == 300.0
    assert M8.lookup("V_HOME").default == -round(mu.rpm_to_v_soll(50))


def test_mis_unit_examples():
    assert su.rpm_to_v_soll(250) == 25000 and su.v_soll_to_rpm(25000) == 250  # §8.2.5
    assert int(to_raw(MIS.lookup("V_SOLL"), su.rpm_to_v_soll(250))) == 25000
    assert su.run_current_to_amps(100) == pytest.approx(0.587)  # §8.2.7
    assert su.amps_to_run_current(9.0) == pytest.approx(1533, abs=1)
    assert su.RUN_CURRENT_MAX == {k: int(a / 5.87e-3) for k, a in
                                  {"MIS17x": 4, "MIS23x": 6, "MIS34x": 9, "MIS43x": 9,
                                   "MIL34x": 6}.items()}
    assert su.COUNTS_PER_FULL_STEP == 2048 and su.rev_to_counts(1) == 409600
    assert su.counts_to_rev(MIS.lookup("GEAR1").default) == 1.0
    # §8.2.13: GEAR1 = 409600, GEAR2 = 2048 -> one input step moves 200 counts
    assert MIS.lookup("GEAR1").default / MIS.lookup("GEAR2").default == 200
    assert su.analogue_to_volts(4095) == pytest.approx(5.0)
    assert su.analogue_to_volts(1) == pytest.approx(1.221e-3, abs=1e-6)
    assert su.cvi_to_volts(MIS.lookup("ACCEPT_VOLTAGE").default) == pytest.approx(18, abs=0.05)
    assert su.cvi_to_volts(MIS.lookup("SAVE_VOLTAGE").default) == pytest.approx(15, abs=0.05)
    assert su.busvol_to_volts(MIS.lookup("MIN_BUSVOL").default) == pytest.approx(15, abs=0.05)
    assert su.temp_to_celsius(40) == pytest.approx(90.8)


def test_mis_closed_loop_current_timing():  # §5.3.7 worked numbers
    inc = MIS.lookup("CUR_SCALE_INC").default
    dec = MIS.lookup("CUR_SCALE_DEC").default
    fac = MIS.lookup("CUR_SCALE_FACTOR").default
    assert su.cur_scale_inc_step_s(inc) == pytest.approx(55.56e-6, abs=0.01e-6)
    assert su.cur_scale_dec_step_s(0, dec, fac) == pytest.approx(111e-6, abs=0.2e-6)
    assert su.cur_scale_dec_step_s(3000, dec, fac) == pytest.approx(1.13e-3, abs=0.01e-3)
    assert su.cur_scale_dec_step_s(-3000, dec, fac) == su.cur_scale_dec_step_s(3000, dec, fac)
    steps = su.CUR_SCALE_FULL + 1  # "regulated in 2048 steps"
    assert su.cur_scale_inc_step_s(inc) * steps == pytest.approx(0.113, abs=0.001)
    assert su.cur_scale_dec_step_s(0, dec, fac) * steps == pytest.approx(0.227, abs=0.001)
    assert su.cur_scale_dec_step_s(3000, dec, fac) * steps == pytest.approx(2.3, abs=0.02)


# ----------------------------------------------------------------------------- loading


HEADER12 = ",".join(SCHEMA) + "\n"


def test_twelve_column_table_with_32_bit_rows(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text(HEADER12
                 + "1,POS,Int32,-2147483648,2147483647,counts,rw,-5,s,pos,Position,yes\n"
                 + "2,GAIN,Fixed24,-128,127.99999994,,rw,0.5,s,gain,,no\n"
                 + "3,BITS,Word32,0,4294967295,,ro,4294967295,s,bits,,yes\n")
    t = load_table(p)
    assert t.fmt_code_array.tolist() == [0, 7, 10, 8]
    assert t.default_raw_array.tolist() == [0, -5, 2**23, 2**32 - 1]
    assert t.lookup("POS").alias == "Position" and not t.lookup("GAIN").user


@pytest.mark.parametrize(
    ("row", "needle"),
    [("1,X,Int32,0,10,,rw,0,s,d,,maybe\n", "user"),
     ("1,X,Fixed16,0,40000,,rw,0,s,d,,yes\n", "Fixed16"),
     ("1,X,Word32,-1,10,,rw,0,s,d,,yes\n", "Word32"),
     ("1,X,Int32,0,10,,rw,0.5,s,d,,yes\n", "integers")],
)
def test_bad_32_bit_rows_raise(tmp_path, row, needle):
    p = tmp_path / "t.csv"
    p.write_text(HEADER12 + row)
    with pytest.raises(TableError, match=needle):
        load_table(p)


# ----------------------------------------------------------------------------- references


def test_family_references_list_every_register_and_are_current():
    from pathlib import Path

    from jvl_gym.families.reference import family_references

    docs = Path(__file__).resolve().parents[1] / "docs" / "families"
    refs = family_references()
    for name, table in (("mac800-registers.md", M8), ("mis-registers.md", MIS)):
        md = refs[name]
        rows = [ln for ln in md.splitlines() if ln.startswith("| ") and ln[2].isdigit()]
        assert len(rows) == len(table)
        assert (docs / name).read_text(encoding="utf-8") == md, (
            f"docs/families/{name} is stale: run python -m jvl_gym.families.reference")
    assert "| 13 | KVOUT | Load | Fixed16 | -32768 … 32767.9999847 |" in refs["mac800-registers.md"]
    assert "| 5 | V_SOLL | Max velocity | Int32 | -300000 … 300000 | 0.01 RPM | rw | 10000 |" in (
        refs["mis-registers.md"])

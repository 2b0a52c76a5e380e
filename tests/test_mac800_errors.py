"""ERR_STAT (register 35) of the MAC800: each bit's condition provoked, with its reaction
(stop with ACC_EMERG then passive, or passive at once; ``mac800.firmware.monitor``)."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mac800 import constants as c
from jvl_gym.families.mac800 import units as u
from jvl_gym.motor.array import ModeError

RPM_1000 = round(u.rpm_to_v_soll(1000))


def running(rpm: float = 1000.0, **params) -> MotorArray:
    m = MotorArray("MAC800", n=1, seed=0, **params)
    m.write_many({"V_SOLL": round(u.rpm_to_v_soll(rpm)), "MODE_REG": 1})
    m.run(0.3)
    return m


def bit(m: MotorArray, b: int) -> bool:
    return bool(m.read("ERR_STAT")[0] & b)


def until(m: MotorArray, b: int, seconds: float) -> int:
    """Servo samples until ERR_STAT bit ``b`` is set (fails after ``seconds``)."""
    for k in range(int(seconds * c.OUTER_HZ)):
        m.step()
        if bit(m, b):
            return k
    raise AssertionError(f"bit {b} not set within {seconds} s")


def stops_with_acc_emerg(m: MotorArray) -> None:
    """After an error of the stopping kind: the profile ramps down by ACC_EMERG per sample in
    the mode it was in, then the motor is passive."""
    mode = int(m.read("MODE_REG")[0])
    assert mode != 0
    f = m.trace(["FNC_OUT"], 3)["FNC_OUT"][:, 0]
    acc = m.read("ACC_EMERG")[0]
    assert np.all(np.diff(f) == -acc / 16.0) or f[-1] == 0
    m.run(0.3)
    assert m.read("MODE_REG")[0] == 0


def goes_passive(m: MotorArray) -> None:
    assert m.read("MODE_REG")[0] == 0
    assert m.read("VF_OUT")[0] == 0


@pytest.mark.statements("mac800:reg35:1")
def test_no_error_in_a_normal_run() -> None:
    m = running(1000.0)
    m.run(1.0)
    assert m.read("ERR_STAT")[0] & c.BLOCKING_ERRORS == 0


@pytest.mark.statements("mac800:reg16:1", "mac800:reg16:2", "mac800:reg17:1", "mac800:reg32:1",
                        "mac800:reg35:2")
def test_i2t_err() -> None:
    m = running(1000.0)
    m.write("I2TLIM", 6554)  # 10 % of the rated current's square
    m.set_input(load_torque=3.0)
    until(m, c.I2T_ERR, 5.0)
    assert m.read("I2T")[0] >= 6554
    stops_with_acc_emerg(m)


@pytest.mark.statements("mac800:reg22:1", "mac800:reg35:3")
def test_flw_err() -> None:
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"FLWERRMAX": 5, "V_SOLL": 2771, "P_SOLL": 0, "MODE_REG": 2})
    m.run(0.2)
    assert not bit(m, c.FLW_ERR)
    m.set_input(load_torque=5.0)
    until(m, c.FLW_ERR, 0.5)
    assert abs(m.read("FLWERR")[0]) > 5
    stops_with_acc_emerg(m)


@pytest.mark.statements("mac800:reg24:1", "mac800:reg26:1", "mac800:reg35:4")
def test_fnc_err() -> None:
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"FNCERRMAX": 2000, "T_SOLL": 30, "V_SOLL": 8000, "A_SOLL": 2000,
                  "P_SOLL": 400000, "MODE_REG": 2})
    until(m, c.FNC_ERR, 1.0)
    assert abs(m.read("FNCERR")[0]) > 2000
    stops_with_acc_emerg(m)


@pytest.mark.statements("mac800:reg18:1", "mac800:reg19:1", "mac800:reg35:5")
def test_uit_err() -> None:
    m = running(3000.0, load_inertia=1e-3)
    m.run(1.0)
    m.write_many({"UITLIM": 1000, "A_SOLL": 40, "V_SOLL": 0})
    until(m, c.UIT_ERR, 2.0)
    assert m.read("UIT")[0] > 1000
    assert m.read("MODE_REG")[0] == 1  # stopping


@pytest.mark.statements("mac800:reg28:1", "mac800:reg28:2", "mac800:reg35:9", "mac800:reg35:16")
def test_plim_err_and_dis_p_lim() -> None:
    m = running(300.0)
    m.write_many({"MIN_P_IST": -1000, "MAX_P_IST": 20000, "ERR_STAT": c.DIS_P_LIM})
    m.run(0.5)
    assert m.read("P_IST")[0] > 20000 and not bit(m, c.PLIM_ERR)  # limits disabled
    m.write("ERR_STAT", 0)
    m.step()
    assert bit(m, c.PLIM_ERR)
    stops_with_acc_emerg(m)


@pytest.mark.statements("mac800:reg31:1", "mac800:reg31:2", "mac800:reg35:10")
def test_degc_err() -> None:
    m = running(500.0)
    assert m.read("DEGC")[0] == pytest.approx(25.0 / u.DEGC_CELSIUS_PER_UNIT, abs=2)
    m = running(500.0, initial_temperature=95.0)
    assert bit(m, c.DEGC_ERR)
    assert m.read("DEGC")[0] > m.read("DEGCMAX")[0]
    assert m.read("MODE_REG")[0] == 0  # stopped within the 0.3 s of running()


def test_degc_rises_with_copper_loss() -> None:
    m = running(100.0)
    t0 = m.temperature[0]
    m.set_input(load_torque=4.0)
    m.run(2.0)
    assert m.temperature[0] > t0


@pytest.mark.statements("mac800:reg23:1", "mac800:reg23:2", "mac800:reg23:4", "mac800:reg35:11",
                        "mac800:reg35:12")
def test_uv_detect_uv_err_and_uv_handle() -> None:
    m = running(1000.0)
    m.write("UV_HANDLE", c.SET_UV_ERR | c.UV_VSOLL0)
    m.set_input(supply_volts=150.0, load_torque=2.0)
    until(m, c.UV_DETECT, 2.0)
    assert bit(m, c.UV_ERR)
    assert m.read("V_SOLL")[0] == 0
    assert m.read("U_BUS")[0] * u.U_BUS_VOLTS_PER_UNIT < c.UV_BUS_VOLTS
    m.set_input(supply_volts=325.0, load_torque=0.0)
    m.run(0.5)
    assert not bit(m, c.UV_DETECT) and bit(m, c.UV_ERR)


@pytest.mark.statements("mac800:reg23:1", "mac800:reg23:2", "mac800:reg23:3")
def test_uv_go_passive() -> None:
    m = running(1000.0)
    m.write("UV_HANDLE", c.UV_GO_PASSIVE)
    m.set_input(supply_volts=150.0, load_torque=2.0)
    until(m, c.UV_DETECT, 2.0)
    goes_passive(m)
    assert not bit(m, c.UV_ERR)


@pytest.mark.statements("mac800:reg35:13")
def test_ov_err() -> None:
    m = running(500.0)
    m.set_input(supply_volts=480.0)
    until(m, c.OV_ERR, 1.0)
    assert m.bus_voltage[0] > 450.0
    goes_passive(m)


@pytest.mark.statements("mac800:reg35:14")
def test_ipeak_err() -> None:
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"KIB1": 0.0, "V_SOLL": RPM_1000, "MODE_REG": 1})  # no current feedback
    until(m, c.IPEAK_ERR, 0.5)
    goes_passive(m)
    m.run(0.01)
    assert m.torque[0] == 0.0  # power stage off: no winding current


@pytest.mark.statements("mac800:reg35:15")
def test_speed_err() -> None:
    m = MotorArray("MAC800", n=1, seed=0, initial_speed=4000 * 2 * np.pi / 60)
    m.step(2)  # passive, turning freely at 4000 RPM: the bit, no reaction
    assert bit(m, c.SPEED_ERR) and m.read("MODE_REG")[0] == 0
    m.write_many({"ERR_STAT": 0, "V_SOLL": round(u.rpm_to_v_soll(4000)), "MODE_REG": 1})
    m.step()
    assert bit(m, c.SPEED_ERR)
    stops_with_acc_emerg(m)


@pytest.mark.statements("mac800:reg35:17")
def test_index_err() -> None:
    m = running(600.0)
    m.run(0.5)
    assert not bit(m, c.INDEX_ERR)
    m.set_input(encoder_fault=1)
    until(m, c.INDEX_ERR, 1.0)
    goes_passive(m)


@pytest.mark.statements("mac800:reg35:18")
def test_old_filt_err() -> None:
    m = MotorArray("MAC800", n=1, seed=0)
    m.write("KVFY5", 1.5)  # a pole at 1.5: the filter setting is not valid
    m.write_many({"V_SOLL": RPM_1000, "MODE_REG": 1})
    m.step()
    assert bit(m, c.OLD_FILT_ERR)
    goes_passive(m)


@pytest.mark.statements("mac800:reg35:19")
def test_u24v_err() -> None:
    m = running(500.0)
    m.set_input(control_volts=15.0)
    m.step()
    assert bit(m, c.U24V_ERR)
    goes_passive(m)
    m.set_input(control_volts=24.0)
    m.run(0.1)
    assert bit(m, c.U24V_ERR)  # "has been too low": kept until cleared


@pytest.mark.statements("mac800:reg33:1", "mac800:reg35:6", "mac800:reg35:7", "mac800:reg35:8")
def test_in_pos_acc_and_dec_flags() -> None:
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"V_SOLL": 2771, "A_SOLL": 100, "P_SOLL": 20000, "MODE_REG": 2})
    m.step(3)
    assert bit(m, c.ACC_FLAG) and not bit(m, c.IN_POS)
    dec = False
    for _ in range(int(2 * c.OUTER_HZ)):
        m.step()
        dec = dec or bit(m, c.DEC_FLAG)
    assert dec and bit(m, c.IN_POS)
    assert abs(m.read("P_IST")[0] - 20000) < m.read("INPOSWIN")[0]


def test_a_blocking_error_refuses_modes_until_cleared() -> None:
    m = running(500.0)
    m.set_input(control_volts=15.0)
    m.step()
    m.set_input(control_volts=24.0)
    with pytest.raises(ModeError, match="U24V_ERR"):
        m.write("MODE_REG", 1)
    assert m.read("MODE_REG")[0] == 0
    m.write("ERR_STAT", 0)
    m.write("MODE_REG", 1)
    assert m.read("MODE_REG")[0] == 1

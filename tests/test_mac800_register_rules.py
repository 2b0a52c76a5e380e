"""MAC800 register rules the register overview states (§1.2): START_MODE takes the modes
MODE_REG takes, ANINP covers the table's range −2048 … 2047."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mac800 import constants as c
from jvl_gym.families.mac800 import units as u
from jvl_gym.motor.array import ModeError
from jvl_gym.registers import RegisterError


@pytest.mark.parametrize("mode", [7, 8, 9, 10, 11, 15])
@pytest.mark.statements("mac800:reg2:10", "mac800:reg37:2")
def test_start_mode_refuses_the_reserved_modes_mode_reg_refuses(mode: int) -> None:
    """START_MODE (register 37) is a MODE_REG value: 7–11 and 15 are reserved (register 2),
    refused as MODE_REG refuses them, and nothing changes."""
    m = MotorArray("MAC800", n=1, seed=0)
    with pytest.raises(ModeError, match="reserved"):
        m.write("MODE_REG", mode)
    with pytest.raises(RegisterError, match="START_MODE.*reserved"):
        m.write("START_MODE", mode)
    assert m.read("START_MODE")[0] == 0
    with pytest.raises(RegisterError, match="START_MODE"):
        MotorArray("MAC800", n=1, setup={"START_MODE": mode})
    m.write("START_MODE", c.VELOCITY_MODE)  # a runnable mode is taken
    assert m.read("START_MODE")[0] == c.VELOCITY_MODE


@pytest.mark.statements("mac800:reg170:1")
def test_aninp_reaches_the_table_minimum() -> None:
    """ANINP (register 170): range −2048 … 2047, V = ANINP × 0.0048828."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.set_input(analog_volts=-10.5)
    m.step()
    assert m.read("ANINP")[0] == -2048
    m.set_input(analog_volts=10.5)
    m.step()
    assert m.read("ANINP")[0] == 2047
    m.set_input(analog_volts=-3.0)
    m.step()
    assert m.read("ANINP")[0] == round(-3.0 / u.ANINP_VOLTS_PER_UNIT)


# --- register sets (overview §1.2 "Registers (P0-7, V0-7 etc.)") ---------------------------
@pytest.mark.parametrize("selector, target, names", [
    ("P_REG_P", "P_SOLL", ("POS0", "POS1", "POS2", "POS3", "POS4", "POS5", "POS6", "POS7")),
    ("V_REG_P", "V_SOLL", ("VEL0", "VEL1", "VEL2", "VEL3", "VEL4", "VEL5", "VEL6", "VEL7")),
    ("A_REG_P", "A_SOLL", ("ACC0", "ACC1", "ACC2", "ACC3")),
    ("T_REG_P", "T_SOLL", ("TQ0", "TQ1", "TQ2", "TQ3")),
    ("L_REG_P", "KVOUT", ("LOAD0", "LOAD1", "LOAD2", "LOAD3")),
    ("Z_REG_P", "INPOSWIN", ("ZERO0", "ZERO1", "ZERO2", "ZERO3"))])
@pytest.mark.statements("mac800:reg43:1", "mac800:reg44:1", "mac800:reg45:1", "mac800:reg46:1",
                        "mac800:reg47:1", "mac800:reg48:1", "mac800:reg49:1", "mac800:reg65:1",
                        "mac800:reg73:1", "mac800:reg77:1", "mac800:reg81:1", "mac800:reg85:1",
                        "mac800:reg86:1")
def test_every_register_of_a_set_is_selected_by_its_pointer(
        selector: str, target: str, names: tuple[str, ...]) -> None:
    """Writing k to a selector copies the k-th register of its set to the target."""
    m = MotorArray("MAC800", n=1, seed=0)
    values = {name: (2.0 + k if target == "KVOUT" else 10 + k) for k, name in enumerate(names)}
    m.write_many(values)
    for k, name in enumerate(names):
        m.write(selector, k + 1)
        assert m.read(target)[0] == values[name]


# --- the main filter's taps (overview §1.2 "Filters"; firmware/main_filter.py) -------------
_TAPS = {"KFF5": ("FF", 0), "KFF4": ("FF", 1), "KFF3": ("FF", 2), "KFF2": ("FF", 3),
         "KFF1": ("FF", 4), "KFF0": ("FF", 5), "KVB4": ("VB", 0), "KVB3": ("VB", 1),
         "KVB2": ("VB", 2), "KVB1": ("VB", 3), "KVB0": ("VB", 4)}


@pytest.mark.parametrize("name", list(_TAPS))
def test_each_feed_forward_and_feedback_tap_has_its_delay(name: str) -> None:
    """FF(z) = KFF5 + KFF4 z⁻¹ + … + KFF0 z⁻⁵ on FNC_OUT, VB(z) = KVB4 + … + KVB0 z⁻⁴ on
    16·V_IST: an impulse comes out of FF_OUT / VB_OUT after the tap's delay, scaled by it."""
    from jvl_gym.families.mac800.firmware.main_filter import clear_filter, main_filter

    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({**dict.fromkeys(_TAPS, 0.0), "S_ORDER": 6, name: 0.5})
    r, s = m.regs[0], m.state[0]
    clear_filter(s)
    kind, delay = _TAPS[name]
    out = []
    for k in range(7):
        r[m.table.lookup("V_IST").number] = 1000 if (kind == "VB" and k == 0) else 0
        main_filter(r, s, 1600.0 if (kind == "FF" and k == 0) else 0.0, False, 1023.0)
        out.append(m.read(f"{kind}_OUT")[0])
    expected = [0] * 7
    expected[delay] = 800 if kind == "FF" else 8000
    assert out == expected


_VF = {"KVFX6": ("X", 0), "KVFX5": ("X", 1), "KVFX4": ("X", 2), "KVFX3": ("X", 3),
       "KVFX2": ("X", 4), "KVFX1": ("X", 5), "KVFY5": ("Y", 1), "KVFY4": ("Y", 2),
       "KVFY3": ("Y", 3), "KVFY2": ("Y", 4), "KVFY1": ("Y", 5), "KVFY0": ("Y", 6)}


@pytest.mark.parametrize("name", list(_VF))
@pytest.mark.statements("mac800:1.2:5")
def test_each_servo_filter_tap_has_its_delay(name: str) -> None:
    """VF(z) = (KVFX6 + KVFX5 z⁻¹ + … + KVFX1 z⁻⁵)/(1 − KVFY5 z⁻¹ − … − KVFY0 z⁻⁶): a numerator
    tap passes an impulse of the speed error after its delay; a denominator tap feeds the
    output back after its delay (with KVFX6 = 1 passing the impulse itself)."""
    from jvl_gym.families.mac800.firmware.main_filter import clear_filter, main_filter

    m = MotorArray("MAC800", n=1, seed=0)
    zero = {k: 0.0 for k in (*_VF, *_TAPS)}
    kind, delay = _VF[name]
    m.write_many({**zero, "S_ORDER": 6, "KFF5": 1.0, "MODEL_POT": 0, "KVOUT": 1.0,
                  **({name: 0.25} if kind == "X" else {"KVFX6": 1.0, name: 0.25})})
    r, s = m.regs[0], m.state[0]
    clear_filter(s)
    out = []
    for k in range(8):
        main_filter(r, s, 400.0 if k == 0 else 0.0, False, 1023.0)
        out.append(m.read("VF_OUT")[0])
    if kind == "X":
        assert out[:delay + 1] == [0] * delay + [100]
    else:
        assert out[0] == 400 and out[1:delay] == [0] * (delay - 1) and out[delay] == 100


# --- readouts of the loops (overview §1.2 "Outer/Inner loop registers") --------------------
def test_loop_readouts_are_consistent_at_steady_speed() -> None:
    """FF_OUT = KFF5·FNC_OUT (1/16 units), VB_OUT = (KVB4 + KVB3)·16·V_IST at constant speed;
    I_NOM = |VF_OUT|·AMPLITUDE/1023; PHI_SOLL leads ELDEG_IST by a quarter turn (1024 of 4096)
    plus V_ELDEG·PHASE_COMP/256; UA/UB/UC_VAL and EMK_A/B/C are three-phase (sum ≈ 0), the
    back-EMF in proportion to the speed."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"PHASE_COMP": 0, "V_SOLL": round(u.rpm_to_v_soll(1000)), "MODE_REG": 1})
    m.step(800)
    regs = {k: int(m.read(k)[0]) for k in (
        "FF_OUT", "VB_OUT", "FNC_OUT", "V_IST", "VF_OUT", "I_NOM", "AMPLITUDE", "PHI_SOLL",
        "ELDEG_IST", "V_ELDEG", "UA_VAL", "UB_VAL", "UC_VAL", "EMK_A", "EMK_B", "EMK_C")}
    assert regs["FF_OUT"] == round(16 * m.read("FNC_OUT")[0])
    assert abs(regs["VB_OUT"] - 16 * regs["V_IST"]) <= 16 * 2
    assert abs(regs["I_NOM"] - abs(regs["VF_OUT"]) * regs["AMPLITUDE"] / 1023) <= 1
    lead = (regs["PHI_SOLL"] - regs["ELDEG_IST"]) % 4096
    assert lead in (1024, 3072)
    volts = [regs["UA_VAL"], regs["UB_VAL"], regs["UC_VAL"]]
    emk = [regs["EMK_A"], regs["EMK_B"], regs["EMK_C"]]
    assert 0 < regs["V_ELDEG"]
    for three in (volts, emk):
        assert max(map(abs, three)) > 0 and abs(sum(three)) <= 0.1 * max(map(abs, three))
    m.write("PHASE_COMP", 256)
    m.step(1)
    lead = (int(m.read("PHI_SOLL")[0]) - int(m.read("ELDEG_IST")[0])) % 4096
    assert (lead - int(m.read("V_ELDEG")[0])) % 4096 in (1024, 3072)


@pytest.mark.statements("mac800:reg163:1")
def test_geared_velocity_and_function_term_in_gear_mode() -> None:
    """GV_EXT = 16·V_EXT·GEARF_1/GEARF_2 (the remainder carried); G_FNC is the geared input not
    yet followed (0 when FNC_OUT keeps up)."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"GEARF_1": 3, "GEARF_2": 2, "MODE_REG": 3})
    m.set_input(pulse_counts=4)
    m.step(5)
    assert m.read("V_EXT")[0] == 4 and m.read("GV_EXT")[0] == 16 * 4 * 3 // 2
    assert m.read("G_FNC")[0] == 0


@pytest.mark.statements("mac800:reg171:1")
def test_analogue_offset_is_subtracted() -> None:
    """ANINP_OFFSET (register 171): ANINP = the input − the offset."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write("ANINP_OFFSET", 100)
    m.set_input(analog_volts=2.0)
    m.step()
    assert m.read("ANINP")[0] == round(2.0 / u.ANINP_VOLTS_PER_UNIT) - 100


@pytest.mark.statements("mac800:reg34:1", "mac800:reg35:6")
def test_in_position_needs_inposcnt_samples() -> None:
    """ERR_STAT bit 4 IN_POS after INPOSCNT samples inside INPOSWIN (registers 33, 34)."""
    seen = []
    for count in (1, 200):
        m = MotorArray("MAC800", n=1, seed=0)
        m.write_many({"INPOSCNT": count, "P_SOLL": 4000, "V_SOLL": 2000, "A_SOLL": 20,
                      "MODE_REG": 2})
        st = m.trace(["ERR_STAT"], 1500)["ERR_STAT"][:, 0]
        seen.append(int(np.flatnonzero(st & c.IN_POS).min()))
    assert seen[1] - seen[0] >= 150


@pytest.mark.statements("mac800:reg158:1")
def test_sample_channels_3_and_4_record() -> None:
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"SAMPLE3": 10, "SAMPLE4": 12, "REC_CNT": 20, "V_SOLL": 300, "MODE_REG": 1})
    m.write("CNTRL_BITS", c.RECORDBIT)
    m.step(100)
    buf = m.sample_buffer()
    assert "P_IST" in buf and "V_IST" in buf and np.any(buf["P_IST"] != 0)


@pytest.mark.statements("mac800:reg203:1")
def test_motor_type_is_the_configs_code() -> None:
    for motor in ("MAC400", "MAC800"):
        m = MotorArray(motor, n=1, seed=0)
        assert m.read("MOTOR_TYPE")[0] == m.motor_configs[0].motor_type_code


@pytest.mark.statements("mac800:reg2:16", "mac800:reg2:17")
def test_analog_gear_mode_scales_the_gear_by_aninp() -> None:
    """MODE_REG 18 (analogue gear): the gear factor GEARF_1/GEARF_2 times the analogue gear
    factor 1.01 + 0.14·ANINP/2047 (0.87 … 1.15 over ±10 V)."""
    m = MotorArray("MAC800", n=2, seed=0)
    m.set_input(analog_volts=np.array([9.995, 5.0]), pulse_counts=8)
    m.write_many({"GEARF_1": 1, "GEARF_2": 1, "MODE_REG": c.ANALOG_GEAR_MODE})
    m.step(50)
    gv = m.read("GV_EXT")
    factor = 1.01 + 0.14 * m.read("ANINP") / 2047
    assert m.read("ANINP")[0] == 2047
    assert np.all(np.abs(gv - 16 * 8 * factor) <= 1)


@pytest.mark.statements("mac800:reg36:6")
def test_relposfnc_adds_the_selected_position_to_the_function_position() -> None:
    """CNTRL_BITS bit 4 RELPOSPFNC: a position selected by P_REG_P is added to the function
    position (P_FUNC)."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"POS0": 5000, "P_FUNC": 1000})
    m.write("CNTRL_BITS", c.RELPOSPFNC)
    m.write("P_REG_P", 1)
    assert m.read("P_SOLL")[0] == 6000


def test_current_feedback_tap_kib0_changes_the_current_loop() -> None:
    """KIB0 (register 149): the current feedback filter IB(z) = KIB1 + KIB0 z⁻¹."""
    m = MotorArray("MAC800", n=2, seed=0)
    m.write("KIB0", 0.5, index=1)
    m.write_many({"V_SOLL": 300, "MODE_REG": 1})
    m.step(50)
    ia = m.read("IA_IST")
    assert ia[0] != ia[1]

"""MAC050–141 registers the register description (manual 3.2) and the function blocks state,
each by name: the register-mode sets, the analogue offset and the sample channels."""

from __future__ import annotations

import pytest

from jvl_gym import MotorArray


@pytest.mark.parametrize("pointer, target, names", [
    ("P_REG_P", "P_SOLL", ("P1", "P2", "P3", "P4", "P5", "P6", "P7", "P8")),
    ("V_REG_P", "V_SOLL", ("V1", "V2", "V3", "V4", "V5", "V6", "V7", "V8")),
    ("A_REG_P", "A_SOLL", ("A1", "A2", "A3", "A4")),
    ("T_REG_P", "T_SOLL", ("T1", "T2", "T3", "T4")),
    ("L_REG_P", "KVOUT", ("L1", "L2", "L3", "L4")),
    ("Z_REG_P", "INPOSWIN", ("Z1", "Z2", "Z3", "Z4"))])
@pytest.mark.statements("mac050_141:3.2.33:8", "mac050_141:3.2.43:1", "mac050_141:3.2.44:1",
                        "mac050_141:3.2.45:1", "mac050_141:3.2.46:1", "mac050_141:3.2.47:1",
                        "mac050_141:3.2.48:1", "mac050_141:3.2.49:1", "mac050_141:3.2.65:1",
                        "mac050_141:3.2.73:1", "mac050_141:3.2.77:1", "mac050_141:3.2.81:1",
                        "mac050_141:3.2.85:1")
def test_every_register_of_a_set_is_copied_by_its_pointer(
        pointer: str, target: str, names: tuple[str, ...]) -> None:
    """Manual 3.2.43–3.2.88: writing k to a pointer copies the k-th register of its set to the
    target, and the pointer reads 0 again."""
    m = MotorArray("MAC140", n=1, seed=0)
    values = {name: (1.5 + k if target == "KVOUT" else 10 + k) for k, name in enumerate(names)}
    m.write_many(values)
    for k, name in enumerate(names):
        m.write(pointer, k + 1)
        assert m.read(target)[0] == values[name] and m.read(pointer)[0] == 0


@pytest.mark.statements("mac050_141:3.2.122:3", "mac050_141:3.2.123:1")
def test_analogue_offset_is_added_to_the_input() -> None:
    """ANINP_OFFSET (manual 3.2.123): offset compensation added to the analogue input."""
    m = MotorArray("MAC140", n=2, seed=0)
    m.write("ANINP_OFFSET", 0, index=0)
    m.write("ANINP_OFFSET", 50, index=1)
    m.set_input(analog_volts=2.0)
    m.step()
    a = m.read("ANINP")
    assert a[1] - a[0] == 50


@pytest.mark.statements("mac050_141:3.2.36:8", "mac050_141:3.2.112:1")
def test_sample_channels_2_and_4_record_their_registers() -> None:
    """SAMPLE1–4 (manual 3.2.112–115): the register recorded in each channel."""
    m = MotorArray("MAC140", n=1, seed=0)
    m.write_many({"SAMPLE1": 10, "SAMPLE2": 12, "SAMPLE3": 3, "SAMPLE4": 5,
                  "REC_CNT": 50, "V_SOLL": 200, "MODE_REG": 1})
    m.write("CNTRL_BITS", 1 << 6)  # RECORDBIT
    m.step(100)
    buf = m.sample_buffer()
    assert set(buf) == {"P_IST", "V_IST", "P_SOLL", "V_SOLL"}
    assert set(buf["V_SOLL"][0].tolist()) <= {0, 200} and buf["V_SOLL"][0][-1] == 200


_TAPS = {"KFF3": ("FF", 0), "KFF2": ("FF", 1), "KFF1": ("FF", 2), "KFF0": ("FF", 3),
         "KVB3": ("VB", 0), "KVB2": ("VB", 1), "KVB1": ("VB", 2), "KVB0": ("VB", 3)}


@pytest.mark.parametrize("name", list(_TAPS))
@pytest.mark.statements("mac050_141:3.2.89:1", "mac050_141:3.2.101:1", "mac050_141:3.2.118:1",
                        "mac050_141:3.2.119:1", "mac050_141:4.2.1:1", "mac050_141:4.2.1:7")
def test_each_feed_forward_and_feedback_tap_has_its_delay(name: str) -> None:
    """Manual 4.2, 3.2.89–3.2.105: FF(z) = KFF3 + KFF2 z⁻¹ + KFF1 z⁻² + KFF0 z⁻³ on FNC_OUT,
    VB(z) = KVB3 + … + KVB0 z⁻³ on V_IST (times GEARB): an impulse comes out of FF_OUT / VB_OUT
    after the tap's delay, scaled by it."""
    from jvl_gym.families.mac050_141.firmware.speed_loop import speed_regulator

    m = MotorArray("MAC140", n=1, seed=0)
    m.write_many({**dict.fromkeys(_TAPS, 0.0), "GEARB": 1.0, name: 0.5})
    r, s = m.regs[0], m.state[0]
    kind, delay = _TAPS[name]
    v_ist = m.table.lookup("V_IST").number
    out = []
    for k in range(5):
        r[v_ist] = 100 if (kind == "VB" and k == 0) else 0
        speed_regulator(r, s, 200.0 if (kind == "FF" and k == 0) else 0.0, False, 1023.0)
        out.append(int(m.read(f"{kind}_OUT")[0]))
    expected = [0] * 5
    expected[delay] = 100 if kind == "FF" else 50
    assert out == expected


@pytest.mark.statements("mac050_141:3.2.16:3", "mac050_141:3.2.126:1")
def test_i2t_trips_at_i2tlim_and_phase_comp_leads_the_field() -> None:
    """I2TLIM (manual 3.2.17): I2T_ERR when I2T passes it; a larger limit keeps the motor
    running. PHASE_COMP (3.2.126): the commutation angle leads by V_ELDEG·PHASE_COMP, so the
    same speed needs a different torque command at a different PHASE_COMP."""
    from jvl_gym.families.mac050_141 import constants as c

    m = MotorArray("MAC140", n=2, seed=0)
    m.write("I2TLIM", 200, index=0)
    m.write_many({"V_SOLL": 1600, "MODE_REG": 1})
    m.set_input(load_torque=0.3)
    m.step(600)
    err = m.read("ERR_STAT")
    assert err[0] & c.I2T_ERR and not err[1] & c.I2T_ERR
    assert m.read("I2T")[1] > 0
    p = MotorArray("MAC140", n=2, seed=0)
    p.write("PHASE_COMP", 0, index=0)
    p.write("PHASE_COMP", 40, index=1)
    p.write_many({"V_SOLL": 3000, "MODE_REG": 1})
    p.step(400)
    vf = p.read("VF_OUT")
    assert vf[0] != vf[1]


@pytest.mark.statements("mac050_141:3.2.18:2", "mac050_141:4.5.2:2")
def test_uit_trips_at_uitlim_only_above_52_volts() -> None:
    """UITLIM (manual 3.2.19): UIT_ERR when UIT passes it and the supply is above 52 V."""
    from jvl_gym.families.mac050_141 import constants as c

    m = MotorArray("MAC140", n=2, seed=0)
    m.write_many({"UITLIM": 1, "V_SOLL": 3000, "MODE_REG": 1})
    m.step(300)
    m.write("V_SOLL", -3000)  # braking feeds power back
    m.step(300)
    assert m.read("UIT").max() > 1
    assert not (m.read("ERR_STAT") & c.UIT_ERR).any()  # the default supply is below 52 V


@pytest.mark.statements("mac050_141:3.2.28:1", "mac050_141:3.2.35:1", "mac050_141:3.2.35:11",
                        "mac050_141:3.2.35:12", "mac050_141:4.1.1:2", "mac050_141:4.4.2:9")
def test_acc_and_dec_flags_and_dis_p_lim() -> None:
    """ERR_STAT bits 5/6 (manual 3.2.35): ACC_FLAG while the profile accelerates, DEC_FLAG
    while it decelerates; bit 14 DIS_P_LIM disables the position limits (no PLIM_ERR)."""
    from jvl_gym.families.mac050_141 import constants as c

    m = MotorArray("MAC140", n=1, seed=0)
    m.write_many({"A_SOLL": 5, "V_SOLL": 1000, "MODE_REG": 1})
    st = m.trace(["ERR_STAT"], 300)["ERR_STAT"][:, 0]
    assert st[5] & c.ACC_FLAG and not st[5] & c.DEC_FLAG and not st[-1] & c.ACC_FLAG
    m.write("V_SOLL", 0)
    st = m.trace(["ERR_STAT"], 20)["ERR_STAT"][:, 0]
    assert st[5] & c.DEC_FLAG
    lim = MotorArray("MAC140", n=2, seed=0)
    lim.write_many({"MIN_P_IST": -100, "MAX_P_IST": 100})
    lim.write("ERR_STAT", c.DIS_P_LIM, index=1)
    lim.write_many({"V_SOLL": 500, "MODE_REG": 1})
    lim.step(300)
    err = lim.read("ERR_STAT")
    assert err[0] & c.PLIM_ERR and not err[1] & c.PLIM_ERR


@pytest.mark.statements("mac050_141:3.2.160:2")
def test_uv_handle_go_passive() -> None:
    """UV_HANDLE bit 1 UV_GO_PASSIVE (manual 3.2.23): an under-voltage makes the motor
    passive."""
    from jvl_gym.families.mac050_141 import constants as c
    from jvl_gym.world import SupplyEvents, World

    m = MotorArray("MAC140", n=1, seed=0, viscous_friction=1e-3)
    m.write_many({"U_MIN_SUP": round(35 / 0.0537), "UV_HANDLE": c.UV_GO_PASSIVE,
                  "V_SOLL": 6000, "MODE_REG": c.V_MODE})
    m.run(0.3)
    assert m.read("MODE_REG")[0] == c.V_MODE
    m.world = World(supply=SupplyEvents([(0.0, 0.3, 20.0)], nominal=48.0, n=1))
    m.run(0.25)
    assert m.read("ERR_STAT")[0] & c.UV_DETECT
    assert m.read("MODE_REG")[0] in (c.STOP_MODE, c.INIT_MODE)
    m.run(1.0)
    assert m.read("MODE_REG")[0] == c.INIT_MODE

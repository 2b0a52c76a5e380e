"""The studio's engineering units (each family's unit conversions), mode and bit registers, and
the motion panel's logic on a simulated motor of each family."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym.families import families, family, family_of_motor
from jvl_gym.registers import from_raw
from jvl_gym.studio.motion import Motion, MotionError
from jvl_gym.studio.motor import SimMotor
from jvl_gym.studio.units_view import Kind, UnitsView


def _mac050_141(t: str) -> dict:
    u = family_of_motor(t).units
    m = family_of_motor(t).load_motor(t)
    return {
        "counts": lambda v: v / u.COUNTS_PER_REV,
        "1/16 count": lambda v: v / 16 / u.COUNTS_PER_REV,
        "1/16 count/sample": u.v_soll_to_rpm,
        "counts/sample": u.v_ist_to_rpm,
        "1/16 count/sample^2": u.a_soll_to_rpm_per_s,
        "1/1023 peak torque": lambda v: v / u.VF_FULL * m.peak_torque,
        "ADC counts": lambda v: v * m.amps_per_count,
        "ANINP": lambda v: v * u.ANINP_VOLTS / u.ANINP_FULL,
        "ANINP_OFFSET": lambda v: v * u.ANINP_VOLTS / u.ANINP_FULL,
        "53.7 mV": lambda v: v * u.U_SUPPLY_VOLTS_PER_UNIT,
        "1/2048 electrical turn": lambda v: v * 360 / u.ELDEG_PER_TURN,
    }


def _mac800(t: str) -> dict:
    u = family_of_motor(t).units
    m = family_of_motor(t).load_motor(t)
    return {
        "counts": lambda v: v / u.COUNTS_PER_REV,
        "1/16 count/sample": u.v_soll_to_rpm,
        "counts/sample": u.v_ist_to_rpm,
        "1/16 count/sample^2": u.a_soll_to_rpm_per_s,
        "1/1023 peak torque": lambda v: v / u.T_SOLL_FULL * m.peak_torque,
        "0.0048828 V": u.aninp_to_volts,
        "0.013428 V": u.u_24v_to_volts,
        "0.12207 degC": u.degc_to_celsius,
        "0.888798 V": u.u_bus_to_volts,
    }


def _mis(t: str) -> dict:
    u = family_of_motor(t).units
    return {
        "counts (1/409600 rev)": u.counts_to_rev,
        "0.01 RPM": u.v_soll_to_rpm,
        "RPM/s": lambda v: v,
        "5.87 mA": u.run_current_to_amps,
        "1.221 mV": u.analogue_to_volts,
        "26.525 mV": u.busvol_to_volts,
        "8.764 mV": u.cvi_to_volts,
        "2.27 degC": u.temp_to_celsius,
        "0.001 degC": lambda v: v * u.TEMP_HIGHRES_CELSIUS_PER_UNIT,
    }


#: family → its own conversions of a motor type, by register unit (or register name)
BY_FAMILY = {"mac050_141": _mac050_141, "mac800": _mac800, "mis": _mis}
#: a motor type of each family → its conversions
CONVERSIONS = {"MAC140": _mac050_141, "MAC800": _mac800, "MIS232": _mis}
#: every motor type of every family (the factors of some are the motor's own data)
EVERY_TYPE = [t for k in families() for t in family(k).motor_types()]


def test_the_conversions_cover_every_family():
    """Every packaged family (a test's own registered family, such as the toy family of the
    family-contract tests, has no conversions here)."""
    assert set(BY_FAMILY) == set(families()) - {"toy"}


@pytest.mark.parametrize("motor_type", EVERY_TYPE)
def test_every_engineering_value_is_the_familys_conversion(motor_type):
    view = UnitsView(motor_type)
    expected = BY_FAMILY[family_of_motor(motor_type).key](motor_type)
    shown = 0
    for reg in view.facts.table:
        if reg.access.value == "reserved" or view.unit_of(reg) is None:
            continue
        key = reg.name if reg.name in expected else reg.unit
        assert key in expected, f"{reg.name} [{reg.unit}] shown in {view.unit_text(reg)}"
        for raw in np.linspace(reg.raw_min, reg.raw_max, 7).round().astype(int):
            value = float(from_raw(reg, int(raw)))
            assert view.value(reg, int(raw)) == pytest.approx(expected[key](value), rel=1e-12,
                                                              abs=1e-12), reg.name
            # a value typed in the engineering unit is the register value it came from
            assert view.to_register(reg, view.value(reg, int(raw))) == pytest.approx(
                value, abs=1.0 / reg.scale)
        shown += 1
    assert shown >= 8
    view.raw = True  # the raw toggle: every register in its own unit
    assert all(view.unit_of(r) is None for r in view.facts.table)


@pytest.mark.parametrize("motor_type, register, unit", [
    ("MAC140", "V_SOLL", "rpm"), ("MAC140", "P_IST", "turns"), ("MAC140", "T_SOLL", "N·m"),
    ("MAC800", "DEGC", "°C"), ("MAC800", "U_BUS", "V"), ("MIS232", "RUN_CURRENT", "A"),
    ("MIS232", "V_IST", "rpm"), ("MIS232", "TEMP", "°C")])
def test_the_units_an_engineer_reads(motor_type, register, unit):
    view = UnitsView(motor_type)
    assert view.unit_text(view.facts.table.lookup(register)) == unit


def test_positions_in_degrees_on_request():
    view = UnitsView("MAC140", prefer={"°"})
    reg = view.facts.table.lookup("P_IST")
    assert view.unit_text(reg) == "°"
    assert view.value(reg, 1024) == pytest.approx(90.0)  # a quarter of 4096 counts


@pytest.mark.parametrize("motor_type", sorted(CONVERSIONS))
def test_modes_as_names_and_bits_as_boxes(motor_type):
    view = UnitsView(motor_type)
    table = view.facts.table
    mode = table.lookup(view.facts.mode_register)
    assert view.kind(mode) == Kind.MODE
    assert view.modes(mode)[1] == f"{view.facts.mode_names[1]} (1)"
    for name in family_of_motor(motor_type).constants.MODE_VALUED_REGISTERS:
        assert view.kind(table.lookup(name)) == Kind.MODE
    bits = [r for r in table if view.kind(r) == Kind.BITS]
    assert bits
    reg = bits[0]
    boxes = view.bits(reg)
    first = boxes[0].first
    assert view.bits_set(reg, 1 << first) == {f.first: f.first == first for f in boxes}


def test_a_bit_box_changes_its_bit_only():
    view = UnitsView("MAC140")
    reg = view.facts.table.lookup("CNTRL_BITS")
    rec = next(f.first for f in view.bits(reg) if f.name.startswith("RECORD"))
    assert view.with_bit(reg, 0b1, rec, True) == 0b1 | 1 << rec
    assert view.with_bit(reg, 0b1 | 1 << rec, rec, False) == 0b1
    with pytest.raises(ValueError, match="read-only"):
        view.with_bit(view.facts.table.lookup("V_IST"), 0, 0, True)
    with pytest.raises(ValueError, match="names no bit"):
        view.with_bit(reg, 0, 15, True)


# ---------------------------------------------------------------------- motion
MOTORS = ["MAC140", "MAC800", "MIS232"]


@pytest.fixture(scope="module", params=MOTORS)
def motor(request) -> SimMotor:
    return SimMotor(request.param, 1)


def _settle(m: SimMotor, seconds: float) -> None:
    m.step(int(seconds * m.facts.outer_hz))


def test_run_at_speed_jog_and_release(motor):
    mo = Motion(motor)
    reg = motor.register(motor.facts.constants.MOTION_REGISTERS["velocity"])
    lsb = max(2.0, mo.view.value(reg, 1))  # one count of the velocity register [rpm]
    mo.passive()
    _settle(motor, 0.05)
    mo.run(120.0)
    assert motor.read_raw(motor.facts.mode_register) in mo.modes["velocity"]
    _settle(motor, 1.5)
    assert mo.speed() == pytest.approx(120.0, rel=0.02, abs=lsb)
    mo.jog_start(-1, 60.0)
    assert mo.jogging == -1
    _settle(motor, 1.5)
    assert mo.speed() == pytest.approx(-60.0, rel=0.02, abs=lsb)
    mo.jog_stop()  # the button released (or the page gone)
    assert mo.jogging == 0 and motor.read("V_SOLL") == 0
    _settle(motor, 1.5)
    assert mo.speed() == pytest.approx(0.0, abs=lsb)
    mo.passive()


def test_moves_absolute_and_relative(motor):
    mo = Motion(motor)
    mo.enable()
    assert motor.read_raw(motor.facts.mode_register) in mo.modes["position"]
    start = mo.position()
    mo.move_absolute(start + 2.0, 300.0)
    _settle(motor, 3.0)
    assert mo.position() == pytest.approx(start + 2.0, abs=0.01)
    mo.move_relative(-0.5, 300.0)
    _settle(motor, 3.0)
    assert mo.position() == pytest.approx(start + 1.5, abs=0.01)
    mo.passive()


def test_a_refused_motion_changes_nothing(motor):
    mo = Motion(motor)
    mo.passive()
    before = {n: motor.read_raw(n) for n in ("V_SOLL", "P_SOLL", motor.facts.mode_register)}
    hi = mo.limits().speed[1]
    with pytest.raises(MotionError, match="speed"):
        mo.run(hi * 2 + 1)
    with pytest.raises(MotionError, match="direction"):
        mo.jog_start(0, 10.0)
    motor.write("MIN_P_IST", motor.read("P_IST") - 1)
    motor.write("MAX_P_IST", motor.read("P_IST") + 1)
    try:
        lim = mo.limits()
        assert lim.position is not None and "position" in lim.text()
        with pytest.raises(MotionError, match="software limits"):
            mo.move_absolute(lim.position[1] + 1.0, 100.0)
    finally:
        motor.write("MIN_P_IST", 0)
        motor.write("MAX_P_IST", 0)
    assert {n: motor.read_raw(n) for n in before} == before
    assert mo.limits().position is None


def test_home_modes_are_the_familys(motor):
    mo = Motion(motor)
    modes = mo.home_modes()
    assert modes and all("home" in n.lower() or "zero" in n.lower() for n in modes.values())
    with pytest.raises(MotionError, match="none of"):
        mo.home(1)


# ---------------------------------------------------------------------- parameters
@pytest.mark.parametrize("motor_type", ["MAC140", "MIS232"])
def test_compare_with_flash_undo_redo_and_write_to_flash(motor_type):
    from jvl_gym.studio import parameters as P

    m = SimMotor(motor_type, 3)
    name = "KVOUT" if motor_type == "MAC140" else "A_SOLL"
    assert P.flash_changes(m) == []  # a new motor is its defaults, which its flash holds
    before = m.read(name)
    hist = P.History(m)
    assert hist.edit(name, str(before * 2)).ok
    diffs = P.flash_changes(m)
    assert [(d.name, d.base, d.now) for d in diffs] == [(name, before, before * 2)]
    assert "→" in P.describe(diffs[0])
    assert hist.undo().ok and m.read(name) == before and P.flash_changes(m) == []
    assert not hist.undo().ok  # nothing left to undo
    assert hist.redo().ok and m.read(name) == before * 2
    assert not hist.redo().ok
    refused = hist.edit(name, "1e12")
    assert not refused.ok and len(hist.done) == 1  # a refused edit is no step of the history
    assert P.write_flash(m).ok
    assert P.flash_changes(m) == [] and m.read(name) == before * 2
    # against the defaults, the change shows; against a setup file of the motor, nothing does
    assert [d.name for d in P.changed(P.compare(m, P.default_values(m)))] == [name]
    from jvl_gym.studio.registers import setup_text
    assert P.changed(P.compare(m, P.file_values(m, setup_text(m)))) == []

"""MIS inputs: the analogue filter example of MIS manual §2.3.5, the digital input filter
(§2.2.7, §8.2.75–76), and the task interface a compiled task sees."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mis.firmware.inputs import analogue_filter_step


@pytest.mark.statements(
    "mis:8.2.53:2", "mis:8.2.54:2", "mis:8.2.55:2", "mis:2.3.5:3", "mis:2.3.5:4", "mis:2.3.5:5",
    "mis:2.3.5:6")
def test_analogue_filter_example_of_the_manual() -> None:
    """§2.3.5: confidence 0 … 500, max slope 10, filter 8/64, old value 0: samples 100, 100,
    100, 800 give 1.25, 2.5, 3.75, 3.75; from 95.0 samples of 100 give 95.625, 96.171875,
    96.65, 97.07, 97.44, 97.76, 98.04 … approaching 100.0."""
    args = (0.0, 500.0, 10.0, 8.0)
    out, x = [], 0.0
    for raw in (100, 100, 100, 800):
        x = analogue_filter_step(x, raw, *args)
        out.append(x)
    assert out == [1.25, 2.5, 3.75, 3.75]
    x, tail = 95.0, []
    for _ in range(48):
        x = analogue_filter_step(x, 100.0, *args)
        tail.append(x)
    assert tail[:2] == [95.625, 96.171875]
    manual = [96.65, 97.07, 97.44, 97.76, 98.04, 98.28, 98.49, 98.68, 98.85, 99.00, 99.12,
              99.23, 99.33, 99.41, 99.48, 99.55, 99.60, 99.65, 99.70, 99.74, 99.77, 99.80,
              99.82, 99.84, 99.86, 99.88, 99.90, 99.91, 99.92, 99.93, 99.94, 99.95, 99.95,
              99.96, 99.96, 99.97, 99.97, 99.98, 99.98, 99.98, 99.98, 99.98, 99.99, 99.99,
              99.99, 100.0]
    # the manual prints two decimals (its last values are rounded up: 99.99 → 100.0)
    np.testing.assert_allclose(tail[2:], manual, atol=0.011)
    assert all(np.diff(tail) > 0) and tail[-1] < 100.0


@pytest.mark.statements(
    "mis:8.2.45:2", "mis:8.2.46:2", "mis:8.2.53:2", "mis:8.2.54:2", "mis:8.2.55:2")
def test_analogue_inputs_in_the_registers() -> None:
    m = MotorArray("MIS232", n=1)
    m.write_many({"AFZUP_CONFMAX": 500, "AFZUP_MAXSLOPE": 10, "AFZUP_FILTER": 8,
                  "AFZUP_WRITEBITS": 255})  # to every input (§8.2.50)
    m.set_input(analog1=100 * 5.0 / 4095)  # 100 units on IO1
    tr = m.trace(["ANALOGUE_INPUT1", "ANALOGUE_FILTERED1"], 40)
    assert np.all(tr["ANALOGUE_INPUT1"][:, 0] == 100)
    filt = tr["ANALOGUE_FILTERED1"][:, 0]
    assert filt[8] == 0 and filt[9] == 1 and filt[19] == 3 and filt[29] == 4  # every 10 ms


@pytest.mark.statements(
    "mis:8.2.16:3", "mis:8.2.16:4", "mis:8.2.69:2", "mis:8.2.75:2", "mis:8.2.76:2", "mis:6.5.9:2",
    "mis:2.2.2:1", "mis:2.2.5:1")
def test_digital_input_filter() -> None:
    m = MotorArray("MIS232", n=1)
    m.write_many({"INPUT_FILTER_MASK": 0b10, "INPUT_FILTER_CNT": 5})
    m.set_input(digital_inputs=0b11)
    tr = m.trace(["INPUTS"], 8)["INPUTS"][:, 0]
    assert tr.tolist() == [1, 1, 1, 1, 3, 3, 3, 3]  # IO2 after 5 ms stable, IO1 at once
    m.write("IOSETUP", 0b1)  # IO1 active low
    m.step(1)
    assert m.read("INPUTS")[0] == 2


def test_task_interface_reads_the_truth() -> None:
    from numba import njit

    from jvl_gym.engine.view import EngineView
    from jvl_gym.families.mis import task

    @njit
    def probe(arrays, out):
        view = EngineView(*arrays)
        task.set_load_torque(view, 0, 0.1)
        task.set_load_inertia(view, 0, 1e-5)
        task.set_reg(view, 0, task.R.V_SOLL, 10**9)  # saturated to the register's range
        out[0] = task.rotor_angle(view, 0)
        out[1] = task.lost_steps(view, 0)
        out[2] = task.copper_energy(view, 0)
        out[3] = task.reg(view, 0, task.R.V_SOLL)

    m = MotorArray(task.DEFAULT_MOTOR_TYPE, n=1)
    m.write_many({"V_SOLL": 1000, "MODE_REG": 1})
    m.run(0.5)
    out = np.zeros(4)
    probe(m.engine_view(), out)
    assert out[0] == pytest.approx(m.position_rad[0])
    assert out[1] == m.lost_steps[0] == 0
    assert out[2] > 0.0 and out[3] == 300000
    assert m.inputs[0, 0] == 0.1 and m.parameters["load_inertia"][0] == 1e-5

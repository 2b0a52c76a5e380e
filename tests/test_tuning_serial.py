"""jvl-tune over the serial protocol: identification and register writes through the twin.

The twins here run on a simulated clock the procedure advances (``TwinServer(run_clock=False)``
and ``clock=`` the twin's ``advance``): the motor's time passes only when the procedure waits,
so the results do not depend on how busy the machine is. The real-time clock over a slow link is
tested in ``test_tuning_slow_link.py``.
"""

from __future__ import annotations

import numpy as np
import pytest
from tuning.records import RecordError
from tuning.serial_source import SerialMotor, autotune_over_serial

from jvl_gym import MotorArray
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.serving.transport import TwinServer


def _served(m: MotorArray) -> TwinServer:
    """The twin of ``m`` at address 19 over TCP, on a simulated clock."""
    return TwinServer(Twin(m, [19]), tcp=("127.0.0.1", 0), run_clock=False).start()


@pytest.fixture()
def twin_server():
    m = MotorArray("MAC140", n=1, seed=0, load_inertia=30e-6, record_length=64)
    server = _served(m)
    try:
        yield server, m
    finally:
        server.stop()


def test_autotune_over_the_twin_identifies_and_writes(twin_server):
    server, m = twin_server
    url = server.endpoint("mactalk", "tcp").url
    ident, result = autotune_over_serial(url, "MAC140", address=19, n_coil=64, n_mech=64,
                                         write=True, clock=server.twin.advance)
    cfg = m.motor_configs[0]
    assert ident.coil.R_line == pytest.approx(2 * cfg.phase_resistance, rel=0.03)
    assert ident.mechanics.J == pytest.approx(cfg.rotor_inertia + 30e-6, rel=0.08)
    for name, value in result.chosen.registers.items():  # written and read back (MacTalk)
        assert m.read(name)[0] == pytest.approx(value, abs=1 / 256)


def test_autotune_over_the_twin_with_the_firmware_record_length():
    # `jvl-gym serve` records 11 samples by default (manual 4.4.9/4.4.10): the procedure
    # combines several short records and still finds the inertia
    load = 30e-6
    m = MotorArray("MAC140", n=1, seed=0, load_inertia=load)
    server = _served(m)
    try:
        ident, result = autotune_over_serial(server.endpoint("mactalk", "tcp").url, "MAC140",
                                             address=19, clock=server.twin.advance)
    finally:
        server.stop()
    assert all(r.n == 11 for r in ident.records) and len(ident.records) > 20
    J = m.motor_configs[0].rotor_inertia + load
    assert ident.mechanics.J == pytest.approx(J, rel=0.05)
    assert ident.mechanics.coulomb >= 0.0
    assert result.chosen.design is not None and result.reason


def test_serial_record_length_is_checked(twin_server):
    from jvl_gym.protocol import MacTalkClient

    server, _ = twin_server
    with MacTalkClient(server.endpoint("mactalk", "tcp").url, address=19) as client:
        sm = SerialMotor(client, "MAC140", clock=server.twin.advance)
        sm.set_record_length(100)
        sm.write("UMEAS", 50)
        sm.write("MODE_REG", 8)
        sm.step(10)
        with pytest.raises(RecordError, match="recorded 64 samples"):
            sm.sample_buffer()
        assert np.asarray(sm.read("MODE_REG"))[0] == 0


def test_resonance_over_the_twin_with_its_default_record_length():
    # a MAC140 with 4·J_m behind a coupling resonating at 70 Hz; `jvl-gym serve`'s default
    # TESTU/TESTA record length (11) does not limit the free sample-buffer recording (895
    # samples), and the step is found in the record
    from types import SimpleNamespace

    from tuning.identify_resonance import coupling_of, identify_resonance
    from tuning.models import MotorData

    from jvl_gym.protocol import MacTalkClient

    md = MotorData.from_config("MAC140")
    j_l, k, d = coupling_of(md.J_m, 4.0, 70.0, 0.02)
    m = MotorArray("MAC140", n=1, seed=0, load_inertia=j_l, coupling_stiffness=k,
                   coupling_damping=d)
    server = _served(m)
    J = md.J_m + j_l
    ident = SimpleNamespace(motor=md, mechanics=SimpleNamespace(J=J, ci={"J": (0.98 * J,
                                                                                1.02 * J)}))
    try:
        with MacTalkClient(server.endpoint("mactalk", "tcp").url, address=19) as client:
            sm = SerialMotor(client, "MAC140", clock=server.twin.advance)
            est = identify_resonance(sm, [ident])[0]
    finally:
        server.stop()
    assert est.detected
    assert est.f_res == pytest.approx(70.0, rel=0.05)
    assert est.ci["f_res"][0] <= 70.0 <= est.ci["f_res"][1]
    assert m.read("MODE_REG")[0] == 0


def test_cli_autotune_port_resonance_writes_the_kept_notch(tmp_path, monkeypatch):
    # `jvl-tune autotune --port --resonance --write` on a twin MAC140 with 4·J_m behind a
    # coupling at 90 Hz: the two-mass step runs over MacTalk and its notch reaches the motor
    # (the command's run over the port, on the twin's simulated clock)
    import functools

    import tuning.serial_source as serial_source
    from tuning.cli import app
    from tuning.identify_resonance import coupling_of
    from tuning.models import MotorData
    from typer.testing import CliRunner

    md = MotorData.from_config("MAC140")
    j_l, k, d = coupling_of(md.J_m, 4.0, 90.0, 0.02)
    m = MotorArray("MAC140", n=1, seed=0, load_inertia=j_l, coupling_stiffness=k,
                   coupling_damping=d)
    server = _served(m)
    monkeypatch.setattr(serial_source, "autotune_over_serial", functools.partial(
        serial_source.autotune_over_serial, clock=server.twin.advance))
    try:
        res = CliRunner().invoke(app, [
            "autotune", "--motor", "MAC140", "--port", server.endpoint("mactalk", "tcp").url,
            "--address", "19", "--resonance", "--write", "--accept",
            "--out", str(tmp_path)])
    finally:
        server.stop()
    assert res.exit_code == 0, res.output
    report = (tmp_path / "report.txt").read_text()
    assert "Two-mass load" in report and "kept notch" in report
    f_res = float(report.split("  resonance ")[1].split(" Hz")[0])
    assert f_res == pytest.approx(90.0, rel=0.05)
    assert m.read("KVFY2")[0] != 0.0  # the notch fills VF's free order in the motor
    assert m.read("MODE_REG")[0] == 0  # left passive


def test_a_record_on_a_simulated_clock_is_awaited_in_motor_time(twin_server, monkeypatch):
    """However slowly this machine answers (here: every look at the wall clock finds 100 s
    more), the wait for a record on a simulated clock ends when the motor has recorded."""
    import itertools
    import time
    import types

    from tuning import serial_source

    from jvl_gym.protocol import MacTalkClient

    server, _ = twin_server
    ticks = itertools.count(0.0, 100.0)
    monkeypatch.setattr(serial_source, "time", types.SimpleNamespace(
        monotonic=lambda: next(ticks), sleep=time.sleep))
    with MacTalkClient(server.endpoint("mactalk", "tcp").url, address=19) as client:
        sm = SerialMotor(client, "MAC140", clock=server.twin.advance)
        sm.set_record_length(64)
        sm.write("UMEAS", 50)
        sm.write("MODE_REG", 8)
        buf = sm.sample_buffer()
    assert all(v.shape == (1, 64) for v in buf.values())

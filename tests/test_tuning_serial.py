"""jvl-tune over the serial protocol: identification and register writes through the twin."""

from __future__ import annotations

import numpy as np
import pytest
from tuning.records import RecordError
from tuning.serial_source import SerialMotor, autotune_over_serial

from jvl_gym import MotorArray
from jvl_gym.protocol.transport import TwinServer
from jvl_gym.protocol.twin import Twin


@pytest.fixture()
def twin_server():
    m = MotorArray("MAC140", n=1, seed=0, load_inertia=30e-6, record_length=64)
    server = TwinServer(Twin(m, [19]), speed=25.0, tcp=("127.0.0.1", 0)).start()
    try:
        yield server, m
    finally:
        server.stop()


def test_autotune_over_the_twin_identifies_and_writes(twin_server):
    server, m = twin_server
    url = server.endpoint("mactalk", "tcp").url
    ident, design = autotune_over_serial(url, "MAC140", address=19, time_scale=25.0,
                                         n_coil=64, n_mech=64, write=True)
    cfg = m.motor_configs[0]
    assert ident.coil.R_line == pytest.approx(2 * cfg.phase_resistance, rel=0.03)
    assert ident.mechanics.J == pytest.approx(cfg.rotor_inertia + 30e-6, rel=0.08)
    for name, value in design.registers.items():  # written and read back through MacTalk
        assert m.read(name)[0] == pytest.approx(value, abs=1 / 256)


def test_autotune_over_the_twin_with_the_firmware_record_length():
    # `jvl-gym serve` records 11 samples by default (manual 4.4.9/4.4.10): the procedure
    # combines several short records and still finds the inertia
    load = 30e-6
    m = MotorArray("MAC140", n=1, seed=0, load_inertia=load)
    server = TwinServer(Twin(m, [19]), speed=25.0, tcp=("127.0.0.1", 0)).start()
    try:
        ident, design = autotune_over_serial(server.endpoint("mactalk", "tcp").url, "MAC140",
                                             address=19, time_scale=25.0)
    finally:
        server.stop()
    assert all(r.n == 11 for r in ident.records) and len(ident.records) > 20
    J = m.motor_configs[0].rotor_inertia + load
    assert ident.mechanics.J == pytest.approx(J, rel=0.05)
    assert ident.mechanics.coulomb >= 0.0
    assert design.acceptance is not None and design.acceptance.reason


def test_serial_record_length_is_checked(twin_server):
    from jvl_gym.protocol import MacTalkClient

    server, _ = twin_server
    with MacTalkClient(server.endpoint("mactalk", "tcp").url, address=19) as client:
        sm = SerialMotor(client, "MAC140", time_scale=25.0)
        sm.set_record_length(100)
        sm.write("UMEAS", 50)
        sm.write("MODE_REG", 8)
        sm.step(10)
        with pytest.raises(RecordError, match="recorded 64 samples"):
            sm.sample_buffer()
        assert np.asarray(sm.read("MODE_REG"))[0] == 0

"""JVL's own client against the twin: the MacTalk code of the ``jvlmotor`` package
(JVL A/S, MIT; ``JVLMotor.Protocols.MacTalkProtocol``, written for the MAC400+ and MIS motors,
whose read reply names the register) reads and writes P_SOLL, V_SOLL and MODE_REG of a MIS and
of a MAC800 twin over a pseudo-terminal and reads back what it wrote.

``jvlmotor`` is installed without its dependencies (``pip install --no-deps jvlmotor``: they pin
pymodbus 3.5.2 and include Windows-only packages); its ``MotorCom`` front end imports them, so
the test drives ``MacTalkProtocol``, the class ``MotorCom.read``/``write`` call, directly. The test
is skipped where ``jvlmotor`` is not installed.
"""

from __future__ import annotations

import os

import pytest

from jvl_gym import MotorArray
from jvl_gym.families import families, mis
from jvl_gym.protocol.mactalk.dialect import MACTALK32
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.serving.transport import TwinServer
from protocol_fakes import RegisterArray

mactalk = pytest.importorskip("JVLMotor.Protocols.MacTalkProtocol",
                              reason="jvlmotor is not installed (pip install --no-deps jvlmotor)")
smc85 = pytest.importorskip("JVLMotor.Motors.SMC85Motor")


def _pty_available() -> bool:
    try:
        fd1, fd2 = os.openpty()
    except OSError:
        return False
    os.close(fd1)
    os.close(fd2)
    return True


pytestmark = pytest.mark.skipif(not _pty_available(), reason="pseudo-terminals are unavailable")

ADDRESS = 7


@pytest.fixture(params=["MIS231", "MAC800"])
def jvl(request):
    """A MIS or MAC800 twin at address 7 on a pty, and jvlmotor's MacTalk client on it."""
    key = "mis" if request.param.startswith("MIS") else "mac800"
    m = (MotorArray(request.param, n=1, seed=0) if key in families()
         else RegisterArray(mis.REGISTERS, 1))
    twin = Twin(m, [ADDRESS], dialect=MACTALK32)
    with TwinServer(twin, pty=True, run_clock=False) as server:
        client = mactalk.MacTalkProtocol(com_type="Serial",
                                         port=server.endpoint("mactalk", "pty").path,
                                         motor_address=ADDRESS, motor="MIS", motor_version="85")
        try:
            yield client, twin
        finally:
            client.communication.close()


def _number(name: str) -> int:
    return smc85.SMC85Motor().registers[name][0]


def test_jvlmotor_register_numbers_are_the_mis_and_mac800_tables() -> None:
    from jvl_gym.families.mac800 import REGISTERS as MAC800

    for name in ("P_SOLL", "V_SOLL", "MODE_REG", "P_IST"):
        assert _number(name.lower()) == mis.REGISTERS.lookup(name).number
    for name in ("P_SOLL", "V_SOLL", "MODE_REG"):
        assert _number(name.lower()) == MAC800.lookup(name).number


@pytest.mark.parametrize("name, values", [
    ("p_soll", [250_000, -1_000, 2**31 - 1, -(2**31)]),
    ("v_soll", [1500, -2500, 300_000]),
    ("mode_reg", [1, 2, 0]),
])
def test_jvlmotor_writes_and_reads_back(jvl, name: str, values: list[int]) -> None:
    client, twin = jvl
    reg = _number(name)
    for v in values:
        # MotorCom.write hands the protocol the value masked to 32 bits
        assert client.write(reg, v & 0xFFFFFFFF) == 0
        assert client.read(reg) == v
        assert int(twin.m.read_raw(reg)[0]) == v


def test_jvlmotor_sees_a_refused_write_as_no_accept(jvl) -> None:
    client, twin = jvl
    reg = _number("mode_reg")
    assert client.write(reg, 1) == 0
    assert client.write(reg, 99) is None  # beyond MODE_REG's range: no accept
    assert client.read(reg) == 1

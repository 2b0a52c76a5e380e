"""Layer setting services of the simulated MIS with ``canopen``'s LSS master (MIS manual
§11.7): switch mode, inquire, configure node id and bit timing, store."""

from __future__ import annotations

from collections.abc import Iterator

import canopen
import pytest

from canopen_rig import Rig


@pytest.fixture
def rig() -> Iterator[Rig]:
    r = Rig()
    yield r
    r.close()


def test_lss_node_id_change_stored_and_taken_at_reset(rig: Rig) -> None:
    lss = rig.net.lss
    assert rig.request(0x7E5, bytes([0x5E]) + bytes(7), 0x7E4) is None  # waiting: no answer
    lss.send_switch_state_global(lss.CONFIGURATION_STATE)
    assert lss.inquire_node_id() == 5
    assert lss.inquire_lss_address(0x5A) == 0x117
    assert lss.inquire_lss_address(0x5B) == int(rig.m.read_raw("MOTORTYPE")[0])
    with pytest.raises(Exception, match="(?i)error"):
        lss.configure_node_id(0)
    lss.configure_node_id(7)
    lss.configure_bit_timing(3)  # 250 kbit/s
    lss.store_configuration()
    lss.send_switch_state_global(lss.WAITING_STATE)
    assert int(rig.m.read_raw("FBUS_NODE_ID")[0]) == 7
    assert int(rig.m.read_raw("FBUS_BAUD")[0]) == 3
    assert rig.m.flash_image(0)[166] == 7 and rig.m.flash_image(0)[167] == 3
    rig.clear()
    rig.node(5).nmt.send_command(0x81)  # reset node: the motor restarts from its flash
    assert rig.sent(0x707) == [b"\x00"]
    assert rig.node(7).sdo[0x1014].raw == 0x87
    assert rig.node(7).sdo[0x2012][166].raw == 7


def test_lss_switch_selective_and_refusals(rig: Rig) -> None:
    lss = rig.net.lss
    slave = rig.slave
    identity = [slave.read_value(0x1018, k) for k in (1, 2, 3, 4)]
    assert lss.send_switch_state_selective(*identity)
    wrong = rig.request(0x7E5, bytes([0x13, 0, 5]) + bytes(5), 0x7E4)
    assert wrong is not None and wrong[:2] == bytes([0x13, 1])  # rate code 5 is reserved
    assert rig.request(0x7E5, bytes([0x5E]), 0x7E4) is None  # not 8 bytes: ignored
    lss.send_switch_state_global(lss.WAITING_STATE)
    with pytest.raises(canopen.lss.LssError):  # no node of that identity answers
        lss.send_switch_state_selective(identity[0] + 1, *identity[1:])
    assert int(rig.m.read_raw("FBUS_BAUD")[0]) == 2

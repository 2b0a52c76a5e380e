"""Random frames at a CANopen slave of the simulated MIS (MIS manual §11.9.4): registers and
flash change only by writes the slave confirms, and the slave never fails."""

from __future__ import annotations

from typing import Any

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jvl_gym import MotorArray
from jvl_gym.protocol.canopen.facts import facts_of
from jvl_gym.protocol.canopen.objects import build_dictionary
from jvl_gym.protocol.canopen.slave import CanopenSlave

M = MotorArray("MIS232", n=1)
FACTS = facts_of(M)
OD = build_dictionary(M.table, FACTS)
SENT: list[tuple[int, bytes]] = []
SLAVE = CanopenSlave(M, 0, OD, FACTS, lambda cob, data, remote: SENT.append((cob, data)))
SLAVE.boot()

#: COB-IDs of interest: NMT, SYNC, the default PDOs, SDO, guarding, LSS, and any other
COBS = st.one_of(st.sampled_from([0x000, 0x080, 0x205, 0x305, 0x405, 0x505, 0x605, 0x705,
                                  0x7E5, 0x185]), st.integers(0, 0x7FF))
#: SDO requests biased to real objects: command byte, index, sub-index, 4 data bytes
SDO = st.builds(lambda cmd, index, sub, data: bytes([cmd]) + index.to_bytes(2, "little")
                + bytes([sub]) + data,
                st.integers(0, 255),
                st.sampled_from([0x1000, 0x1003, 0x1005, 0x1010, 0x1011, 0x1017, 0x1400,
                                 0x1600, 0x1800, 0x1A00, 0x2010, 0x2012, 0x2013, 0x2014,
                                 0x2018, 0x2100, 0x6040, 0x6060, 0x607A, 0x6098, 0x60FE]),
                st.integers(0, 255), st.binary(min_size=4, max_size=4))
FRAMES = st.one_of(st.tuples(COBS, st.binary(max_size=8), st.booleans()),
                   st.tuples(st.just(0x605), SDO, st.just(False)))


def _flash() -> dict[int, int]:
    return dict(M.flash_image(0))


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(frames=st.lists(FRAMES, min_size=1, max_size=6))
def test_random_frames_change_only_by_confirmed_writes(frames: list[Any]) -> None:
    for cob, data, remote in frames:
        regs, flash = M.regs.copy(), _flash()
        SENT.clear()
        SLAVE.on_frame(cob, data, remote)
        replies = [d for c, d in SENT if c == 0x580 + SLAVE.node_id]
        confirmed = any(d[0] in (0x60, 0x20, 0x30) for d in replies)
        reset = cob == 0 and len(data) == 2 and data[0] in (0x81, 0x82)
        lss_store = cob == 0x7E5 and any(c == 0x7E4 and d[:2] == b"\x17\x00" for c, d in SENT)
        pdo = cob in (0x205, 0x305, 0x405, 0x505) and SLAVE.operational
        if not (confirmed or reset or lss_store or pdo):
            assert np.array_equal(M.regs, regs), (hex(cob), data.hex())
        if not (lss_store or (confirmed and data[1:3] == b"\x10\x10")):
            assert _flash() == flash, (hex(cob), data.hex())
        for c, d in SENT:
            assert 0 < len(d) <= 8 or c == 0x080
            if c == 0x580 + SLAVE.node_id and d[0] == 0x80:  # an abort names a §11.9.4 code
                code = int.from_bytes(d[4:8], "little")
                assert code >> 24 in (0x05, 0x06, 0x08)

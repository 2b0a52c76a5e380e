"""FlexMAC codec (manual 5.2.2): the byte examples in both directions, the index tables, and the
malformed messages."""

from __future__ import annotations

import pytest

from jvl_gym.protocol import FrameError
from jvl_gym.protocol.mactalk import flexmac as fx


def h(text: str) -> bytes:
    """Bytes from the manual's notation (``50h,50h``, ``063H, 0F3H``) or plain hex."""
    tokens = text.replace(",", " ").split()
    return bytes(int(t.rstrip("hH"), 16) for t in tokens)


V_SOLL_INDEX = h("063H, 063H, 063H, 047H, 0B8H, 005H, 0FAH")
V_SOLL_NUMBER = h("060H, 060H, 060H, 009H, 0F6H, 047H, 0B8H, 005H, 0FAH")
V_SOLL_ADDRESS = h("060H, 060H, 060H, 000H, 0FFH, 012H, 0EDH, 004H, 0FBH, 047H, 0B8H, 005H, 0FAH")
P_IST_INDEX = h("0F3H, 0F3H, 0F3H")
P_IST_NUMBER = h("0F0H, 0F0H, 0F0H, 00EH, 0F1H")
P_IST_ADDRESS = h("0F0H, 0F0H, 0F0H, 000H, 0FFH, 01CH, 0E3H, 004H, 0FBH")
USE_FASTMAC = h("07FH, 07FH, 07FH")


def test_example_write_v_soll_by_index() -> None:
    assert fx.encode_write(0x0547, index=3) == V_SOLL_INDEX
    msg = fx.decode(V_SOLL_INDEX)
    assert msg == fx.FlexWrite(False, b"\x47\x05", index=3)
    assert msg.register == 5  # V_SOLL


def test_example_write_v_soll_by_register_number() -> None:
    assert fx.flex_number(5) == 0x09
    assert fx.encode_write(0x0547, number=0x09) == V_SOLL_NUMBER
    msg = fx.decode(V_SOLL_NUMBER)
    assert msg == fx.FlexWrite(False, b"\x47\x05", number=9) and msg.register == 5


def test_example_write_v_soll_by_address() -> None:
    assert fx.flex_address(5) == 0x0412
    assert fx.encode_write(0x0547, address=0x0412) == V_SOLL_ADDRESS
    msg = fx.decode(V_SOLL_ADDRESS)
    assert msg == fx.FlexWrite(False, b"\x47\x05", address=0x0412) and msg.register == 5


def test_example_read_p_ist_three_forms() -> None:
    assert fx.encode_read(long=True, index=3) == P_IST_INDEX
    assert fx.decode(P_IST_INDEX) == fx.FlexRead(True, index=3)
    assert fx.flex_number(10) == 0x0E and fx.flex_address(10) == 0x041C
    assert fx.encode_read(long=True, number=0x0E) == P_IST_NUMBER
    assert fx.decode(P_IST_NUMBER) == fx.FlexRead(True, number=0x0E)
    assert fx.encode_read(long=True, address=0x041C) == P_IST_ADDRESS
    assert fx.decode(P_IST_ADDRESS) == fx.FlexRead(True, address=0x041C)
    for raw in (P_IST_INDEX, P_IST_NUMBER, P_IST_ADDRESS):
        assert fx.decode(raw).register == 10


def test_example_switch_to_fastmac() -> None:
    assert fx.encode_use_fastmac() == USE_FASTMAC
    msg = fx.decode(USE_FASTMAC)
    assert msg.use_fastmac and msg.register is None


def test_header_byte_format() -> None:
    assert fx.header_byte(read=False, long=False) == fx.W2 == 0x60
    assert fx.header_byte(read=False, long=True) == fx.W4 == 0xE0
    assert fx.header_byte(read=True, long=False) == fx.R2 == 0x70
    assert fx.header_byte(read=True, long=True, index=3) == fx.R4 + 3


def test_index_tables_formats() -> None:
    longs = {k for k, (_, _, n) in fx.WRITE_INDEX.items() if n == 4}
    assert longs == {2, 8, 9}
    assert fx.encode_write(-5, long=True, index=2)[:3] == bytes([0xE2] * 3)
    with pytest.raises(ValueError, match="longword"):
        fx.encode_write(1, index=2)


def test_read_reply_roundtrip() -> None:
    raw = fx.encode_read_reply(0xF3, b"\x01\x02\x03\x04")
    assert fx.decode_read_reply(raw, long=True) == (0xF3, b"\x01\x02\x03\x04")
    with pytest.raises(FrameError, match="bad complement"):
        fx.decode_read_reply(raw[:-1] + b"\x00", long=True)
    with pytest.raises(FrameError, match="wrong length"):
        fx.decode_read_reply(raw, long=False)


@pytest.mark.parametrize("raw, code, words", [
    (h("63 63 62 47 B8 05 FA"), "bad_sync", "header bytes differ"),
    (h("43 43 43 47 B8 05 FA"), "bad_header", "not a FlexMAC header"),
    (h("63 63 63 47 B8 05 FB"), "bad_complement", "data byte 1"),
    (h("60 60 60 09 F7 47 B8 05 FA"), "bad_complement", "register number"),
    (h("62 62 62 47 B8 05 FA"), "bad_format", "write index 2 (P_SOLL) is a longword"),
    (h("73 73 73"), "bad_format", "read index 3 (P_IST) is a longword"),
    (h("63 63 63 47 B8"), "truncated", "truncated"),
])
def test_malformed_messages(raw, code, words) -> None:
    with pytest.raises(FrameError) as err:
        fx.decode(raw)
    assert err.value.code == code and words in err.value.reason


def test_stream_resynchronises() -> None:
    stream = b"\x00\x12" + V_SOLL_INDEX + h("63 63 63 47 B9") + P_IST_NUMBER + USE_FASTMAC
    d = fx.FlexMacDecoder()
    items = d.feed(stream) + d.flush()
    kinds = [x.code if isinstance(x, FrameError) else type(x).__name__ for x in items]
    assert kinds == ["bad_header", "FlexWrite", "bad_complement", "FlexRead", "FlexRead"]

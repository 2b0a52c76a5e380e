"""MacTalk codec (manual 5.1): every byte example in both directions, and every malformed frame
rejected with a precise reason."""

from __future__ import annotations

import pytest

from jvl_gym.protocol import FrameError
from jvl_gym.protocol.mactalk import codec16 as mt


def h(text: str) -> bytes:
    """Bytes from the manual's notation (``50h,50h``, ``063H, 0F3H``) or plain hex."""
    tokens = text.replace(",", " ").split()
    return bytes(int(t.rstrip("hH"), 16) for t in tokens)


# ---------------------------------------------------------------- manual 5.1 byte examples
READ_7 = h("50h,50h,50h,13h,ECh,07h,F8h,AAh,AAh")
READ_7_REPLY = h("52h,52h,52h,00h,FFh,04h,FBh,11h,EEh,47h,B8h,00h,FFh,00h,FFh,AAh,AAh")
WRITE_8 = h("52h,52h,52h,10h,EFh,08h,F7h,02h,FDh,22h,DDh,33h,CCh,AAh,AAh")
SAFE_17 = h("54h,54h,54h,17h,E8h,AAh,AAh")
ACCEPT = h("11h,11h,11h")


def test_example_read_register_7_of_unit_13h() -> None:
    assert mt.encode_read(0x13, 7) == READ_7
    assert mt.decode(READ_7) == mt.Request(mt.Command.READ, 0x13, 7)


def test_example_read_reply_longint_rule_low_byte_first() -> None:
    # register 7 = 4711h, register 8 = 0000h: always four bytes (LongInt rule), low byte first
    data = mt.words_to_bytes([0x4711, 0x0000])
    assert mt.encode_data_reply(data) == READ_7_REPLY
    reply = mt.decode(READ_7_REPLY)
    assert reply == mt.DataReply(data)
    assert mt.bytes_to_words(reply.data) == [0x4711, 0x0000]
    assert mt.bytes_to_long(reply.data) == 0x4711


def test_example_write_3322h_to_register_8_of_unit_10h() -> None:
    assert mt.encode_write_word(0x10, 8, 0x3322) == WRITE_8
    req = mt.decode(WRITE_8)
    assert req == mt.Request(mt.Command.WRITE, 0x10, 8, b"\x22\x33")
    assert mt.bytes_to_words(req.data) == [0x3322]


def test_example_go_safe_mode_unit_17h_and_accept() -> None:
    assert mt.encode_go_safe_mode(0x17) == SAFE_17
    assert mt.decode(SAFE_17) == mt.Request(mt.Command.GO_SAFE_MODE, 0x17)
    assert mt.encode_accept() == ACCEPT
    assert mt.decode(ACCEPT) == mt.Accept()


@pytest.mark.parametrize("enc, cmd", [
    (mt.encode_read_sample_buffer, mt.Command.READ_SAMPLE_BUFFER),
    (mt.encode_go_safe_mode, mt.Command.GO_SAFE_MODE),
    (mt.encode_go_init_mode, mt.Command.GO_INIT_MODE),
    (mt.encode_write_flash, mt.Command.WRITE_FLASH),
    (mt.encode_reset, mt.Command.RESET),
])
def test_address_only_messages(enc, cmd) -> None:
    raw = enc(0x21)
    assert raw == bytes([cmd] * 3) + h("21 DE AA AA")
    assert mt.decode(raw) == mt.Request(cmd, 0x21)
    assert mt.encode(mt.decode(raw)) == raw


def test_read_block_and_broadcast() -> None:
    raw = mt.encode_read_block(mt.BROADCAST, 0x70)
    assert raw == h("51 51 51 FF 00 70 8F AA AA")
    assert mt.decode(raw) == mt.Request(mt.Command.READ_BLOCK, 0xFF, 0x70)


def test_write_long_low_word_first() -> None:
    # MAC800 quick guide example 2: 230 000 = 38270h is sent 70h 82h 03h 00h
    raw = mt.encode_write_long(7, 3, 230_000)
    assert raw == h("52 52 52 07 F8 03 FC 04 FB 70 8F 82 7D 03 FC 00 FF AA AA")
    assert mt.bytes_to_long(mt.decode(raw).data) == 230_000
    assert mt.bytes_to_long(mt.long_to_bytes(-2)) == -2


def test_roundtrip_every_frame_kind() -> None:
    frames = [mt.encode_read(1, 255), mt.encode_read_block(254, 1), mt.encode_write_word(5, 9, 0),
              mt.encode_write_long(5, 9, -1), mt.encode_data_reply(b""),
              mt.encode_data_reply(bytes(range(32))), mt.encode_accept()]
    for raw in frames:
        assert mt.encode(mt.decode(raw)) == raw


def test_encoder_refuses_bad_arguments() -> None:
    with pytest.raises(ValueError, match="regnr"):
        mt.encode_read(1, 0)
    with pytest.raises(ValueError, match="address"):
        mt.encode_read(256, 1)
    with pytest.raises(ValueError, match="master"):
        mt.encode_write_word(0, 5, 1)
    with pytest.raises(ValueError, match="2 or 4"):
        mt.encode_write(1, 5, b"\x01\x02\x03")


# ---------------------------------------------------------------- malformed frames
@pytest.mark.parametrize("raw, code, words", [
    (h("50 50 50 13 ED 07 F8 AA AA"), "bad_complement", "address: 13h followed by EDh"),
    (h("50 50 50 13 EC 07 F9 AA AA"), "bad_complement", "register number"),
    (h("50 50 51 13 EC 07 F8 AA AA"), "bad_sync", "sync bytes differ"),
    (h("58 58 58 13 EC 07 F8 AA AA"), "unknown_sync", "unknown sync byte 58h"),
    (h("50 50 50 13 EC 07 F8 AA AB"), "bad_end", "expected AAh AAh"),
    (h("50 50 50 13 EC 00 FF AA AA"), "bad_register", "register number 0"),
    (h("52 52 52 10 EF 08 F7 03 FC 22 DD 33 CC 44 BB AA AA"), "wrong_length", "datalength is 3"),
    (h("52 52 52 10 EF 08 F7 04 FB 22 DD 33 CC AA AA"), "wrong_length", "end sync AAh AAh "
     "follows after 2"),
    (h("52 52 52 10 EF 08 F7 02 FD 22 DD 33 CC 00 FF AA AA"), "bad_end", "missing end sync"),
    (h("52 52 52 10 EF 08 F7 02 FD 22 DD 33 CD AA AA"), "bad_complement", "data byte 1"),
    (h("11 11 12"), "bad_sync", "incomplete accept"),
    (h("50 50 50 13 EC 07"), "truncated", "truncated frame: 6 bytes"),
])
def test_malformed_frame_rejected_with_precise_reason(raw, code, words) -> None:
    with pytest.raises(FrameError) as err:
        mt.decode(raw)
    assert err.value.code == code
    assert words in err.value.reason


def test_trailing_bytes_after_a_frame_are_an_error() -> None:
    with pytest.raises(FrameError):
        mt.decode(READ_7 + b"\x00")
    with pytest.raises(FrameError, match="exactly one"):
        mt.decode(READ_7 + READ_7)


def test_stream_resynchronises_after_garbage_and_bad_frames() -> None:
    stream = (b"\x00\x01" + READ_7 + h("50 50 50 13 ED") + WRITE_8 + b"\xff" + SAFE_17
              + ACCEPT + READ_7[:4])
    d = mt.MacTalkDecoder()
    items = []
    for k in range(0, len(stream), 3):  # arbitrary chunking
        items += d.feed(stream[k:k + 3])
    items += d.flush()
    kinds = [type(x).__name__ if not isinstance(x, FrameError) else x.code for x in items]
    assert kinds == ["unknown_sync", "Request", "bad_complement", "Request", "unknown_sync",
                     "Request", "Accept", "truncated"]
    assert items[0].offset == 0 and items[0].data == b"\x00\x01"
    assert items[3].register == 8 and items[5].command == mt.Command.GO_SAFE_MODE
    # every byte is accounted for exactly once
    assert sum(len(x.data) for x in items if isinstance(x, FrameError)) + sum(
        len(mt.encode(x)) for x in items if not isinstance(x, FrameError)) == len(stream)


def test_truncated_frame_followed_by_a_good_one_keeps_the_good_one() -> None:
    items = mt.decode_all(READ_7[:5] + READ_7)
    assert [type(x).__name__ for x in items] == ["FrameError", "Request"]
    assert items[0].code == "bad_complement"
    assert items[1] == mt.Request(mt.Command.READ, 0x13, 7)


def test_byte_by_byte_feeding_equals_one_shot() -> None:
    stream = READ_7 + WRITE_8 + READ_7_REPLY + ACCEPT + SAFE_17
    d = mt.MacTalkDecoder()
    items = [x for b in stream for x in d.feed(bytes([b]))]
    assert items == mt.decode_all(stream)
    assert d.frames == 5 and d.errors == 0

"""MacTalk of the 32-bit register families (MAC800 serial quick guide §1.3, MIS manual §18.2):
every byte example produced and parsed byte for byte, corrupt frames rejected with a reason,
hypothesis round trips and fuzzing of the streaming decoder."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jvl_gym.protocol import FrameError
from jvl_gym.protocol.mactalk import codec32 as m32

FAST = settings(max_examples=300, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow])


def h(text: str) -> bytes:
    """Bytes from the manuals' notation (``52h,52h - 08h,F7h``) or plain hex."""
    tokens = text.replace(",", " ").replace("-", " ").split()
    return bytes(int(t.rstrip("hH"), 16) for t in tokens)


C = m32.Command
ACCEPT = h("11h,11h,11h")

# ------------------------------------------------------------ MAC800 quick guide §1.3.2 write
#: example 1: writing 600 (258h) to register 5 of the motor with address 8
QG_WRITE_600 = h("52h,52h,52h - 08h,F7h - 05h,FAh - 04h,FBh - 58h,A7h,02h,FDh,00h,FFh,00h,FFh"
                 " - AAh,AAh")
#: example 2: writing 230,000 (38270h) to register 3 of the motor with address 7
QG_WRITE_230000 = h("52h,52h,52h - 07h,F8h - 03h,FCh - 04h,FBh - 70h,8Fh,82h,7Dh,03h,FCh,00h,FFh"
                    " - AAh,AAh")
# ------------------------------------------------------------ §1.3.4 application examples
QG_MODE_1 = h("52h,52h,52h - 08h,F7h - 02h,FDh - 04h,FBh - 01h,FEh,00h,FFh,00h,FFh,00h,FFh"
              " - AAh,AAh")
QG_P_SOLL_100000 = h("52h,52h,52h - 07h,F8h - 03h,FCh - 04h,FBh - A0h,5Fh,86h,79h,01h,FEh,00h,FFh"
                     " - AAh,AAh")
QG_V_SOLL_2771 = h("52h,52h,52h - 08h,F7h - 05h,FAh - 04h,FBh - D3h,2Ch,0Ah,F5h,00h,FFh,00h,FFh"
                   " - AAh,AAh")

WRITE_EXAMPLES = [
    # (frame, address, register, value)
    (QG_WRITE_600, 8, 5, 600),
    (QG_WRITE_230000, 7, 3, 230_000),
    (QG_MODE_1, 8, 2, 1),
    (QG_P_SOLL_100000, 7, 3, 100_000),  # the text says motor 8; the bytes address 7
    (QG_V_SOLL_2771, 8, 5, 2771),
]


@pytest.mark.parametrize("frame, address, register, value", WRITE_EXAMPLES)
def test_quick_guide_write_examples(frame: bytes, address: int, register: int,
                                    value: int) -> None:
    assert m32.encode_write_value(address, register, value) == frame
    req = m32.decode(frame)
    assert req == m32.Request(C.WRITE, address, register, m32.value_bytes(value))
    assert m32.data_value(req.data) == value
    assert m32.encode(req) == frame
    assert m32.encode_accept() == ACCEPT and m32.decode(ACCEPT) == m32.Accept()


# ------------------------------------------------------------ §1.3.3 read, §1.3.4 reads
READ_EXAMPLES = [
    # (request, reply, address, register, value)
    # §1.3.3 example 1: the register byte is printed 05h,F6h (complement misprint: 05h, FAh)
    # and the value "500 (258h)" (258h = 600)
    (h("50h,50h,50h - 08h,F7h - 05h,FAh - AAh,AAh"),
     h("52h,52h,52h - 00h,FFh - 05h,FAh - 04h,FBh - 58h,A7h,02h,FDh,00h,FFh,00h,FFh - AAh,AAh"),
     8, 5, 600),
    # §1.3.3 example 2: the reply names register 5 in print; "always the same as requested": 3
    (h("50h,50h,50h - 08h,F7h - 03h,FCh - AAh,AAh"),
     h("52h,52h,52h - 00h,FFh - 03h,FCh - 04h,FBh - 70h,8Fh,82h,7Dh,03h,FCh,00h,FFh - AAh,AAh"),
     8, 3, 230_000),
    # §1.3.4 reading the motor status: ERR_STAT = 0010h, "In Position"
    (h("50h,50h,50h - 08h,F7h - 23h,DCh - AAh,AAh"),
     h("52h,52h,52h - 00h,FFh - 23h,DCh - 04h,FBh - 10h,EFh,00h,FFh,00h,FFh,00h,FFh - AAh,AAh"),
     8, 35, 0x10),
    # §1.3.4 reading the actual position: 245,000 counts (3BD08h)
    (h("50h,50h,50h - 08h,F7h - 0Ah,F5h - AAh,AAh"),
     h("52h,52h,52h - 00h,FFh - 0Ah,F5h - 04h,FBh - 08h,F7h,BDh,42h,03h,FCh,00h,FFh - AAh,AAh"),
     8, 10, 245_000),
    # MIS §18.2.2: register 5 of address 7, data E8h,17h,03h,FCh,00h,FFh,00h,FFh = 1000
    (h("50h,50h,50h - 07h,F8h - 05h,FAh - AAh,AAh"),
     h("52h,52h,52h - 00h,FFh - 05h,FAh - 04h,FBh - E8h,17h,03h,FCh,00h,FFh,00h,FFh - AAh,AAh"),
     7, 5, 1000),
]


@pytest.mark.parametrize("request_, reply, address, register, value", READ_EXAMPLES)
def test_read_examples_request_and_reply_with_register_number(
        request_: bytes, reply: bytes, address: int, register: int, value: int) -> None:
    assert m32.encode_read(address, register) == request_
    assert m32.decode(request_) == m32.Request(C.READ, address, register)
    assert m32.encode_reply(register, m32.value_bytes(value)) == reply
    got = m32.decode(reply)
    assert got == m32.Reply(register, m32.value_bytes(value))
    assert len(got.data) == m32.READ_LENGTH and m32.data_value(got.data) == value


def test_quick_guide_misprinted_read_is_a_bad_complement() -> None:
    """§1.3.3 example 1 as printed (05h, F6h) is not a valid frame: nothing is decoded."""
    printed = h("50h,50h,50h - 08h,F7h - 05h,F6h - AAh,AAh")
    with pytest.raises(FrameError) as e:
        m32.decode(printed)
    assert e.value.code == "bad_complement" and "register number" in e.value.reason


# ------------------------------------------------------------ MIS §18.2.3 – §18.2.9
def test_mis_read_block_example_128_bytes() -> None:
    req = h("51h,51h,51h - 07h,F8h - 05h,FAh - AAh,AAh")
    assert m32.encode_read_block(7, 5) == req
    assert m32.decode(req) == m32.Request(C.READ_BLOCK, 7, 5)
    values = [1000] + list(range(1, m32.BLOCK_REGISTERS))
    data = b"".join(m32.value_bytes(v) for v in values)
    reply = m32.encode_reply(5, data)
    # "80h,7Fh (Len = 128)", data "E8h,17h, 03h,FCh …"
    assert reply.startswith(h("52h,52h,52h - 00h,FFh - 05h,FAh - 80h,7Fh - E8h,17h,03h,FCh"))
    assert len(reply) == 3 + 6 + 2 * m32.BLOCK_LENGTH + 2
    got = m32.decode(reply)
    assert got == m32.Reply(5, data) and len(got.data) == 128


def test_mis_write_example_len_2() -> None:
    frame = h("52h,52h,52h - 07h,F8h - 05h,FAh - 02h,FDh - E8h,17h,03h,FCh - AAh,AAh")
    assert m32.encode_write_value(7, 5, 1000, length=2) == frame
    req = m32.decode(frame)
    assert req == m32.Request(C.WRITE, 7, 5, b"\xe8\x03")
    assert m32.data_value(req.data) == 1000


@pytest.mark.parametrize("encoder, command, sync", [
    (m32.encode_enter_safe_mode, C.ENTER_SAFE_MODE, "54h,54h,54h"),  # §18.2.5
    (m32.encode_exit_safe_mode, C.EXIT_SAFE_MODE, "55h,55h,55h"),  # §18.2.6
    (m32.encode_write_flash, C.WRITE_FLASH, "56h,56h,56h"),  # §18.2.7
    (m32.encode_reset, C.RESET, "57h,57h,57h"),  # §18.2.8
])
def test_mis_address_only_commands(encoder, command, sync: str) -> None:
    frame = h(f"{sync} - 07h,F8h - AAh,AAh")
    assert encoder(7) == frame
    assert m32.decode(frame) == m32.Request(command, 7)
    assert m32.encode(m32.Request(command, 7)) == frame


def test_read_sample_frames() -> None:
    """MIS §8.2.63: "The sampled values are read back using the command hex 53"; the request
    as the MAC050–141's (manual 5.1), a sample (four 32-bit channels) in the reply frame naming
    SAMPLE1 (register 112, MIS §8.2.60), an empty reply after the last (decision)."""
    req = h("53h,53h,53h - 07h,F8h - AAh,AAh")
    assert m32.encode_read_sample(7) == req
    assert m32.decode(req) == m32.Request(C.READ_SAMPLE, 7)
    sample = b"".join(m32.value_bytes(v) for v in (1000, -1, 0, 230_000))
    reply = m32.encode_reply(112, sample)
    assert reply.startswith(h("52h,52h,52h - 00h,FFh - 70h,8Fh - 10h,EFh - E8h,17h,03h,FCh"))
    assert m32.decode(reply) == m32.Reply(112, sample)
    assert m32.decode(h("52h,52h,52h - 00h,FFh - 70h,8Fh - 00h,FFh - AAh,AAh")) == \
        m32.Reply(112, b"")


def test_mis_group_write_example() -> None:
    frame = h("59h,59h,59h - 07h,F8h - 04h,FBh - 05h,FAh - 02h,FDh - E8h,17h,03h,FCh - AAh,AAh")
    assert m32.encode_group_write(7, 4, 5, m32.value_bytes(1000, 2)) == frame
    got = m32.decode(frame)
    assert got == m32.GroupWrite(group=7, sequence=4, register=5, data=b"\xe8\x03")
    assert m32.encode(got) == frame


# ------------------------------------------------------------ short writes, values
@pytest.mark.parametrize("data, signed, value", [
    ("e8 03", True, 1000), ("ff ff", True, -1), ("ff ff", False, 65535),
    ("00 80", True, -32768), ("70 82 03 00", True, 230_000),
    ("ff ff ff ff", True, -1), ("ff ff ff ff", False, 2**32 - 1),
])
def test_data_value_extends_as_the_register_format(data: str, signed: bool, value: int) -> None:
    assert m32.data_value(bytes.fromhex(data), signed=signed) == value


@pytest.mark.parametrize("value, length", [(2**32, 4), (-(2**31) - 1, 4), (2**16, 2),
                                           (-(2**15) - 1, 2), (1, 3), (True, 4), (1.0, 4)])
def test_value_bytes_refuses_what_does_not_fit(value, length) -> None:
    with pytest.raises(ValueError):
        m32.value_bytes(value, length)


@pytest.mark.parametrize("call", [
    lambda: m32.encode_read(0, 5),  # the master's address
    lambda: m32.encode_read(7, 0),  # register 0
    lambda: m32.encode_read(7, 256),
    lambda: m32.encode_write(7, 5, b"\x01\x02\x03"),
    lambda: m32.encode_group_write(256, 1, 5, b"\x01\x00"),
    lambda: m32.encode_reply(5, bytes(256)),
    lambda: m32.encode(m32.Request(C.GROUP_WRITE, 7)),
])
def test_encoders_refuse_bad_arguments(call) -> None:
    with pytest.raises(ValueError):
        call()


# ------------------------------------------------------------ corrupt frames
CORRUPT = [
    # (bytes, code, words in the reason)
    (h("50 50 50 08 f6 05 fa aa aa"), "bad_complement", "address"),
    (h("52 52 52 08 f7 05 fa 04 fb 58 a7 02 fd 00 ff 00 fe aa aa"), "bad_complement", "data"),
    (h("52 52 52 08 f7 05 fa 04 fa 58 a7 02 fd 00 ff 00 ff aa aa"), "bad_complement", "length"),
    (h("52 52 52 08 f7 05 fa 03 fc 58 a7 02 fd 00 ff aa aa"), "wrong_length", "Len is 3"),
    (h("52 52 52 08 f7 05 fa 04 fb 58 a7 02 fd aa aa"), "wrong_length", "end sync"),
    (h("52 52 52 08 f7 05 fa 02 fd 58 a7 02 fd 00 ff aa aa"), "bad_end", "end sync"),
    (h("59 59 59 07 f8 04 fb 05 fa 01 fe e8 17 aa aa"), "wrong_length", "Len is 1"),
    (h("59 59 59 07 f8 04 fb 00 ff 02 fd e8 17 03 fc aa aa"), "bad_register", "register"),
    (h("50 50 50 08 f7 00 ff aa aa"), "bad_register", "register"),
    (h("50 50 50 00 ff 05 fa aa aa"), "bad_address", "master"),
    (h("58 58 58 08 f7 aa aa"), "unknown_sync", "58h"),
    (h("54 54 55 08 f7 aa aa"), "bad_sync", "differ"),
    (h("11 11 12"), "bad_sync", "accept"),
]


@pytest.mark.parametrize("data, code, words", CORRUPT)
def test_corrupt_frames_raise_frame_errors_with_a_reason(data: bytes, code: str,
                                                         words: str) -> None:
    with pytest.raises(FrameError) as e:
        m32.decode(data)
    assert e.value.code == code
    assert words.lower() in e.value.reason.lower()


def test_truncated_frame_is_held_then_reported_by_flush() -> None:
    d = m32.MacTalk32Decoder()
    assert d.feed(QG_WRITE_600[:-3]) == []
    assert d.pending == QG_WRITE_600[:-3]
    (err,) = d.flush()
    assert err.code == "truncated" and err.data == QG_WRITE_600[:-3]
    assert d.feed(QG_WRITE_600) == [m32.decode(QG_WRITE_600)]


def test_decoder_resynchronises_after_garbage() -> None:
    d = m32.MacTalk32Decoder()
    out = d.feed(b"\x00\x59\x52" + QG_MODE_1 + h("50 50 50 08 f6 05 fa aa aa") + QG_V_SOLL_2771)
    frames = [x for x in out if not isinstance(x, FrameError)]
    assert frames == [m32.decode(QG_MODE_1), m32.decode(QG_V_SOLL_2771)]
    assert isinstance(out[0], FrameError) and isinstance(out[-2], FrameError)


def test_one_shot_decode_wants_exactly_one_frame() -> None:
    with pytest.raises(FrameError) as e:
        m32.decode(QG_MODE_1 + ACCEPT)
    assert e.value.code == "trailing"


# ------------------------------------------------------------ property tests
def frames() -> st.SearchStrategy[m32.Frame]:
    unit = st.integers(1, 255)
    reg = st.integers(1, 255)
    data = st.sampled_from(m32.WRITE_LENGTHS).flatmap(lambda n: st.binary(min_size=n,
                                                                          max_size=n))
    return st.one_of(
        st.builds(m32.Request, st.sampled_from([C.READ, C.READ_BLOCK]), unit, reg),
        st.builds(m32.Request, st.just(C.WRITE), unit, reg, data),
        st.builds(m32.Request, st.sampled_from([C.READ_SAMPLE, C.ENTER_SAFE_MODE,
                                                C.EXIT_SAFE_MODE, C.WRITE_FLASH, C.RESET]),
                  unit),
        st.builds(m32.GroupWrite, st.integers(0, 255), st.integers(0, 255), reg, data),
        st.builds(m32.Reply, reg, st.binary(max_size=255)),
        st.just(m32.Accept()),
    )


@FAST
@given(frames())
def test_round_trip_frame_bytes_frame(frame: m32.Frame) -> None:
    raw = m32.encode(frame)
    assert m32.decode(raw) == frame
    assert m32.encode(m32.decode(raw)) == raw


@FAST
@given(st.lists(frames(), min_size=1, max_size=6), st.data())
def test_stream_of_frames_in_any_chunks(items: list[m32.Frame], data: st.DataObject) -> None:
    stream = b"".join(m32.encode(f) for f in items)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=8)))
    d = m32.MacTalk32Decoder()
    out: list = []
    for a, b in zip([0, *cuts], [*cuts, len(stream)]):
        out += d.feed(stream[a:b])
    out += d.flush()
    assert out == items


def _accounted(stream: bytes, chunks: list[int]) -> list:
    d = m32.MacTalk32Decoder()
    out: list = []
    pos = 0
    for n in chunks:
        out += d.feed(stream[pos:pos + n])
        pos += n
    out += d.feed(stream[pos:]) + d.flush()
    used = sum(len(x.data) if isinstance(x, FrameError) else len(m32.encode(x)) for x in out)
    assert used == len(stream)  # every byte is a frame's or an error's
    return out


@FAST
@given(st.binary(max_size=300), st.lists(st.integers(1, 40), max_size=10))
def test_fuzz_random_bytes_never_crash_and_every_byte_is_accounted_for(
        stream: bytes, chunks: list[int]) -> None:
    _accounted(stream, chunks)


@FAST
@given(frames().filter(lambda f: not isinstance(f, m32.Accept)), st.data())
def test_fuzz_one_corrupted_byte_never_yields_the_original_frame(frame: m32.Frame,
                                                                  data: st.DataObject) -> None:
    raw = bytearray(m32.encode(frame))
    k = data.draw(st.integers(3, len(raw) - 1))  # a byte after the sync
    raw[k] ^= data.draw(st.integers(1, 255))
    out = _accounted(bytes(raw), [])
    assert frame not in out
    assert any(isinstance(x, FrameError) for x in out)

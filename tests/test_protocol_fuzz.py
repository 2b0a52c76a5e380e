"""Property-based fuzzing of the decoders (hypothesis): random and mutated frames never crash a
decoder, every byte is accounted for, and (with the twin) never change a motor's state.

The number of frames tried is printed at the end of the module (``pytest -s``) and checked.
"""

from __future__ import annotations

from collections import Counter

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jvl_gym.protocol import FrameError
from jvl_gym.protocol.mactalk import codec16 as mt
from jvl_gym.protocol.mactalk import fastmac as fm
from jvl_gym.protocol.mactalk import flexmac as fx

TRIED: Counter[str] = Counter()
FAST = settings(max_examples=400, deadline=None,
                suppress_health_check=[HealthCheck.too_slow])


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    total = sum(TRIED.values())
    print(f"\nfuzz: {total} frames tried: " + ", ".join(f"{k} {v}" for k, v in TRIED.items()))


def valid_mactalk() -> st.SearchStrategy[bytes]:
    addr = st.integers(0, 255)
    reg = st.integers(1, 255)
    return st.one_of(
        st.builds(mt.encode_read, addr, reg),
        st.builds(mt.encode_read_block, addr, reg),
        st.builds(mt.encode_write_word, st.integers(1, 255), reg, st.integers(0, 0xFFFF)),
        st.builds(mt.encode_write_long, st.integers(1, 255), reg,
                  st.integers(-(2**31), 2**31 - 1)),
        st.builds(mt.encode_read_sample_buffer, addr),
        st.builds(mt.encode_go_safe_mode, addr),
        st.builds(mt.encode_go_init_mode, addr),
        st.builds(mt.encode_write_flash, addr),
        st.builds(mt.encode_reset, addr),
        st.builds(mt.encode_data_reply, st.binary(max_size=40)),
        st.just(mt.ACCEPT),
    )


@st.composite
def mutated(draw, base: st.SearchStrategy[bytes]) -> bytes:
    """A valid frame with a few bytes flipped, dropped, inserted or the end cut off."""
    data = bytearray(draw(base))
    for _ in range(draw(st.integers(1, 3))):
        op = draw(st.sampled_from(["flip", "drop", "insert", "cut"]))
        if not data:
            break
        k = draw(st.integers(0, len(data) - 1))
        if op == "flip":
            data[k] ^= 1 << draw(st.integers(0, 7))
        elif op == "drop":
            del data[k]
        elif op == "insert":
            data.insert(k, draw(st.integers(0, 255)))
        else:
            del data[k:]
    return bytes(data)


def _account(items, stream: bytes, encode) -> None:
    """Every byte of the stream is in exactly one frame or one error."""
    used = sum(len(x.data) if isinstance(x, FrameError) else len(encode(x)) for x in items)
    assert used == len(stream)


def _chunks(draw_sizes: list[int], data: bytes) -> list[bytes]:
    out, k = [], 0
    for s in draw_sizes:
        out.append(data[k:k + s])
        k += s
    out.append(data[k:])
    return out


@FAST
@given(st.lists(st.one_of(valid_mactalk(), mutated(valid_mactalk()), st.binary(max_size=12)),
                max_size=6),
       st.lists(st.integers(1, 9), max_size=20))
def test_mactalk_decoder_never_crashes(parts: list[bytes], sizes: list[int]) -> None:
    stream = b"".join(parts)
    d = mt.MacTalkDecoder()
    items = [x for c in _chunks(sizes, stream) for x in d.feed(c)] + d.flush()
    TRIED["mactalk"] += len(parts)
    _account(items, stream, mt.encode)
    for x in items:
        if isinstance(x, FrameError):
            assert x.reason and x.code


@FAST
@given(valid_mactalk())
def test_mactalk_valid_frames_roundtrip(raw: bytes) -> None:
    TRIED["mactalk valid"] += 1
    assert mt.encode(mt.decode(raw)) == raw


@FAST
@given(mutated(valid_mactalk()))
def test_mactalk_mutated_frame_is_rejected_or_is_another_valid_frame(raw: bytes) -> None:
    TRIED["mactalk mutated"] += 1
    try:
        frame = mt.decode(raw)
    except FrameError as err:
        assert err.reason
    else:  # a mutation can produce another well-formed frame: then it re-encodes exactly
        assert mt.encode(frame) == raw


def valid_flexmac() -> st.SearchStrategy[bytes]:
    word_idx = [k for k, v in fx.WRITE_INDEX.items() if v[2] == 2]
    long_idx = [k for k, v in fx.WRITE_INDEX.items() if v[2] == 4]
    return st.one_of(
        st.builds(lambda v, i: fx.encode_write(v, index=i), st.integers(0, 0xFFFF),
                  st.sampled_from(word_idx)),
        st.builds(lambda v, i: fx.encode_write(v, long=True, index=i),
                  st.integers(0, 2**32 - 1), st.sampled_from(long_idx)),
        st.builds(lambda v, n, lg: fx.encode_write(v, long=lg, number=n),
                  st.integers(0, 0xFFFF), st.integers(1, 255), st.booleans()),
        st.builds(lambda v, a: fx.encode_write(v, address=a), st.integers(0, 0xFFFF),
                  st.integers(0, 0xFFFF)),
        st.builds(lambda n, lg: fx.encode_read(long=lg, number=n), st.integers(1, 255),
                  st.booleans()),
        st.builds(lambda i: fx.encode_read(long=fx.READ_INDEX[i][2] == 4, index=i),
                  st.integers(1, 15)),
        st.builds(lambda a: fx.encode_read(address=a), st.integers(0, 0xFFFF)),
    )


def _flex_encode(m) -> bytes:
    if isinstance(m, fx.FlexRead):
        if m.index:
            return bytes([m.header] * 3)
        return fx.encode_read(long=m.long, number=m.number, address=m.address)
    value = int.from_bytes(m.data, "little")
    return fx.encode_write(value, long=m.long, index=m.index, number=m.number,
                           address=m.address)


@FAST
@given(st.lists(st.one_of(valid_flexmac(), mutated(valid_flexmac()), st.binary(max_size=10)),
                max_size=6),
       st.lists(st.integers(1, 9), max_size=20))
def test_flexmac_decoder_never_crashes(parts: list[bytes], sizes: list[int]) -> None:
    stream = b"".join(parts)
    d = fx.FlexMacDecoder()
    items = [x for c in _chunks(sizes, stream) for x in d.feed(c)] + d.flush()
    TRIED["flexmac"] += len(parts)
    _account(items, stream, _flex_encode)


@FAST
@given(st.binary(min_size=1, max_size=64))
def test_fastmac_receiver_never_crashes(data: bytes) -> None:
    rx = fm.FastMacReceiver()
    TRIED["fastmac bytes"] += len(data)
    for b in data:
        out = rx.feed(b)
        assert out is None or isinstance(out, (fm.FastMacByte, FrameError))


# ---------------------------------------------------------------- the twin never changes state
@pytest.fixture(scope="module")
def twin():
    import numpy as np  # noqa: F401

    from jvl_gym import MotorArray
    from jvl_gym.protocol.mactalk.twin16 import Twin

    t = Twin(MotorArray("MAC140", n=2, seed=0), [19, 20])
    m = t.m
    m.write("CNTRL_BITS", 3)
    m.enter_safe_mode(0)
    m.write_flash(0)  # motor 0: FastMAC/FlexMAC user interface active
    return t


def _addressed(items) -> bool:
    return any(isinstance(x, mt.Request) and x.address in (19, 20, mt.BROADCAST) for x in items)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                    HealthCheck.function_scoped_fixture])
@given(st.lists(st.one_of(mutated(st.builds(mt.encode_write_word, st.sampled_from([19, 20]),
                                            st.integers(1, 164), st.integers(0, 0xFFFF))),
                          mutated(valid_mactalk()), st.binary(max_size=16)), max_size=5))
def test_twin_mactalk_malformed_frames_change_nothing(twin, parts: list[bytes]) -> None:
    import numpy as np

    stream = b"".join(parts)
    TRIED["twin mactalk"] += len(parts)
    if _addressed(mt.decode_all(stream)):  # a mutation made a valid request: not this test
        TRIED["twin mactalk (valid, skipped)"] += 1
        return
    before = twin.m.regs.copy()
    s = twin.session()
    assert s.feed(stream) + s.flush() == b""
    np.testing.assert_array_equal(twin.m.regs, before)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                    HealthCheck.function_scoped_fixture])
@given(st.lists(st.one_of(mutated(valid_flexmac()), st.binary(max_size=10)), max_size=5))
def test_twin_flexmac_malformed_messages_change_nothing(twin, parts: list[bytes]) -> None:
    import numpy as np

    stream = b"".join(parts)
    TRIED["twin flexmac"] += len(parts)
    d = fx.FlexMacDecoder()
    if any(not isinstance(x, FrameError) for x in d.feed(stream) + d.flush()):
        TRIED["twin flexmac (valid, skipped)"] += 1
        return
    u = twin.user[0]
    u.power_on()
    u.flexmac = True  # as after command 1Fh
    before = twin.m.regs.copy()
    u.feed(stream)
    u.flush()
    np.testing.assert_array_equal(twin.m.regs, before)
    u.power_on()


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                    HealthCheck.function_scoped_fixture])
@given(st.binary(min_size=1, max_size=40))
def test_twin_any_bytes_never_crash(twin, data: bytes) -> None:
    TRIED["twin random bytes"] += 1
    s = twin.session()
    s.feed(data)
    s.flush()
    u = twin.user[0]
    u.feed(data)  # FastMAC/FlexMAC: valid commands may act, nothing may crash
    u.flush()
    twin.m.software_reset(0) if twin.mode(0) in (0, 15) else twin.m.go_init_mode(0)

"""Refusals are whole: a write that is refused leaves registers, state, flash, flash files and a
running profile as they were, whatever side effects the registers before the refused one have
(a reset or a save by COMMAND 267–269, MIS manual §8.2.22; MODE_REG 256–258 in SAFE_MODE,
MAC050–141 manual 4.4.16; the register-set selectors of the MAC800), through the API and every
protocol (MacTalk, 32-bit MacTalk, Modbus RTU); and a save through any protocol reaches the flash
file, so that it holds after a restart."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jvl_gym import MotorArray
from jvl_gym.protocol.mactalk import codec16 as mt
from jvl_gym.protocol.mactalk import codec32 as m32
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.modbus import codec as mb
from jvl_gym.protocol.modbus.twin import modbus_bus
from jvl_gym.registers import RegisterError

FEW = settings(max_examples=25, deadline=None,
               suppress_health_check=[HealthCheck.function_scoped_fixture])
ADDRESS = 7
COMMANDS = (267, 268, 269, 2, 3, 4, 5)  # MIS: reset, save + reset, save, FastMac commands


def _whole(m: MotorArray) -> tuple:
    """Everything a refusal must leave as it was."""
    return (m.regs.copy(), m.state.copy(), m.params.copy(), m.inputs.copy(),
            [m.flash_image(i) for i in range(m.n)])


def _same(a: tuple, b: tuple) -> bool:
    return all(np.array_equal(x, y, equal_nan=True) for x, y in zip(a[:4], b[:4])) \
        and a[4] == b[4]


def _files(folder: Path | None) -> dict[str, str]:
    if folder is None or not folder.exists():
        return {}
    return {p.name: p.read_text() for p in sorted(folder.iterdir())}


def _file_matches_flash(twin: Twin, i: int = 0) -> bool:
    """The motor's flash file holds its flash (or there is neither)."""
    path = twin.flash_dir / f"flash_{i}.json"
    image = twin.m.flash_image(i)
    if not path.exists():
        return True  # nothing saved through the twin yet
    saved = {int(k): v for k, v in json.loads(path.read_text())["registers"].items()}
    return saved == image


def _mis_running(m: MotorArray) -> None:
    m.write_many({"V_SOLL": 500, "A_SOLL": 2000, "P_SOLL": 200_000, "MODE_REG": 2})
    m.step(30)


# ----------------------------------------------------------------------------- the API
def test_mis_save_then_refused_mode_saves_nothing() -> None:
    m = MotorArray("MIS232", n=1, seed=0)
    before = _whole(m)
    with pytest.raises(RegisterError):
        m.write_many({"V_SOLL": 1234, "A_SOLL": 3333, "COMMAND": 269, "MODE_REG": 9})
    assert m.flash_image(0) == {}
    assert _same(_whole(m), before)


@FEW
@given(prefix=st.dictionaries(st.sampled_from(["V_SOLL", "A_SOLL", "P_SOLL", "RUN_CURRENT"]),
                              st.integers(1, 500), max_size=3),
       command=st.sampled_from(COMMANDS), running=st.booleans(), saved=st.booleans())
def test_mis_refused_batch_with_a_command_changes_nothing(prefix, command, running,
                                                          saved) -> None:
    m = MotorArray("MIS232", n=2, seed=1)
    if saved:
        m.write_many({"COMMAND": 269})
    if running:
        _mis_running(m)
    before = _whole(m)
    with pytest.raises(RegisterError):
        m.write_many({**prefix, "COMMAND": command, "MODE_REG": 9}, index=[1, 0])
    assert _same(_whole(m), before)
    if running:  # the profile goes on as if nothing had been sent
        twin = MotorArray("MIS232", n=2, seed=1)
        if saved:
            twin.write_many({"COMMAND": 269})
        _mis_running(twin)
        m.step(20)
        twin.step(20)
        assert np.array_equal(m.regs, twin.regs)


@FEW
@given(prefix=st.dictionaries(st.sampled_from(["V_SOLL", "A_SOLL", "P_SOLL"]),
                              st.integers(1, 500), max_size=3),
       request=st.sampled_from([256, 257, 258]), saved=st.booleans())
def test_mac050_141_refused_batch_after_a_safe_mode_command_changes_nothing(
        prefix, request, saved) -> None:
    m = MotorArray("MAC140", n=1, seed=0)
    m.enter_safe_mode()
    if saved:
        m.write_flash()
        m.enter_safe_mode()
    before = _whole(m)
    with pytest.raises(RegisterError):  # 256 saves and resets, then MODE_REG 99 is refused
        m.write_many({**prefix, "MODE_REG": request, 2: 99})
    assert _same(_whole(m), before)


@FEW
@given(selector=st.sampled_from(["P_REG_P", "V_REG_P", "A_REG_P", "T_REG_P"]),
       k=st.integers(1, 4), mode=st.sampled_from([9, 99, 1000]))
def test_mac800_refused_batch_after_a_selector_changes_nothing(selector, k, mode) -> None:
    m = MotorArray("MAC800", n=1, seed=0)
    before = _whole(m)
    with pytest.raises(RegisterError):
        m.write_many({selector: k, "MODE_REG": mode})
    assert _same(_whole(m), before)


# ----------------------------------------------------------------------------- Modbus RTU
def _mis_twin(folder: Path | None, n: int = 1) -> Twin:
    return Twin(MotorArray("MIS232", n=n, seed=0), [ADDRESS] * n, flash_dir=folder)


def _modbus_write(twin: Twin, first: int, values: list[int]) -> mb.Response:
    words = [w for v in values for w in mb.words_of(v)]
    reply, _ = modbus_bus(twin).handle(mb.encode_write_request(ADDRESS, 2 * first, words), 0.0)
    return mb.decode_response(reply)


@pytest.mark.parametrize("first, values, running", [
    (24, [267, 0], False),  # COMMAND reset, then STATUSBITS (read-only)
    (24, [269, 0], False),  # COMMAND save, then STATUSBITS
    (2, [0, 1000, 5], True),  # MODE_REG passive, P_SOLL, RESERVED_4
])
def test_modbus_refused_write_with_a_command_changes_nothing(tmp_path, first, values,
                                                             running) -> None:
    twin = _mis_twin(tmp_path)
    twin.m.write("V_SOLL", 1234)  # not saved: a reset would undo it
    if running:
        _mis_running(twin.m)
    before, files = _whole(twin.m), _files(tmp_path)
    assert isinstance(_modbus_write(twin, first, values), mb.ExceptionResponse)
    assert _same(_whole(twin.m), before) and _files(tmp_path) == files


@FEW
@given(first=st.integers(1, 28), values=st.lists(
    st.sampled_from([0, 1, 2, 9, 267, 268, 269, 1000, -5, 70_000]), min_size=1, max_size=4),
    running=st.booleans())
def test_modbus_write_is_all_or_nothing(tmp_path_factory, first, values, running) -> None:
    folder = tmp_path_factory.mktemp("flash")
    twin = _mis_twin(folder)
    if running:
        _mis_running(twin.m)
    before, files = _whole(twin.m), _files(folder)
    reply = _modbus_write(twin, first, values)
    if isinstance(reply, mb.ExceptionResponse):
        assert _same(_whole(twin.m), before) and _files(folder) == files
    assert _file_matches_flash(twin)


# ----------------------------------------------------------------------------- MacTalk
@FEW
@given(register=st.sampled_from([2, 5, 24]), value=st.sampled_from([0, 9, 267, 268, 269, 400]),
       safe=st.booleans(), running=st.booleans())
def test_mactalk32_refused_write_changes_nothing(tmp_path_factory, register, value, safe,
                                                 running) -> None:
    folder = tmp_path_factory.mktemp("flash")
    twin = _mis_twin(folder)
    if running:
        _mis_running(twin.m)
    if safe:
        twin.m.enter_safe_mode()
    before, files = _whole(twin.m), _files(folder)
    reply = twin.session().feed(m32.encode_write_value(ADDRESS, register, value))
    if reply != m32.ACCEPT:
        assert _same(_whole(twin.m), before) and _files(folder) == files
    assert _file_matches_flash(twin)


@FEW
@given(value=st.sampled_from([0, 2, 99, 256, 257, 258]), safe=st.booleans(),
       saved=st.booleans())
def test_mactalk_mode_write_saves_to_the_file_or_changes_nothing(tmp_path_factory, value, safe,
                                                                   saved) -> None:
    folder = tmp_path_factory.mktemp("flash")
    twin = Twin(MotorArray("MAC140", n=1, seed=0), [ADDRESS], flash_dir=folder)
    session = twin.session()
    if saved:
        session.feed(mt.encode_go_safe_mode(ADDRESS))
        session.feed(mt.encode_write_flash(ADDRESS))
    if safe:
        session.feed(mt.encode_go_safe_mode(ADDRESS))
    before, files = _whole(twin.m), _files(folder)
    reply = session.feed(mt.encode_write_word(ADDRESS, 2, value))
    if reply != mt.ACCEPT:
        assert _same(_whole(twin.m), before) and _files(folder) == files
    assert _file_matches_flash(twin)


# ----------------------------------------------------------------------------- restart
def test_save_by_command_over_modbus_holds_after_restart(tmp_path) -> None:
    twin = _mis_twin(tmp_path)
    assert not isinstance(_modbus_write(twin, 5, [1234]), mb.ExceptionResponse)
    assert not isinstance(_modbus_write(twin, 24, [268]), mb.ExceptionResponse)
    twin.close()
    assert _mis_twin(tmp_path).m.read("V_SOLL").tolist() == [1234]


def test_save_by_command_over_mactalk32_holds_after_restart(tmp_path) -> None:
    twin = _mis_twin(tmp_path)
    session = twin.session()
    assert session.feed(m32.encode_write_value(ADDRESS, 5, 1234)) == m32.ACCEPT
    assert session.feed(m32.encode_write_value(ADDRESS, 24, 269)) == m32.ACCEPT
    twin.close()
    assert _mis_twin(tmp_path).m.read("V_SOLL").tolist() == [1234]


def test_save_by_safe_mode_request_over_mactalk_holds_after_restart(tmp_path) -> None:
    """MODE_REG 256 loads the defaults and saves them (MAC050–141 manual 4.4.16): after a
    restart the motor has the defaults, not the registers saved before."""
    def twin() -> Twin:
        return Twin(MotorArray("MAC140", n=1, seed=0), [ADDRESS], flash_dir=tmp_path)

    def restarted() -> Twin:  # a power cycle: the running twin gives its directory to a new one
        first.close()
        again = twin()
        again.close()
        return again

    first = twin()
    default = int(first.m.read_raw("V_SOLL")[0])
    session = first.session()
    session.feed(mt.encode_go_safe_mode(ADDRESS))
    assert session.feed(mt.encode_write_word(ADDRESS, 5, default + 100)) == mt.ACCEPT
    session.feed(mt.encode_write_flash(ADDRESS))
    assert restarted().m.read_raw("V_SOLL").tolist() == [default + 100]
    session.feed(mt.encode_go_safe_mode(ADDRESS))
    assert session.feed(mt.encode_write_word(ADDRESS, 2, 256)) == mt.ACCEPT
    assert restarted().m.read_raw("V_SOLL").tolist() == [default]

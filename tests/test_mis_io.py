"""The MIS/SMC SSI encoder port (MIS manual §5.7, §8.2.22 commands 320–322, §8.2.39,
§8.2.57, §8.2.59, SETUP_BITS 13 and 20, ERR_BITS 11, WARN_BITS 7), the command-side firmware
state (999 and the protected commands, the K-phase flash, the RelativeMove flag, the H3 preset
316, command 406; §8.2.21–8.2.23, §5.8.4), FLEXREGISTER (§8.2.40, §8.2.117) and the analogue
filter settings per input (AFZUP_WRITEBITS / AFZUP_READINDEX, §8.2.50–51)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c
from jvl_gym.families.mis import layout as L
from jvl_gym.families.mis.firmware.ssi import SsiSetup, gray_to_binary

#: SSI_SETUP1 of §5.7.3's example: 25 data bits, clock 1 × 10 kHz
EXAMPLE = 25 | (1 << 8)


def _ssi(setup1: int = EXAMPLE, setup2: int = 100, **regs: int) -> MotorArray:
    m = MotorArray("MIS232", n=1, seed=0)
    m.write_many({"SSI_SETUP1": setup1, "SSI_SETUP2": setup2, **regs})
    m.write("COMMAND", 320)
    return m


def _setup1(bits: int, clock: int, samples: int = 1, deviation: int = 0,
            retries: int = 0) -> int:
    return bits | (samples << 5) | (clock << 8) | (deviation << 16) | (retries << 29)


def _to_gray(n: int) -> int:
    return n ^ (n >> 1)


def _ext2(m: MotorArray) -> int:
    return int(m.read("EXTENCODER2")[0])


@pytest.mark.statements("mis:8.2.22:8", "mis:8.2.22:9", "mis:8.2.39:2", "mis:8.2.57:1",
    "mis:5.7.3:1")
def test_ssi_position_arrives_after_the_prepare_time_and_the_clock_periods() -> None:
    """§5.7.3: "Time = Prepare time + (1/Clock frequency × (Number of Data bits + 1))", 2.7 ms
    for 100 µs, 10 kHz and 25 bits: the value is in register 47 at the first outer sample
    (1 ms) after 2.7 ms, not before."""
    assert SsiSetup.of(EXAMPLE, 100).transfer_ms == pytest.approx(2.7)
    m = _ssi()
    m.set_input(ssi_word=123456)
    m.write("COMMAND", 321)
    assert m.read("COMMAND")[0] == 0
    m.step(2)
    assert _ext2(m) == 0
    m.step(1)
    assert _ext2(m) == 123456


@pytest.mark.parametrize(("bits", "clock", "prepare", "ms"), [
    (12, 100, 0, 1), (31, 2, 255, 2), (13, 1, 50, 2)])
@pytest.mark.statements("mis:8.2.57:1", "mis:8.2.59:1")
def test_ssi_reading_time_follows_the_setup_fields(bits: int, clock: int, prepare: int,
                                                   ms: int) -> None:
    """Bits 0-4 data bits, 8-15 clock in 10 kHz units, SSI_SETUP2 bits 0-7 prepare time (µs):
    12 bits at 1 MHz take 13 µs (the next outer sample), 31 bits at 20 kHz with 255 µs take
    1.855 ms, 13 bits at 10 kHz with 50 µs take 1.45 ms."""
    m = _ssi(_setup1(bits, clock), prepare)
    m.set_input(ssi_word=77)
    m.write("COMMAND", 321)
    m.step(ms - 1)
    assert _ext2(m) == 0
    m.step(1)
    assert _ext2(m) == 77


@pytest.mark.statements("mis:8.2.57:1")
def test_ssi_keeps_only_the_data_bits() -> None:
    """SSI_SETUP1 bits 0-4: the number of data bits in each transfer; the bits above are not
    read."""
    m = _ssi(_setup1(10, 100), 0)
    m.set_input(ssi_word=0x12345)
    m.write("COMMAND", 321)
    m.step(1)
    assert _ext2(m) == 0x12345 & 0x3FF


@pytest.mark.parametrize(("command", "setup2", "gray"), [
    (321, 0, False), (322, 0, True), (321, 0x100, True)])
@pytest.mark.statements("mis:8.2.22:10", "mis:8.2.39:2", "mis:8.2.59:1")
def test_ssi_gray_code_is_converted_on_322_or_with_setup2_bit_8(command: int, setup2: int,
                                                                 gray: bool) -> None:
    """Command 322 (and 321 with SSI_SETUP2 bit 8) converts the encoder's Gray code to
    binary; 321 alone takes the word as it is."""
    value = 1_000_003
    m = _ssi(_setup1(25, 100), setup2)
    m.set_input(ssi_word=_to_gray(value))
    m.write("COMMAND", command)
    m.step(1)
    assert _ext2(m) == (value if gray else _to_gray(value))
    assert all(gray_to_binary(_to_gray(n)) == n for n in range(4096))


@pytest.mark.statements("mis:8.2.22:8")
def test_ssi_read_without_command_320_reads_nothing() -> None:
    """The RS422 is set up for an SSI encoder by command 320; before it, 321 reads nothing and
    sets no error."""
    m = MotorArray("MIS232", n=1, seed=0)
    m.set_input(ssi_word=55)
    m.write("COMMAND", 321)
    m.step(5)
    assert _ext2(m) == 0 and m.read("ERR_BITS")[0] == 0


def _moving_read(m: MotorArray, step: int, samples: int = 20) -> None:
    """Command 321 with the encoder word growing by ``step`` each outer sample."""
    word = 1000
    m.set_input(ssi_word=word)
    m.write("COMMAND", 321)
    for _ in range(samples):
        m.step(1)
        word += step
        m.set_input(ssi_word=word)


@pytest.mark.statements("mis:8.2.31:14", "mis:8.2.57:1", "mis:5.7.2:1", "mis:7.2.14:1")
def test_ssi_failed_reading_keeps_the_last_value_and_sets_err_bit_11() -> None:
    """§5.7.2: samples that differ by more than the largest sample deviation fail the reading;
    after the read retries it "will be discarded and 'SSI Encoder value' still shows the last
    correct measurement. An error bit will be set in the ERR_BITS register (34) on position
    11". 3 samples 1.1 ms apart, 2 retries: the error comes after 9 transfers (9.9 ms)."""
    setup1 = _setup1(10, 1, samples=3, deviation=10, retries=2)  # 1.1 ms per transfer
    m = _ssi(setup1, 0)
    _moving_read(m, step=5)  # within the deviation: a good reading
    good = _ext2(m)
    assert 1000 < good < 1100 and m.read("ERR_BITS")[0] == 0
    m.set_input(ssi_word=500)
    m.write("COMMAND", 321)
    for k in range(12):
        m.set_input(ssi_word=500 + 100 * ((k + 1) % 2))  # jumps by 100 > 10 between samples
        m.step(1)
        if k == 8:  # 9 ms after the command: still retrying
            assert m.read("ERR_BITS")[0] == 0
    assert _ext2(m) == good
    err = int(m.read("ERR_BITS")[0])
    assert err & (1 << 11) and err & c.ERR_GENERAL


@pytest.mark.statements("mis:8.2.32:8", "mis:8.2.68:15")
def test_setup_bit_20_disables_the_ssi_error_and_warns_instead() -> None:
    """SETUP_BITS bit 20 "Disable SSI encoder error": a failed reading sets no error bit; the
    simulator shows it in WARN_BITS bit 7 (SSI encoder) instead."""
    m = _ssi(_setup1(10, 1, samples=2, deviation=0), 0, SETUP_BITS=1 << 20)
    _moving_read(m, step=1)
    assert m.read("ERR_BITS")[0] == 0
    assert m.read("WARN_BITS")[0] & (1 << 7)
    assert _ext2(m) == 0


@pytest.mark.statements("mis:5.7.2:1")
def test_ssi_failed_reading_in_an_active_mode_stops_the_motor() -> None:
    """ERR_BITS bit 11 is an error: an active motor stops and goes passive (§7.2.14)."""
    m = _ssi(_setup1(10, 1, samples=2, deviation=0), 0, V_SOLL=1000)
    m.write("MODE_REG", c.VELOCITY)
    _moving_read(m, step=1, samples=200)
    assert m.read("MODE_REG")[0] == c.PASSIVE


@pytest.mark.statements("mis:8.2.68:10")
def test_setup_bit_13_keeps_the_ssi_register_over_a_reset() -> None:
    """SETUP_BITS bit 13: "Do not zero the SSI data register at start-up"; without it
    EXTENCODER2 (default 0) is zeroed."""
    for bits, kept in ((0, 0), (1 << 13, 4321)):
        m = _ssi(_setup1(20, 100), 0, SETUP_BITS=bits)
        m.set_input(ssi_word=4321)
        m.write("COMMAND", 321)
        m.step(1)
        assert _ext2(m) == 4321
        m.enter_safe_mode()
        m.write_flash()
        assert _ext2(m) == kept


def test_ssi_word_input_refuses_bad_values_and_changes_nothing() -> None:
    m = MotorArray("MIS232", n=2, seed=0)
    m.set_input(ssi_word=7)
    for bad in (math.nan, -1, 2.0**31, 1.5):
        with pytest.raises(ValueError, match="ssi_word"):
            m.set_input(ssi_word=bad, supply_volts=30.0)
    assert m.inputs[:, L.I_SSI_WORD].tolist() == [7.0, 7.0]
    assert m.inputs[:, L.I_SUPPLY_VOLTS].tolist() != [30.0, 30.0]


def test_ssi_reading_of_a_program_arrives_while_it_runs() -> None:
    """A program that gives command 321 itself sees EXTENCODER2 change at the outer sample the
    value arrives in (2.7 ms after the command: the 3rd), and copies it to P2 there."""
    m = _ssi()
    m.set_input(ssi_word=999)
    m.store_program("set_register register=COMMAND value=321\n"
                    "wait_register register=EXTENCODER2 operator== value=999\n"
                    "set_register register=P2 value=1\n"
                    "wait_ms time=1000\n")
    m.program_start()
    m.step(2)
    assert _ext2(m) == 0
    m.step(1)
    assert _ext2(m) == 999 and m.read("P2")[0] == 0
    m.step(1)
    assert m.read("P2")[0] == 1


# --- 999, the K-phase flash, the RelativeMove flag ----------------------------------------------
@pytest.mark.statements("mis:8.2.22:18", "mis:8.2.23:1", "mis:8.2.23:2")
def test_protected_kphase_commands_need_999_first() -> None:
    """720 saves KPHASE in flash, 721 loads it back; both are "protected from accidental
    writes. Must be preceded by 999 command": without 999 they do nothing."""
    m = MotorArray("MIS232", n=1, seed=0)
    m.write("KPHASE", 50)
    m.write("COMMAND", 720)
    assert m.kphase_flash()[0] == 0
    m.write("COMMAND", 999)
    m.write("COMMAND", 720)
    assert m.kphase_flash()[0] == 50
    m.write("KPHASE", 10)
    m.write("COMMAND", 721)  # the arming went with 720
    assert m.read("KPHASE")[0] == 10
    m.write("COMMAND", 999)
    m.write("COMMAND", 97)  # another command takes the arming
    m.write("COMMAND", 721)
    assert m.read("KPHASE")[0] == 10
    m.write("COMMAND", 999)
    m.write("COMMAND", 721)
    assert m.read("KPHASE")[0] == 50
    m.enter_safe_mode()
    m.write_flash()
    assert m.kphase_flash()[0] == 50


@pytest.mark.statements("mis:8.2.21:12", "mis:8.2.21:13", "mis:8.2.21:14")
def test_fastmac_20_to_22_clear_and_set_the_relative_move_flag() -> None:
    """FastMac 20 (116) clears, 21 (117) and 22 (118) set the RelativeMove flag."""
    m = MotorArray("MIS232", n=2, seed=0)
    assert m.relative_move.tolist() == [False, False]
    m.write("COMMAND", 117, index=0)
    m.write("COMMAND", 118, index=1)
    assert m.relative_move.tolist() == [True, True]
    m.write("COMMAND", 116, index=1)
    assert m.relative_move.tolist() == [True, False]
    m.software_reset()
    assert m.relative_move.tolist() == [False, False]


# --- FLEXREGISTER --------------------------------------------------------------------------------
def _flex(low: tuple[int, int], high: tuple[int, int] = (0, 0)) -> int:
    """A FLEXREGSETUP value: (register, bit) of its low and its high FLEXREGISTER bit."""
    return low[0] | (low[1] << 9) | (high[0] << 16) | (high[1] << 25)


@pytest.mark.statements("mis:8.2.40:2", "mis:8.2.117:2")
def test_flexregister_collects_the_bits_its_setup_registers_name() -> None:
    """Each FLEXREGSETUP register sets up 2 of FLEXREGISTER's 16 bits (§8.2.117): here bit 0
    follows STATUSBITS bit 4 (in position), bit 1 INPUTS bit 0, bit 14 P1 bit 3 and bit 15 (the
    sign of the signed 16-bit value, §8.2.40) P1 bit 31; register 0 gives 0."""
    m = MotorArray("MIS232", n=1, seed=0)
    m.step(1)
    assert m.read("FLEXREGISTER")[0] == 0
    m.write_many({"FLEXREGSETUP1": _flex((25, 4), (18, 0)), "FLEXREGSETUP8": _flex((49, 3),
                                                                                    (49, 31)),
                  "P_SOLL": 0, "MODE_REG": c.POSITION})
    m.set_input(digital_inputs=1)
    m.step(2)
    assert m.read("STATUSBITS")[0] & (1 << 4) and m.read("INPUTS")[0] & 1
    assert m.read("FLEXREGISTER")[0] == 0b11
    m.write("P1", -8)  # bits 3 … 31 set
    m.set_input(digital_inputs=0)
    m.step(2)
    assert m.read("FLEXREGISTER")[0] == (0b01 | 0b11 << 14) - (1 << 16)
    m.write_many({"FLEXREGSETUP1": 0, "FLEXREGSETUP8": 0})
    m.step(1)
    assert m.read("FLEXREGISTER")[0] == 0
    names = ("FLEXREGSETUP1", "FLEXREGSETUP2", "FLEXREGSETUP3", "FLEXREGSETUP4",
             "FLEXREGSETUP5", "FLEXREGSETUP6", "FLEXREGSETUP7", "FLEXREGSETUP8")
    for k, name in enumerate(names):  # in position: STATUSBITS bit 4 in the high half
        m.write_many({other: 0 for other in names} | {name: _flex((0, 0), (25, 4))})
        m.step(1)
        assert m.read("FLEXREGISTER")[0] == (1 << (2 * k + 1)) - (1 << 16) * (k == 7)


# --- the analogue filter settings of each input -------------------------------------------------
def _settings(m: MotorArray) -> list[int]:
    return [int(m.read(k)[0]) for k in ("AFZUP_CONFMIN", "AFZUP_CONFMAX", "AFZUP_MAXSLOPE",
                                        "AFZUP_FILTER")]


@pytest.mark.statements("mis:8.2.50:1", "mis:8.2.51:1")
def test_afzup_writebits_hands_the_settings_to_the_inputs_it_selects() -> None:
    """§8.2.50: registers 102-105 loaded, then bits 0-7 of AFZUP_WRITEBITS select the inputs
    that take them and the firmware sets bit 15; §8.2.51: writing n to AFZUP_READINDEX loads
    input n's settings back into 102-105 and sets bit 15. A filter of 1/64 on IO2 only: IO1
    follows its input at once, IO2 slowly."""
    m = MotorArray("MIS232", n=1, seed=0)
    assert m.read("AFZUP_WRITEBITS")[0] == 0
    m.write_many({"AFZUP_CONFMIN": 5, "AFZUP_CONFMAX": 3000, "AFZUP_MAXSLOPE": 200,
                  "AFZUP_FILTER": 1})
    m.write("AFZUP_WRITEBITS", 0b10)
    assert m.read("AFZUP_WRITEBITS")[0] == 0b10 | 1 << 15
    m.write_many({"AFZUP_CONFMIN": 0, "AFZUP_CONFMAX": 4095, "AFZUP_MAXSLOPE": 4095,
                  "AFZUP_FILTER": 64})
    m.set_input(analog1=1.0, analog2=1.0)
    m.step(10)
    assert m.read("ANALOGUE_FILTERED1")[0] == m.read("ANALOGUE_INPUT1")[0] == 819
    assert m.read("ANALOGUE_FILTERED2")[0] == 3  # 200/64 of the slope-limited step
    m.write("AFZUP_READINDEX", 2)
    assert m.read("AFZUP_READINDEX")[0] == 32768 + 2
    assert _settings(m) == [5, 3000, 200, 1]
    m.write("AFZUP_READINDEX", 1)
    assert _settings(m) == [0, 4095, 4095, 64]


@pytest.mark.parametrize("bad", [9, 100, 32767, 32776])
@pytest.mark.statements("mis:8.2.51:1")
def test_afzup_readindex_refuses_values_outside_its_range(bad: int) -> None:
    m = MotorArray("MIS232", n=1, seed=0)
    with pytest.raises(Exception, match=r"AFZUP_READINDEX .*8\.2\.51"):
        m.write("AFZUP_READINDEX", bad)
    assert m.read("AFZUP_READINDEX")[0] == 0 and _settings(m) == [0, 4095, 4095, 64]


@pytest.mark.statements("mis:8.2.22:17")
def test_closed_loop_set_up_acts_without_command_406() -> None:
    """Command 406 "activate closed loop configuration registers": the simulator's closed loop
    follows SETUP_BITS 24 at once, so the loop is on with or without 406, and 406 changes
    nothing (mis-sim.md, "Closed-loop activation")."""
    m = MotorArray("MIS232", n=2, seed=0)
    m.write_many({"SETUP_BITS": 1 << 24, "V_SOLL": 1000, "MODE_REG": c.VELOCITY})
    before = m.regs[1].copy()
    m.write("COMMAND", 406, index=1)
    assert (m.regs[1] == before).all()
    m.step(5)
    assert (m.read("STATUSBITS") & c.ST_CLOSED_LOOP).all()


@pytest.mark.statements("mis:8.2.22:7", "mis:5.8.4:1")
def test_command_316_presets_the_h3_encoder_with_p_new() -> None:
    """§5.8.4: "a new encoder position is preset by writing it to P_NEW and then 316 to
    COMMAND": the H3's position (ABSENCODER, and ENCODER_POS with it) reads P_NEW and counts on
    from there; P_IST stays; the H3 keeps the preset over a reset, where SETUP_BITS bit 11 takes
    P_IST from it. A motor with another encoder (an H2) is not changed."""
    m = MotorArray("MIS232", n=2, seed=0, encoder_type=np.array([2, 3]))
    # no follow error check and no auto-correction: the preset leaves P_IST 10⁶ counts from
    # the encoder, which either would act on (§8.2.19, §5.2)
    m.write_many({"FLWERRMAX": 0, "IN_POSITION_COUNT": 0, "V_SOLL": 30000, "A_SOLL": 10000})
    old = m.read("ABSENCODER")[1]
    m.write("P_NEW", 1_000_000)
    m.write("COMMAND", 316)
    assert m.read("ABSENCODER").tolist() == [1_000_000, old]
    assert m.read("ENCODER_POS")[0] == 1_000_000 and m.read("P_IST").tolist() == [0, 0]
    m.step(1)
    assert m.read("ABSENCODER")[0] == 1_000_000
    m.write_many({"P_SOLL": 409600, "MODE_REG": c.POSITION})
    m.run(1.5)
    moved = m.read("ABSENCODER")[0] - 1_000_000
    assert moved == pytest.approx(409600, abs=2000)
    m.write("MODE_REG", c.PASSIVE)
    m.write("SETUP_BITS", c.SETUP_MULTI_TURN_AT_POWER_UP)
    m.enter_safe_mode()
    m.write_flash()
    m.step(1)
    assert m.read("P_IST")[0] == m.read("ABSENCODER")[0] == pytest.approx(1_409_600, abs=2000)


def test_a_refused_transaction_takes_the_commands_back() -> None:
    """A register set refused part-way (an active mode while ERR_BITS ≠ 0) leaves the motor as
    it was: no RelativeMove flag, no arming, no SSI set-up or reading."""
    m = _ssi()
    m.set_input(ssi_word=5)
    m.write("ERR_BITS", 1)
    for command in (117, 999, 321):
        with pytest.raises(Exception, match="MODE_REG"):
            m.write_many({"COMMAND": command, "MODE_REG": c.VELOCITY})
    m.write("KPHASE", 9)
    m.write("COMMAND", 720)  # not armed: nothing saved
    assert m.relative_move.tolist() == [False] and m.kphase_flash()[0] == 0
    m.step(5)
    assert _ext2(m) == 0

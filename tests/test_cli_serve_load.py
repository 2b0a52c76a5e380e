"""``jvl-gym serve`` with a load: inertia, friction and an elastic coupling per motor
(cli_serve.LOAD_OPTIONS), checked before anything is served."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jvl_gym.cli.main import app
from jvl_gym.cli.serve import LOAD_OPTIONS, LoadError, load_per_motor
from jvl_gym.families.mac050_141 import constants as c
from jvl_gym.protocol.mactalk import codec16 as mt

J_M = 17.3e-6  #: MAC140 rotor inertia [kg·m²] (families/mac050_141/configs/motors/MAC140.yaml)
RIGID = ["--coulomb-friction", "0", "--viscous-friction", "0"]


class _Started(Exception):
    """Raised by the stand-in server when serve would start serving."""


@pytest.fixture
def served(monkeypatch: pytest.MonkeyPatch) -> Any:
    """``served(*argv)``: run ``jvl-gym serve --tcp 127.0.0.1:0 *argv`` up to the start of the
    server and return the line it would serve (None when serve stopped before) and the exit
    code; the server is a stand-in that raises on ``start``."""
    from jvl_gym.protocol.serving import transport

    lines: list[Any] = []

    class Server:
        def __init__(self, line: Any, **_: Any) -> None:
            lines.append(line)

        def start(self) -> None:
            raise _Started

    monkeypatch.setattr(transport, "TwinServer", Server)

    def run(*argv: str) -> tuple[Any, int]:
        lines.clear()
        with pytest.raises(SystemExit) as info:
            app(["serve", "--tcp", "127.0.0.1:0", *argv])
        return (lines[0] if lines else None), info.value.code

    return run


def _accelerate(twin: Any, samples: int = 20) -> tuple[float, float]:
    """Mean motor torque [N·m] and the rotor's mean acceleration [rad/s²] over ``samples``
    outer samples of a constant torque command (AT_MODE at 0.2 V, manual 4.4.5)."""
    m = twin.m
    m.write("MODE_REG", c.AT_MODE)
    m.set_input(analog_volts=0.2)
    m.step(5)
    w0, torque = m.speed_rad_s[0], []
    for _ in range(samples):
        m.step(1)
        torque.append(m.torque[0])
    return float(np.mean(torque)), (m.speed_rad_s[0] - w0) / (samples * c.OUTER_DT)


def _v_ist_over_mactalk(twin: Any, address: int) -> int:
    reply = mt.decode(twin.session().feed(mt.encode_read(address, 12)))  # V_IST (3.2.12)
    return mt.bytes_to_words(reply.data)[0]


def test_the_load_options_reach_each_served_motor(served: Any) -> None:
    line, code = served("-a", "19", "-a", "20", "--load-inertia", "1e-4", "--load-inertia",
                        "2e-5", "--coulomb-friction", "0.01", "--viscous-friction", "3e-5",
                        "--coupling-stiffness", "5", "--coupling-stiffness", "0",
                        "--coupling-damping", "1e-4", "--coupling-damping", "0")
    assert code == 1  # the stand-in server's start
    p = line.m.parameters
    np.testing.assert_array_equal(p["load_inertia"], [1e-4, 2e-5])
    np.testing.assert_array_equal(p["coulomb_friction"], [0.01, 0.01])
    np.testing.assert_array_equal(p["viscous_friction"], [3e-5, 3e-5])
    np.testing.assert_array_equal(p["coupling_stiffness"], [5.0, 0.0])
    np.testing.assert_array_equal(p["coupling_damping"], [1e-4, 0.0])
    assert line.addresses() == [19, 20]  # the power-on with the load keeps the addresses


def test_a_served_mac140_with_a_load_inertia_accelerates_as_rotor_plus_load(served: Any
                                                                              ) -> None:
    bare, _ = served("-a", "19", *RIGID)
    loaded, _ = served("-a", "19", *RIGID, "--load-inertia", "1e-4")
    t_bare, a_bare = _accelerate(bare)
    t_loaded, a_loaded = _accelerate(loaded)
    assert t_bare / a_bare == pytest.approx(J_M, rel=0.02)
    assert t_loaded / a_loaded == pytest.approx(J_M + 1e-4, rel=0.02)
    # under about the same torque the loaded rotor turns (J_m + J_l)/J_m ≈ 6.8 times slower
    assert 5.5 < _v_ist_over_mactalk(bare, 19) / _v_ist_over_mactalk(loaded, 19) < 8.0


def test_a_coupling_stiffness_serves_a_two_mass_plant_at_its_resonance(served: Any) -> None:
    j_l, f_res = 1e-4, 100.0
    w = 2 * math.pi * f_res
    k = w * w / (1 / J_M + 1 / j_l)  # tuning.identify_resonance.coupling_of
    d = 2 * 0.05 * w * J_M * j_l / (J_M + j_l)
    line, _ = served("-a", "19", *RIGID, "--load-inertia", str(j_l),
                     "--coupling-stiffness", repr(k), "--coupling-damping", repr(d))
    rigid, _ = served("-a", "19", *RIGID, "--load-inertia", str(j_l))
    twist = []
    for twin in (line, rigid):
        m = twin.m
        m.write("MODE_REG", c.AT_MODE)
        m.set_input(analog_volts=0.2)
        angles = []
        for _ in range(52):  # 0.1 s
            m.step(1)
            angles.append(m.position_rad[0] - m.load_angle[0])
        twist.append(np.array(angles))
    np.testing.assert_array_equal(twist[1], 0.0)  # a rigid load turns with the shaft
    swing = twist[0] - twist[0].mean()
    crossings = np.count_nonzero(np.diff(np.sign(swing)) != 0)
    assert crossings / 2 / (52 * c.OUTER_DT) == pytest.approx(f_res, rel=0.15)


@pytest.mark.parametrize(("argv", "words"), [
    (["--load-inertia", "-1e-4"], "--load-inertia: values must be >= 0"),
    (["--coulomb-friction", "nan"], "--coulomb-friction: values must be finite"),
    (["--viscous-friction", "inf"], "--viscous-friction: values must be finite"),
    (["--load-inertia", "1e-4", "--load-inertia", "1e-4", "--load-inertia", "1e-4"],
     "--load-inertia: give one value for every motor or one per --address (2), got 3"),
    (["--coupling-damping", "1e-4"], "--coupling-damping 0.0001 for the motor at address 19 "
     "needs a --coupling-stiffness > 0"),
    (["--coupling-stiffness", "5"], "motor at address 19: --load-inertia must be > 0"),
    (["--coupling-stiffness", "1e9", "--load-inertia", "1e-4"],
     "--coupling-stiffness 1e+09 N·m/rad gives a coupling natural frequency"),
    (["-m", "MAC800", "--coupling-stiffness", "5", "--load-inertia", "1e-4"],
     "--coupling-stiffness: the MAC800 integrated servo motors (MAC800) model no coupling "
     "stiffness (only the MAC050–141 integrated servo motors do)"),
    (["-m", "MIS231", "--coupling-damping", "1e-4", "--coupling-stiffness", "5",
      "--load-inertia", "1e-4"], "--coupling-stiffness: the MIS/SMC integrated step motors"),
])
def test_bad_load_values_are_one_line_errors_and_nothing_is_served(
        served: Any, capsys: pytest.CaptureFixture[str], argv: list[str], words: str) -> None:
    line, code = served("-a", "19", "-a", "20", *argv)
    assert line is None and code == 2
    err = [line for line in capsys.readouterr().err.strip().splitlines()
           if not line.startswith("jvl_gym: compil")]  # first-use compile notices
    assert len(err) == 1 and words in err[0], err


def test_a_family_without_a_coupling_takes_a_rigid_load(served: Any) -> None:
    line, code = served("-m", "MAC800", "-a", "3", "--load-inertia", "2e-4",
                        "--coupling-stiffness", "0")
    assert code == 1
    assert line.m.parameters["load_inertia"][0] == 2e-4


_VALUES = st.floats(allow_nan=True, allow_infinity=True, width=64)


@settings(max_examples=30, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(option=st.sampled_from(["--load-inertia", "--coulomb-friction", "--viscous-friction"]),
       values=st.lists(_VALUES, min_size=1, max_size=3))
def test_a_load_value_is_served_exactly_or_refused_in_one_line(
        served: Any, capsys: pytest.CaptureFixture[str], option: str,
        values: list[float]) -> None:
    argv = [a for v in values for a in (option, repr(v))]
    line, code = served("-a", "19", "-a", "20", *argv)
    err = capsys.readouterr().err.strip().splitlines()
    ok = len(values) in (1, 2) and all(math.isfinite(v) and v >= 0 for v in values)
    if not ok:
        assert line is None and code == 2 and len(err) == 1 and option in err[0]
        return
    expected = values * (2 // len(values))
    np.testing.assert_array_equal(line.m.parameters[LOAD_OPTIONS[option]], expected)


@given(n=st.integers(1, 4), counts=st.dictionaries(st.sampled_from(list(LOAD_OPTIONS)),
                                                   st.integers(0, 5)))
def test_load_per_motor_takes_one_value_or_one_per_address(n: int,
                                                           counts: dict[str, int]) -> None:
    given_values = {o: [float(k + 1) for k in range(m)] for o, m in counts.items()}
    addresses = list(range(1, n + 1))
    damped = [o for o in given_values if o == "--coupling-damping" and given_values[o]]
    if any(m not in (0, 1, n) for m in counts.values()) or (
            damped and not given_values.get("--coupling-stiffness")):
        with pytest.raises(LoadError):
            load_per_motor(given_values, addresses)
        return
    load = load_per_motor(given_values, addresses)
    for option, values in given_values.items():
        if values:
            assert load[LOAD_OPTIONS[option]] == (values if len(values) == n else values * n)
        else:
            assert LOAD_OPTIONS[option] not in load


# ------------------------------------------------------------------ addresses and ports
def _error_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = [line for line in capsys.readouterr().err.strip().splitlines()
           if not line.startswith("jvl_gym: compil")]  # first-use compile notices
    assert len(err) == 1, err
    return err[0]


@pytest.mark.parametrize("motors", [("MIS232", "MIS232"), ("MAC140", "MAC140"),
                                    ("MAC140", "MIS232")])
def test_two_motors_at_one_address_are_refused_before_anything_is_served(
        served: Any, capsys: pytest.CaptureFixture[str], motors: tuple[str, str]) -> None:
    line, code = served("-m", motors[0], "-a", "3", "-m", motors[1], "-a", "3")
    assert line is None and code == 2
    text = _error_line(capsys)
    assert "--address" in text and "same address 3" in text and motors[1] in text


def test_two_flash_files_at_one_address_are_refused(
        served: Any, capsys: pytest.CaptureFixture[str], tmp_path: Any) -> None:
    """The flash files of a --flash-dir set MYADDR at power-on: two motors given one address
    there are refused as two --address values would be."""
    from jvl_gym.families.mis.table import TABLE

    myaddr = TABLE.lookup("MY_ADDR").number
    for i in range(2):
        (tmp_path / f"flash_{i}.json").write_text(
            f'{{"motor": {i}, "registers": {{"{myaddr}": 9}}}}')
    line, code = served("-m", "MIS232", "-a", "3", "-a", "4", "--flash-dir", str(tmp_path))
    assert line is None and code == 2
    text = _error_line(capsys)
    assert "--flash-dir" in text and "same address 9" in text


@settings(max_examples=30, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(base=st.one_of(st.integers(-2**40, 3), st.integers(65530, 2**40)),
       n=st.integers(1, 3))
def test_user_tcp_base_port_is_a_tcp_port_for_every_motor(
        served: Any, capsys: pytest.CaptureFixture[str], base: int, n: int) -> None:
    """Motor i's user interface listens on BASE+i: every one of them a port 1..65535, or
    BASE 0 (free ports); anything else is a usage error before anything is served."""
    argv = [a for k in range(n) for a in ("-a", str(k + 1))]
    line, code = served("-m", "MAC050", *argv, "--user-tcp", str(base))
    err = capsys.readouterr().err.strip().splitlines()
    if base == 0 or 1 <= base <= 65536 - n:
        assert code == 1 and line is not None  # up to the (stand-in) server's start
        return
    assert line is None and code == 2 and len(err) == 1 and "--user-tcp" in err[0], err


def test_a_record_length_below_one_is_a_usage_error(
        served: Any, capsys: pytest.CaptureFixture[str]) -> None:
    line, code = served("--record-length", "0")
    assert line is None and code == 2 and "--record-length" in _error_line(capsys)


@pytest.mark.parametrize(("motor", "length"), [("MAC140", "896"), ("MIS232", "10")])
def test_a_record_length_the_motor_refuses_is_a_usage_error(
        served: Any, capsys: pytest.CaptureFixture[str], motor: str, length: str) -> None:
    """Beyond the sample buffer's depth, or on a motor type without a TESTU/TESTA record
    length, ``--record-length`` is a one-line usage error naming the option and the type."""
    line, code = served("-m", motor, "--record-length", length)
    err = _error_line(capsys)
    assert line is None and code == 2 and "--record-length" in err and motor in err

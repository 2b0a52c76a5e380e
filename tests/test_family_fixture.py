"""A second motor family from a fixture folder (tests/fixtures/toy_family) runs through the
generic layers — MotorArray, the MacTalk twin (read, write, safe mode, flash save and reload)
and a task env — with no edit outside it: everything the layers need is in its contract
(``FAMILY``, :mod:`jvl_gym.families.contract`)."""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from jvl_gym import MotorArray
from jvl_gym.families import Capability, UnsupportedOperation, family_of_motor, register_family
from jvl_gym.protocol.mactalk import codec16 as mt
from jvl_gym.protocol.mactalk.twin16 import Twin

FIXTURES = Path(__file__).resolve().parent / "fixtures"


@pytest.fixture(scope="module", autouse=True)
def toy() -> None:
    sys.path.insert(0, str(FIXTURES))
    register_family("toy", "toy_family")
    yield
    sys.path.remove(str(FIXTURES))


def test_a_motor_type_of_the_fixture_makes_a_toy_array() -> None:
    m = MotorArray("TOY1", n=3, seed=0, inertia=[1e-4, 2e-4, 4e-4])
    assert type(m).__name__ == "ToyMotorArray"
    assert family_of_motor("TOY1").key == "toy"
    assert m.read("KP").tolist() == [2.0, 2.0, 2.0]
    m.write_many({"V_SOLL": 400, "MODE_REG": 1})
    m.step(300)
    speed = m.read("V_IST")
    assert np.all(np.abs(speed - 400) < 40)
    assert speed[0] != speed[2] or m.speed[0] != m.speed[2]  # the inertias differ
    with pytest.raises(Exception, match="MODE_REG"):
        m.write("MODE_REG", 5)  # out of the toy table's range: nothing changes
    assert m.read("MODE_REG").tolist() == [1, 1, 1]


def test_one_toy_motor_equals_its_row_of_an_array() -> None:
    big = MotorArray("TOY1", n=5, seed=1, inertia=np.linspace(1e-4, 3e-4, 5))
    big.write_many({"V_SOLL": 300, "MODE_REG": 1})
    big.step(50)
    one = MotorArray("TOY1", n=1, seed=1, inertia=np.linspace(1e-4, 3e-4, 5)[3])
    one.write_many({"V_SOLL": 300, "MODE_REG": 1})
    one.step(50)
    np.testing.assert_array_equal(one.state[0], big.state[3])


def test_the_twin_reads_and_writes_toy_registers_over_mactalk() -> None:
    m = MotorArray("TOY1", n=2, seed=0)
    twin = Twin(m, addresses=[5, 6])
    session = twin.session()
    reply = session.feed(mt.encode_write(6, 3, mt.words_to_bytes([250]))) + session.flush()
    assert reply == mt.ACCEPT
    assert m.read("V_SOLL").tolist() == [0, 250]
    reply = mt.decode(session.feed(mt.encode_read(6, 3)) + session.flush())
    assert isinstance(reply, mt.DataReply)
    assert mt.bytes_to_words(reply.data)[0] == 250
    # a write the table refuses (MODE_REG above 1) changes nothing
    session.feed(mt.encode_write(5, 2, mt.words_to_bytes([7])))
    session.flush()
    assert m.read("MODE_REG").tolist() == [0, 0]


def test_a_task_env_on_the_toy_family() -> None:
    from toy_family.speed_env import ToySpeedVectorEnv

    vec = ToySpeedVectorEnv(num_envs=3)
    obs, _ = vec.reset(seed=4)
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, (20, 3, 1))
    for a in actions:
        obs, reward, term, trunc, _ = vec.step(a)
    single = ToySpeedVectorEnv(num_envs=1)
    single.reset(seed=6)
    for a in actions:
        obs1, reward1, *_ = single.step(a[2:3])
    np.testing.assert_array_equal(obs1[0], obs[2])  # copy 2 of the vector env = a single env
    assert np.all(np.isfinite(reward))

    from jvl_gym.envs.single import MotorEnv

    class ToySpeedEnv(MotorEnv):
        vector_class = ToySpeedVectorEnv

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(ToySpeedEnv(), skip_render_check=True)
    assert not caught, [str(w.message) for w in caught]


def test_a_world_source_for_an_input_the_family_lacks_is_refused() -> None:
    """The toy drive has no pulse input: a world that drives one is refused before the step,
    and nothing moves."""
    from jvl_gym.world import PulseInput, SpeedProfile, World

    m = MotorArray("TOY1")
    m.write_many({"V_SOLL": 500, "MODE_REG": 1})
    before = m.regs.copy(), m.state.copy()
    m.world = World(pulse=PulseInput(SpeedProfile.constant(1.0, n=1), lines=1000))
    with pytest.raises(ValueError, match="pulse_counts"):
        m.step(1)
    np.testing.assert_array_equal(m.regs, before[0])
    np.testing.assert_array_equal(m.state, before[1])


def test_world_inputs_of_a_family_go_through_the_generic_checks() -> None:
    """``set_input`` is the engine's: the toy family only declares its inputs; a bad value or
    an unknown input changes nothing."""
    m = MotorArray("TOY1", n=2)
    m.set_input(load_torque=[0.5, -0.5])
    np.testing.assert_array_equal(m.inputs[:, 0], [0.5, -0.5])
    for bad, error in (({"load_torque": np.nan}, ValueError), ({"load_torque": [1.0]}, ValueError),
                       ({"load_torque": "1"}, ValueError), ({"pulse_counts": 1}, TypeError)):
        with pytest.raises(error):
            m.set_input(**bad)
        np.testing.assert_array_equal(m.inputs[:, 0], [0.5, -0.5])
    with pytest.raises(AttributeError, match="no shaft state"):
        m.speed_rpm  # noqa: B018  (the toy declares no shaft columns)


def ask(twin: Twin, frame: bytes) -> bytes:
    session = twin.session()
    return session.feed(frame) + session.flush()


def test_the_twin_saves_the_toy_registers_to_flash_and_reloads_them(tmp_path: Path) -> None:
    """Safe mode, write flash and reset over MacTalk as the toy's contract declares them: the
    flash file holds the registers, and a new twin on a fresh array powers on from it."""
    m = MotorArray("TOY1", n=1, seed=0)
    twin = Twin(m, addresses=[5], flash_dir=tmp_path)
    assert ask(twin, mt.encode_write(5, 7, mt.words_to_bytes([3 * 256]))) == mt.ACCEPT
    assert ask(twin, mt.encode_write_flash(5)) == b""  # refused outside safe mode
    assert twin.stats["refused"] == 1 and not (tmp_path / "flash_0.json").exists()
    assert ask(twin, mt.encode_go_safe_mode(5)) == mt.ACCEPT
    assert m.mode_name(0) == "safe"
    assert ask(twin, mt.encode_write_flash(5)) == b""  # saved, then reset from flash
    assert (tmp_path / "flash_0.json").exists()
    assert m.read("KP").tolist() == [3.0] and m.mode_name(0) == "passive"
    again = MotorArray("TOY1", n=1, seed=0)
    assert again.read("KP").tolist() == [2.0]
    twin.close()  # the flash directory has one owner: the first twin gives it up
    Twin(again, addresses=[5], flash_dir=tmp_path)
    assert again.read("KP").tolist() == [3.0] and again.read("MYADDR").tolist() == [5]
    assert ask(twin, mt.encode_go_safe_mode(5)) == mt.ACCEPT
    assert ask(twin, mt.encode_go_init_mode(5)) == mt.ACCEPT  # leaves safe mode
    assert m.mode_name(0) == "passive"


def test_programs_and_fieldbuses_the_toy_does_not_declare_are_refused_by_name(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The program CLI and the CANopen slave ask the family record: the toy, declaring neither
    Capability.PROGRAMS nor Capability.CANOPEN, is refused by name; the program CLI lists the
    motor types of the registered families that run programs."""
    from jvl_gym.cli.main import app
    from jvl_gym.families import families_with
    from jvl_gym.protocol.canopen.facts import facts_of, has_canopen

    m = MotorArray("TOY1", n=1, seed=0)
    assert not has_canopen(m)
    with pytest.raises(UnsupportedOperation, match="CANOPEN"):
        facts_of(m)
    (tmp_path / "p.txt").write_text("mode mode=position\n")
    with pytest.raises(SystemExit) as info:
        app(["program", "run", str(tmp_path / "p.txt"), "--motor", "TOY1", "--seconds", "0.01",
             "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    types = [t for fam in families_with(Capability.PROGRAMS) for t in fam.motor_types()]
    assert info.value.code == 2 and err.count("\n") == 1 and "Capability.PROGRAMS" in err
    assert types and f"({', '.join(types)})" in err and "TOY1" not in err.split(";")[1]
    assert not (tmp_path / "o").exists()


def test_operations_the_toy_does_not_declare_are_refused_by_name() -> None:
    """The toy has no sample buffer, torque, energy or init-mode command: the array raises
    UnsupportedOperation naming the capability, the twin refuses and nothing changes."""
    m = MotorArray("TOY1", n=1, seed=0)
    for call, cap in ((lambda: m.sample_buffer(), Capability.SAMPLE_BUFFER),
                      (lambda: m.torque, Capability.TORQUE),
                      (lambda: m.energy, Capability.ENERGY),
                      (lambda: m.go_init_mode(), Capability.INIT_MODE)):
        with pytest.raises(UnsupportedOperation, match=cap.name) as info:
            call()
        assert info.value.capability is cap
    twin = Twin(m, addresses=[5])
    before = m.regs.copy()
    assert ask(twin, mt.encode_read_sample_buffer(5)) == b""
    assert ask(twin, mt.encode_go_init_mode(5)) == b""
    assert twin.stats["refused"] == 2 and "INIT_MODE" in twin.last_refusal
    np.testing.assert_array_equal(m.regs, before)


def test_jvl_tune_autotune_runs_the_toy_familys_own_strategy(tmp_path: Path) -> None:
    """``jvl-tune autotune --motor TOY1`` goes through the one pipeline with the strategy the
    toy family names in its contract (``TuningSpec.implementation``, in the fixture folder):
    the identified inertia is the simulated one, the kept gain settles the speed step faster
    than the table's default, and the setup written loads."""
    from tuning.cli import app
    from typer.testing import CliRunner

    res = CliRunner().invoke(app, ["autotune", "--motor", "TOY1", "--load-inertia", "2e-4",
                                   "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    report = (tmp_path / "report.txt").read_text()
    row = next(ln for ln in report.splitlines() if ln.startswith("J "))
    J, true_J = float(row.split()[1]), float(row.split()[-1])
    assert true_J == pytest.approx(4e-4) and J == pytest.approx(true_J, rel=0.05)
    assert "kept the p design" in report
    assert {p.name for p in tmp_path.iterdir()} >= {"setup.yaml", "report.txt", "fits.png",
                                                    "bode.png", "steps.png"}
    m = MotorArray("TOY1", n=1)
    m.load_setup(tmp_path / "setup.yaml")
    assert m.read("KP")[0] > 2.0  # the designed gain, above the default's
    # an option the toy strategy does not take is refused, naming it, and nothing is written
    res = CliRunner().invoke(app, ["autotune", "--motor", "TOY1", "--structure", "ip",
                                   "--out", str(tmp_path / "no")])
    assert res.exit_code != 0 and "--structure" in res.output
    assert not (tmp_path / "no").exists()

"""``jvl-gym program run``: a program with an I/O script on a simulated MIS, its trace CSV and
plot; errors one line with exit status 2."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jvl_gym.cli.main import app
from jvl_gym.families import Capability, families_with
from jvl_gym.families.mis.program.bench import IoScriptError, load_io_script

PICK = """mode mode=position
move_sensor distance=20480 velocity=300 safety_distance=409600 input=3 condition=high
set_output output=1 state=high
wait_input input=1 condition=rising
move_absolute position=0 velocity=600
set_output output=1 state=low
jump line=7
"""
IO = """registers: {A_SOLL: 20000, IN_POSITION_COUNT: 0}
sensors:
  - {input: 3, from: 200000, to: 220000}
inputs:
  - {t: 0.5, set: {1: high}}
load: [{t: 0, torque: 0.02}]
"""


def _run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as info:
        app(args)
    out, err = capsys.readouterr()
    err = "".join(line for line in err.splitlines(keepends=True)
                  if not line.startswith("jvl_gym: compil"))  # first-use compile notices
    return int(info.value.code or 0), out, err


def _files(tmp_path: Path, program: str = PICK, io: str = IO) -> tuple[Path, Path]:
    (tmp_path / "p.txt").write_text(program)
    (tmp_path / "io.yaml").write_text(io)
    return tmp_path / "p.txt", tmp_path / "io.yaml"


def test_program_run_writes_the_trace(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                      ) -> None:
    prog, io = _files(tmp_path)
    code, out, _ = _run(["program", "run", str(prog), "--motor", "MIS232", "--seconds", "1",
                         "--io", str(io), "--out", str(tmp_path / "o")], capsys)
    assert code == 0 and "at line 7" in out
    rows = list(csv.DictReader((tmp_path / "o" / "trace.csv").open()))
    assert len(rows) == 1000 and rows[0]["t [s]"] == "0.001"
    hit = next(r for r in rows if int(r["INPUTS"]) & 4)  # the sensor at 200000 counts
    assert float(hit["rotor [counts]"]) >= 200000
    stop = next(r for r in rows if int(r["OUTPUTS"]) & 1)  # 20480 counts after it
    assert int(stop["P_IST"]) == int(hit["P_IST"]) + 20480 or abs(
        int(stop["P_IST"]) - int(hit["P_IST"]) - 20480) < 2048
    at_input = [r for r in rows if float(r["t [s]"]) > 0.5 and r["line"] == "5"]
    assert at_input and float(at_input[0]["t [s]"]) <= 0.503  # the input 1 edge at 0.5 s
    assert rows[-1]["line"] == "7" and rows[-1]["OUTPUTS"] == "0"
    assert (tmp_path / "o" / "trace.png").stat().st_size > 10000


@pytest.mark.parametrize(("program", "io", "args", "words"), [
    ("mode mode=position\nmove_relative distance=x\n", IO, [], "line 2, field distance"),
    (PICK, "inputs: [{t: -1, set: {1: high}}]\n", [], "inputs[0].t"),
    (PICK, "sensors: [{input: 9, from: 0, to: 1}]\n", [], "input 9"),
    (PICK, "bogus: 1\n", [], "unknown key 'bogus'"),
    (PICK, IO, ["--motor", "MAC140"], "no stored programs (the family does not declare "
                                      "Capability.PROGRAMS); give a motor type that runs "
                                      "stored programs (MIS171, "),
    (PICK, IO, ["--motor", "MIS999"], "--motor MIS999"),
    (PICK, "registers: {NOPE: 1}\n", [], "NOPE"),
])
def test_errors_are_one_line_with_status_2(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                           program: str, io: str, args: list[str],
                                           words: str) -> None:
    prog, script = _files(tmp_path, program, io)
    code, _, err = _run(["program", "run", str(prog), "--io", str(script), "--seconds", "0.01",
                         "--out", str(tmp_path / "o"), *args], capsys)
    assert code == 2 and err.count("\n") == 1 and words in err, err
    assert not (tmp_path / "o").exists()


def test_io_script_checks() -> None:
    s = load_io_script({"inputs": [{"t": 1, "set": {2: "high"}}, {"t": 0, "set": {2: 0}}],
                        "load": 0.1})
    assert s.inputs == [(0.0, {2: 0}), (1.0, {2: 1})] and s.load == [(0.0, 0.1)]
    with pytest.raises(IoScriptError, match="level"):
        load_io_script({"inputs": [{"t": 0, "set": {1: "on"}}]})
    with pytest.raises(IoScriptError, match="from"):
        load_io_script({"sensors": [{"input": 1, "from": 5, "to": 1}]})


def test_the_motor_defaults_to_a_family_that_runs_programs(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Without --motor the program runs on the first motor type of the first registered family
    that declares Capability.PROGRAMS."""
    prog, io = _files(tmp_path)
    code, out, _ = _run(["program", "run", str(prog), "--seconds", "0.01", "--io", str(io),
                         "--out", str(tmp_path / "o")], capsys)
    first = families_with(Capability.PROGRAMS)[0]
    assert code == 0 and f" on {first.motor_types()[0]}, " in out
    assert first.programs is not None and first.programs.ProgramError.__name__ == "ProgramError"


_FEW = settings(max_examples=25, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture])


@_FEW
@given(seconds=st.one_of(st.sampled_from([math.nan, math.inf, -math.inf, 0.0]),
                         st.floats(max_value=0.000999), st.floats(min_value=3600.001)))
def test_seconds_out_of_range_say_the_range(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                            seconds: float) -> None:
    """A time that is not 0.001 … 3600 s (NaN too) is a usage error that names it and the
    range, and nothing is written."""
    prog, io = _files(tmp_path)
    out = tmp_path / "o"
    code, _, err = _run(["program", "run", str(prog), "--seconds", repr(seconds), "--out",
                         str(out)], capsys)
    assert code == 2 and err.count("\n") == 1, err
    assert "--seconds" in err and "0.001 to 3600" in err and not out.exists()


@_FEW
@given(number=st.one_of(st.integers(max_value=0), st.integers(min_value=254)))
def test_a_register_number_the_motor_has_not_is_named(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str],
                                                      number: int) -> None:
    prog, io = _files(tmp_path)
    out = tmp_path / "o"
    code, _, err = _run(["program", "run", str(prog), "--motor", "MIS232", "--seconds", "0.01",
                         "--register", str(number), "--out", str(out)], capsys)
    assert code == 2 and err.count("\n") == 1, err
    assert f"--register {number}: no register number {number}" in err
    assert "mis-registers.md" in err and not out.exists()


def test_a_register_to_trace_by_number(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                       ) -> None:
    prog, io = _files(tmp_path)
    code, _, err = _run(["program", "run", str(prog), "--motor", "MIS232", "--seconds", "0.01",
                         "--register", "51", "--out", str(tmp_path / "o")], capsys)
    assert code == 0, err
    header = (tmp_path / "o" / "trace.csv").read_text().splitlines()[0]
    assert "P2" in header.split(",")


def test_a_program_without_a_mode_line_runs_as_from_power_on(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The run is a power-on: the motor takes the mode a stored program gives it (position
    mode, MIS manual §9.1) and the program's first move runs without a mode line."""
    from jvl_gym.families.mis import constants as c

    prog, io = _files(tmp_path, "move_relative distance=40960 velocity=300\n"
                                "set_output output=1 state=high\njump line=3\n", "")
    code, _, err = _run(["program", "run", str(prog), "--motor", "MIS232", "--seconds", "1",
                         "--out", str(tmp_path / "o")], capsys)
    assert code == 0, err
    rows = list(csv.DictReader((tmp_path / "o" / "trace.csv").open()))
    assert int(rows[0]["MODE_REG"]) == c.POSITION
    done = [r for r in rows if int(r["OUTPUTS"]) & 1]
    assert done and abs(int(done[0]["P_IST"]) - 40960) < 2048 and rows[-1]["line"] == "3"


def test_a_file_larger_than_the_motor_holds_is_refused_unread(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
        ) -> None:
    from jvl_gym.families.mis.program.format import MAX_TEXT_BYTES

    big = tmp_path / "big.txt"
    with big.open("wb") as fh:  # a sparse 64 MB file
        fh.truncate(64 * 2**20)
    opened: list[Path] = []
    real_open = Path.open
    monkeypatch.setattr(Path, "open", lambda self, *a, **k: (
        opened.append(self), real_open(self, *a, **k))[1])
    code, _, err = _run(["program", "run", str(big), "--motor", "MIS232", "--seconds", "0.01",
                         "--out", str(tmp_path / "o")], capsys)
    assert code == 2 and err.count("\n") == 1 and len(err) < 400, err
    assert f"{64 * 2**20} bytes is more than any program" in err and str(MAX_TEXT_BYTES) in err
    assert big not in opened and not (tmp_path / "o").exists()


def test_an_io_script_larger_than_the_limit_is_refused_unread(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
        ) -> None:
    from jvl_gym.cli.program import MAX_IO_SCRIPT_BYTES

    prog, _ = _files(tmp_path)
    big = tmp_path / "big.yaml"
    with big.open("wb") as fh:  # a sparse 64 MB file
        fh.truncate(64 * 2**20)
    opened: list[Path] = []
    for name in ("open", "read_text", "read_bytes"):
        real = getattr(Path, name)
        monkeypatch.setattr(Path, name, lambda self, *a, real=real, **k: (
            opened.append(self), real(self, *a, **k))[1])
    code, _, err = _run(["program", "run", str(prog), "--motor", "MIS232", "--seconds", "0.01",
                         "--io", str(big), "--out", str(tmp_path / "o")], capsys)
    assert code == 2 and err.count("\n") == 1 and len(err) < 400, err
    assert f"{64 * 2**20} bytes is more than an I/O script may have" in err
    assert str(MAX_IO_SCRIPT_BYTES) in err and "nothing was read" in err
    assert big not in opened and not (tmp_path / "o").exists()


@pytest.mark.parametrize(("io", "words"), [
    ("just text\n", "the top level is a mapping"),
    ("inputs: [\n", "io script: while parsing"),
])
def test_an_io_script_that_is_no_mapping_is_one_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], io: str, words: str) -> None:
    prog, script = _files(tmp_path, io=io)
    code, _, err = _run(["program", "run", str(prog), "--motor", "MIS232", "--seconds", "0.01",
                         "--io", str(script), "--out", str(tmp_path / "o")], capsys)
    assert code == 2 and err.count("\n") == 1 and words in err, err
    assert not (tmp_path / "o").exists()


def test_an_error_quoting_the_file_is_short(tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    # a file of NULs under the size limit: the error shows a piece of it and its length
    prog = tmp_path / "nul.txt"
    prog.write_bytes(b"\0" * 1_000_000)
    code, _, err = _run(["program", "run", str(prog), "--motor", "MIS232", "--seconds", "0.01",
                         "--out", str(tmp_path / "o")], capsys)
    assert code == 2 and err.count("\n") == 1 and len(err) < 400, err
    assert "line 1: the line has 1000000 bytes, more than 1024" in err
    assert "(1000000 characters)" in err


def _interrupting(monkeypatch: pytest.MonkeyPatch, error: BaseException) -> list:
    """Make the bench run 50 ms of the program, then raise ``error``; the motors it ran on."""
    import jvl_gym.families.mis.program as programs

    real = programs.run_bench
    seen: list = []

    def run_bench(m, seconds, script=None, extra=()):
        seen.append(m)
        real(m, 0.05, script, extra)
        raise error

    monkeypatch.setattr(programs, "run_bench", run_bench)
    return seen


@pytest.mark.parametrize(("error", "status", "words"), [
    (KeyboardInterrupt(), 130, "interrupted at 0.05"),
    (RuntimeError("boom"), 1, "boom"),
])
def test_ctrl_c_or_an_error_stops_the_program_and_the_motor(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch,
        error: BaseException, status: int, words: str) -> None:
    from jvl_gym.families import family_of_motor

    seen = _interrupting(monkeypatch, error)
    prog, io = _files(tmp_path, "move_relative distance=4096000 velocity=3000\njump line=1\n",
                      "")
    code, _, err = _run(["program", "run", str(prog), "--motor", "MIS232", "--seconds", "1",
                         "--out", str(tmp_path / "o")], capsys)
    assert code == status and err.count("\n") == 1 and words in err, err
    m = seen[0]
    assert m.read_raw("MODE_REG")[0] == family_of_motor("MIS232").twin.passive_mode
    assert m.program_status(0).name == "stopped" and not (tmp_path / "o").exists()

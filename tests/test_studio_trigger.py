"""The scope's trigger, time base, cursors, trace scaling and recording, and the sample buffer
on the same trigger (within one sample of the level crossing)."""

from __future__ import annotations

import time

import numpy as np
import pytest

from jvl_gym.studio import capture
from jvl_gym.studio.session import Session
from jvl_gym.studio.trigger import (
    TIME,
    Edge,
    Recorder,
    Trigger,
    TriggerMode,
    crossing_time,
    cursors,
    find_trigger,
    scaled,
    window,
)


def _ramp() -> dict:
    t = np.arange(0.0, 1.0, 0.01)
    return {TIME: t, "x [V]": np.where(t < 0.5, 0.0, (t - 0.5) * 10.0)}  # 0 V, then 10 V/s


def test_rising_and_falling_edges():
    v = [0, 1, 2, 3, 2, 1, 0]
    assert find_trigger(v, Trigger("x", 1.5)) == 2
    assert find_trigger(v, Trigger("x", 1.5, Edge.FALLING)) == 5
    assert find_trigger(v, Trigger("x", 5.0)) is None
    assert find_trigger(v, Trigger("x", 2.0)) == 2  # at the level counts as crossed
    assert crossing_time(np.arange(7.0), np.asarray(v, float), 2, 1.5) == pytest.approx(1.5)


def test_single_holds_a_whole_window_not_the_edge_alone():
    """Single mode: a crossing recorded with too little after it is not yet the trigger (the
    scope would stop on the edge alone); once ``(1 − pre) · span`` after it is recorded, the
    window is the whole span around the crossing."""
    s = _ramp()  # crosses 1 V at 0.6 s; recorded to 0.99 s
    trig = Trigger("x [V]", 1.0, pre=0.25)
    assert window(s, trig, 0.8, TriggerMode.SINGLE) is None  # needs 0.6 s after: to 1.2 s
    assert window(s, trig, 0.8, TriggerMode.NORMAL) is not None
    w = window(s, trig, 0.4, TriggerMode.SINGLE)  # needs 0.3 s after: to 0.9 s
    assert w[TIME][0] == pytest.approx(-0.1, abs=0.011)
    assert w[TIME][-1] == pytest.approx(0.3, abs=0.011)


def test_a_window_around_the_trigger_with_its_pre_trigger_share():
    s = _ramp()
    w = window(s, Trigger("x [V]", 1.0, pre=0.25), span=0.4)
    # 1 V is reached 0.1 s after the ramp starts at 0.5 s: time 0 there
    t = w[TIME]
    assert t[0] == pytest.approx(-0.1, abs=0.011) and t[-1] == pytest.approx(0.3, abs=0.011)
    assert np.interp(0.0, t, w["x [V]"]) == pytest.approx(1.0)
    # no crossing: auto shows the latest span, normal and single nothing
    high = Trigger("x [V]", 100.0)
    assert window(s, high, 0.2, TriggerMode.AUTO)[TIME][0] == pytest.approx(0.79, abs=0.011)
    assert window(s, high, 0.2, TriggerMode.NORMAL) is None
    assert window(s, high, 0.2, TriggerMode.SINGLE) is None
    with pytest.raises(ValueError, match="no channel"):
        window(s, Trigger("y", 1.0), 0.2)
    with pytest.raises(ValueError, match="span"):
        window(s, None, 0.0)
    with pytest.raises(ValueError, match="pre-trigger"):
        Trigger("x [V]", 1.0, pre=1.5)


def test_cursors_read_dt_dvalue_and_frequency():
    c = cursors(_ramp(), "x [V]", 0.6, 0.8)
    assert c.dt == pytest.approx(0.2) and c.dvalue == pytest.approx(2.0)
    assert c.frequency == pytest.approx(5.0)
    assert "1/Δt = 5 Hz" in c.text("V")


def test_scale_and_offset_on_a_shared_axis():
    assert list(scaled(np.array([1.0, 2.0]), 10.0, -5.0)) == [5.0, 15.0]
    with pytest.raises(ValueError):
        scaled(np.array([1.0]), float("nan"))


def test_recording_to_csv_with_elapsed_time_and_size(tmp_path):
    rec = Recorder(tmp_path / "r.csv", ["a [V]", "b [rpm]"])
    for k in range(100):
        rec.add(k * 0.01, [k, -k])
    assert rec.elapsed == pytest.approx(0.99) and rec.rows == 100 and rec.size > 1000
    path = rec.stop()
    lines = path.read_text().splitlines()
    assert lines[0] == "t [s],a [V],b [rpm]" and len(lines) == 101
    with pytest.raises(ValueError, match="a row has 2 values"):
        Recorder(tmp_path / "s.csv", ["a", "b"]).add(0.0, [1.0])
    with pytest.raises(ValueError, match=r"\.csv or \.parquet"):
        Recorder(tmp_path / "r.txt", ["a"])


def test_recording_to_parquet_where_pyarrow_is(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")
    rec = Recorder(tmp_path / "r.parquet", ["a [V]"])
    rec.add(0.0, [1.0])
    rec.add(0.5, [2.0])
    table = pq.read_table(rec.stop())
    assert table.column_names == ["t [s]", "a [V]"]
    assert table.column("a [V]").to_pylist() == [1.0, 2.0]


@pytest.fixture(scope="module")
def running() -> Session:
    s = Session.simulated(["MAC140", "MIS232", "MAC800"], seed=5)
    s.start()
    yield s
    s.stop()


@pytest.mark.parametrize("k, level", [(0, 100.0), (1, 60.0), (2, 50.0)],
                         ids=["MAC140", "MIS232", "MAC800"])
def test_a_sample_buffer_capture_triggers_within_one_sample_of_the_crossing(running, k,
                                                                             level):
    """A speed step recorded in the motor's sample buffer (MAC050–141 manual 3.2.112–3.2.116,
    the MAC800 by the same RECORD and REWIND bits, MIS manual §8.2.60–8.2.63), triggered on
    V_IST rising through ``level`` in its unit: time 0 lies between the last sample below the
    level and the first at or above it, one sample interval apart."""
    m = running.motors[k]
    with m.lock:
        m.write("MODE_REG", 0)
    end = time.monotonic() + 60  # at rest before the step, however loaded the machine
    while abs(float(m.read("V_IST"))) > 0 and time.monotonic() < end:
        time.sleep(0.05)
    time.sleep(0.05)
    unit = m.register("V_IST").unit
    with m.lock:
        m.write("V_SOLL", 12000 if k == 1 else 1600)  # 120 rpm; 100 counts/sample
        m.write("MODE_REG", 1)
    rec = capture.capture(m, ["V_IST"], 200)
    m.write("MODE_REG", 0)
    key = f"V_IST [{unit}]"
    level = level * 100 if k == 1 else level  # MIS V_IST in 0.01 rpm
    out = capture.triggered(rec, Trigger(key, level))
    t, v = out[TIME], out[key]
    i = int(np.searchsorted(t, 0.0))
    assert v[i - 1] < level <= v[i]
    assert t[i - 1] <= 0.0 <= t[i]
    dt = np.diff(rec[TIME])
    assert t[i] - t[i - 1] == pytest.approx(dt[0]) and np.allclose(dt, dt[0])
    with pytest.raises(capture.CaptureError, match="does not cross"):
        capture.triggered(rec, Trigger(key, 1e9))


# ---------------------------------------------------------------------- compile notice
def test_the_compile_notice_names_the_top_level_jvl_gym_compile():
    from types import SimpleNamespace

    from jvl_gym.studio.compiling import CompileWatch

    def event(module: str, name: str) -> SimpleNamespace:
        fn = SimpleNamespace(__module__=module, __qualname__=name)
        return SimpleNamespace(data={"dispatcher": SimpleNamespace(py_func=fn)})

    w = CompileWatch()
    assert w.current() is None
    w.on_start(event("jvl_gym.families.mac800.inner", "inner_samples"))
    w.on_start(event("jvl_gym.physics.trig", "sin"))  # nested: part of the first
    assert "compiling jvl_gym.families.mac800.inner.inner_samples" in w.current()
    w.on_end(None)
    assert "inner_samples" in w.current()
    w.on_end(None)
    assert w.current() is None
    w.on_start(event("numpy.other", "f"))  # not ours: no notice
    assert w.current() is None


def test_the_compile_watch_sees_a_real_numba_compile():
    import numba

    from jvl_gym.studio import compiling

    watch = compiling.install()
    assert compiling.install() is watch  # once per process
    seen = []
    g = numba.njit(cache=False)(lambda x: x * 2)
    g.py_func.__module__ = "jvl_gym.studio.test_probe"
    start = watch.on_start

    def spy(ev):
        start(ev)
        seen.append(watch.current())
    watch.on_start = spy
    try:
        assert g(2) == 4
    finally:
        del watch.on_start
    assert any(s and "compiling jvl_gym.studio.test_probe" in s for s in seen)
    assert compiling.current() is None

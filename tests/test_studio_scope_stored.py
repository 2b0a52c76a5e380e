"""A stored trace overlaid on a captured one (:mod:`jvl_gym.studio.stored`): a capture saved
and loaded back, the recorder's files loaded, alignment at the trigger, cursors on both, bad
files refused with one line; and the chart's layout (the legend outside the plot)."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym.studio import stored
from jvl_gym.studio.trigger import TIME, Recorder, Trigger, cursors, window


def _step(t0: float, dt: float = 0.01, n: int = 200) -> dict[str, np.ndarray]:
    """A ramp from 0 to 10 V starting at ``t0``, with 2 · V on a second channel."""
    t = np.arange(n) * dt
    v = np.clip((t - t0) * 20.0, 0.0, 10.0)
    return {TIME: t, "x [V]": v, "y [rpm]": 2.0 * v}


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_a_saved_capture_loads_back_as_it_was(tmp_path, suffix):
    if suffix == ".parquet":
        pytest.importorskip("pyarrow")
    s = _step(0.5)
    path = stored.save(s, tmp_path / f"cap{suffix}")
    back = stored.load(path)
    assert list(back) == list(s)
    for k in s:
        np.testing.assert_allclose(back[k], s[k], rtol=1e-8)


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_a_recording_loads_as_a_stored_trace(tmp_path, suffix):
    if suffix == ".parquet":
        pytest.importorskip("pyarrow")
    rec = Recorder(tmp_path / f"r{suffix}", ["x [V]"])
    for k in range(50):
        rec.add(3.0 + 0.02 * k, [float(k)])
    back = stored.load(rec.stop())
    assert list(back) == [TIME, "x [V]"]
    assert back[TIME][0] == pytest.approx(3.0) and back["x [V]"][-1] == 49.0


def test_the_overlay_is_aligned_at_the_trigger_as_the_capture_is():
    """The live window and the stored trace both have time 0 where their own trace crosses
    the level on the edge: a step stored 0.3 s later in its record lies on the live one."""
    live = _step(0.4)
    old = _step(0.7)
    trig = Trigger("x [V]", 5.0, pre=0.25)
    shown = window(live, trig, span=1.0)
    over, how = stored.aligned(old, trig)
    assert how == "aligned at the trigger"
    # both cross 5 V at time 0, and agree sample for sample around it
    assert np.interp(0.0, over[TIME], over["x [V]"]) == pytest.approx(5.0)
    for t in (-0.2, -0.1, 0.1, 0.2):
        assert np.interp(t, over[TIME], over["x [V]"]) == pytest.approx(
            np.interp(t, shown[TIME], shown["x [V]"]))
    # the cursors read both traces at the same times
    a, b = cursors(shown, "y [rpm]", 0.0, 0.1), cursors(over, "y [rpm]", 0.0, 0.1)
    assert (a.v1, a.v2) == pytest.approx((10.0, 14.0))
    assert (b.v1, b.v2) == pytest.approx((10.0, 14.0))
    # no trigger, or a trigger on a channel not stored: the times as stored
    same, how = stored.aligned(old, None)
    assert np.array_equal(same[TIME], old[TIME]) and "trigger is off" in how
    same, how = stored.aligned(old, Trigger("z [A]", 1.0))
    assert np.array_equal(same[TIME], old[TIME]) and "no z [A] stored" in how
    with pytest.raises(stored.StoredTraceError, match="does not cross 50"):
        stored.aligned(old, Trigger("x [V]", 50.0))


BAD = {
    "empty.csv": ("", "empty"),
    "notime.csv": ("a,b\n1,2\n3,4\n", "no 't [s]' column"),
    "onlytime.csv": ("t [s]\n0\n1\n", "no channel"),
    "short.csv": ("t [s],x\n0,1\n", "1 rows"),
    "ragged.csv": ("t [s],x\n0,1\n1\n", "line 3: 1 values for 2 columns"),
    "text.csv": ("t [s],x\n0,1\n1,high\n", "column 'x' holds a value that is not a number"),
    "back.csv": ("t [s],x\n1,1\n0,2\n", "do not increase"),
    "twice.csv": ("t [s],x,x\n0,1,1\n1,2,2\n", "column 'x' more than once"),
    "noname.csv": ("t [s],\n0,1\n1,2\n", "a column without a name"),
    "trace.txt": ("t [s],x\n0,1\n1,2\n", "a .csv or .parquet file"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_a_malformed_file_is_one_line_and_loads_nothing(tmp_path, name):
    text, reason = BAD[name]
    (tmp_path / name).write_text(text, encoding="utf-8")
    with pytest.raises(stored.StoredTraceError) as err:
        stored.load(tmp_path / name)
    assert reason in str(err.value) and "\n" not in str(err.value)


def test_missing_binary_and_unsaveable_files(tmp_path):
    with pytest.raises(stored.StoredTraceError, match="no such file"):
        stored.load(tmp_path / "nothing.csv")
    (tmp_path / "bin.csv").write_bytes(b"\xff\xfe\x00\x01")
    with pytest.raises(stored.StoredTraceError, match="not a text CSV"):
        stored.load(tmp_path / "bin.csv")
    if pytest.importorskip("pyarrow"):
        (tmp_path / "bad.parquet").write_text("not parquet")
        with pytest.raises(stored.StoredTraceError, match="not a Parquet file") as err:
            stored.load(tmp_path / "bad.parquet")
        assert "\n" not in str(err.value)
    with pytest.raises(stored.StoredTraceError, match="nothing captured"):
        stored.save({TIME: np.zeros(0)}, tmp_path / "x.csv")
    with pytest.raises(stored.StoredTraceError, match="this record counts 'sample'"):
        stored.save({"sample": np.arange(3.0), "x": np.ones(3)}, tmp_path / "x.csv")
    with pytest.raises(stored.StoredTraceError, match=r"\.csv or \.parquet"):
        stored.save(_step(0.1), tmp_path / "x.json")
    assert not (tmp_path / "x.csv").exists() and not (tmp_path / "x.json").exists()


def test_the_chart_draws_the_overlay_with_its_own_legend_entry_outside_the_plot():
    pytest.importorskip("nicegui")
    from jvl_gym.studio.ui import scope_page as sp

    live, old = _step(0.4), _step(0.7)
    opts = sp.chart_options(live, "", {"x [V]": (2.0, 1.0)}, None, None, old, "run1")
    names = [s["name"] for s in opts["series"]]
    assert names == ["x [V] ×2+1", "y [rpm]", "x [V] · run1 ×2+1", "y [rpm] · run1"]
    over = opts["series"][2]
    assert over["lineStyle"]["type"] == "dashed"
    # its own times and the live channel's scale and offset
    assert over["data"][-1] == [pytest.approx(old[TIME][-1]), pytest.approx(21.0)]
    # the legend has a line of its own below the zoom slider, which is below the plot
    legend, slider, grid = opts["legend"], opts["dataZoom"][1], opts["grid"]
    assert legend["bottom"] + legend["height"] <= slider["bottom"]
    assert slider["bottom"] + slider["height"] + 36 <= grid["bottom"]  # x labels and name


def test_the_studio_page_points_at_the_studio_benchmark_section():
    """docs/studio.md's link to the figures of ``benchmarks/bench_studio.py`` resolves: the
    generated page has that section, with its figures."""
    import re
    from pathlib import Path

    docs = Path(__file__).resolve().parents[1] / "docs"
    links = re.findall(r"\]\(benchmarks\.md#([\w-]+)\)", (docs / "studio.md").read_text())
    assert links == ["studio"]
    page = (docs / "benchmarks.md").read_text()
    section = page.split("<!-- bench:studio begin -->")[1].split("<!-- bench:studio end -->")[0]
    assert re.search(r"^## studio$", section, re.M | re.I)
    assert "scope frames/s drawn with new data in headless Chromium, 8 channels" in section
    assert "trigger latency" in section

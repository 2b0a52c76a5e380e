"""Plots: the demo scope's phases on their own axis and a readable current panel, the
Bode plot's crossover, bandwidth and margin markers, unsettled motors of the fleet plot, the
step plot's legend, GearSync's tension panel."""

from __future__ import annotations

import numpy as np
import pytest


def test_demo_scope_names_phases_on_a_top_axis_and_plots_the_current_magnitude():
    from jvl_gym.cli.demo import _figure

    t = np.arange(300) * 1.92e-3
    log = {"t": t.tolist(), "rpm": np.sin(t).tolist(), "profile_rpm": np.sin(t).tolist(),
           "p_ist": t.tolist(), "vf_out": t.tolist(), "i_a": np.sin(900 * t).tolist(),
           "i_abs": np.ones(300).tolist(),
           "phase": ["TESTU"] * 3 + ["TESTA"] * 97 + ["P_MODE"] * 100 + ["V_MODE"] * 100}
    fig = _figure(log)
    ax = fig.axes
    assert not ax[0].texts  # no labels inside the speed panel (frame, legend)
    top = [a for a in fig.axes if a not in ax[:4]] or [c for c in ax[0].child_axes]
    names = [tick.get_text() for a in top for tick in a.get_xticklabels()]
    assert names == ["TESTU", "TESTA", "P_MODE", "V_MODE"]
    assert "|i|" in ax[3].get_ylabel()
    np.testing.assert_array_equal(ax[3].lines[0].get_ydata(), log["i_abs"])


@pytest.fixture(scope="module")
def design():
    from tuning.autotune import synthesize
    from tuning.models import MotorData

    md = MotorData.from_config("MAC140")
    return md, synthesize(md, 5e-5, 0.0)


def test_bode_marks_crossover_and_margins(design):
    from tuning.pipeline import Candidate
    from tuning.report import bode_figure
    from tuning.strategy import strategy_of

    md, d = design
    fig = bode_figure(strategy_of("MAC140").open_loops(Candidate("pi", d.registers), md, 5e-5))
    texts = [t.get_text() for a in fig.axes for t in a.texts]
    labels = [ln.get_label() for a in fig.axes for ln in a.get_lines()]
    assert sum(t.startswith("PM ") for t in texts) == 2
    assert sum(t.startswith("GM ") for t in texts) >= 1
    assert sum(label.startswith("open-loop gain crossover") for label in labels) == 4
    assert sum(label.startswith("closed-loop BW") and "report's BW" in label
               for label in labels) == 2


def test_step_plot_legend_has_no_register_units(design):
    from tuning.pipeline import Candidate
    from tuning.report import steps_figure
    from tuning.strategy import strategy_of

    md, d = design
    cl = strategy_of("MAC140").step_loop(Candidate("pi", d.registers), md, 5e-5)
    fig = steps_figure(cl, np.full((50, 1), 1600.0), 1600)
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert not any("1/16" in t for t in legend)
    assert "commanded" in fig.axes[0].get_ylabel()


def test_scope_puts_a_reference_in_the_panel_of_its_quantity():
    from jvl_gym.envs.gear_sync import GearSyncVectorEnv
    from jvl_gym.envs.scope import draw_scope, panels

    groups = panels(GearSyncVectorEnv.scope_channels)
    assert groups[0] == ("tension [N]", [0, 1])
    figures: dict = {}
    image = draw_scope(figures, 0, np.zeros((4, 10)), GearSyncVectorEnv.scope_channels, 0.01)
    assert image.ndim == 3 and len(figures[0].axes) == 3


def test_fleet_plot_draws_unsettled_motors_as_unsettled(tmp_path, monkeypatch):
    import matplotlib.figure
    from tuning.fleet_report import plot_fleet

    figures = []
    save = matplotlib.figure.Figure.savefig
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig",
                        lambda self, *a, **k: (figures.append(self), save(self, *a, **k)))
    rows = [{"settle_default_s": 0.2, "settle_tuned_s": 0.1, "credible": True},
            {"settle_default_s": float("inf"), "settle_tuned_s": 0.15, "credible": True}]
    plot_fleet(rows, tmp_path / "fleet.png")
    ax = figures[0].axes[-1]
    marked = {c.get_label(): c.get_offsets().tolist() for c in ax.collections}
    assert marked["settled"] == [[200.0, 100.0]]
    (x, y), = marked["did not settle (drawn on the dotted edge)"]
    assert x > 200.0 and y == 150.0

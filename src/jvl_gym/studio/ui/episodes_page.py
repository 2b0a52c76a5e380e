"""The Episodes view: one episode of a registered env with its shipped policy or its
baseline on a seed, its signals and rewards."""

from __future__ import annotations

from typing import Any

import numpy as np
from nicegui import run, ui

from ...envs import ENV_IDS
from ..episodes import controllers, run_episode
from .common import frame, tid
from .scope_page import chart_options


def build(session: Any, m: int) -> None:
    """The Episodes page."""
    page = frame(session, "/episodes", m)
    with ui.row().classes("items-center gap-4"):
        env = ui.select(list(ENV_IDS), value=ENV_IDS[0], label="env").props(
            tid("episode-env")).classes("w-72")
        ctl = ui.select(controllers(ENV_IDS[0]), value="baseline", label="controller").props(
            tid("episode-controller")).classes("w-40")
        env.on_value_change(lambda e: ctl.set_options(controllers(e.value), value="baseline"))
        seed = ui.number("seed", value=0, min=0, precision=0).props(tid("episode-seed"))
        button = ui.button("run episode").props(tid("episode-run"))
        total = ui.label("").props(tid("episode-total"))
    signals = ui.echart(chart_options({"step": []})).classes("w-full h-96")
    rewards = ui.echart(chart_options({"step": []})).classes("w-full h-64")

    async def go() -> None:
        page.say(f"running {env.value} with its {ctl.value} on seed {int(seed.value or 0)} …")
        ep = await run.io_bound(run_episode, env.value, ctl.value, int(seed.value or 0))
        steps = np.arange(len(ep.signals["reward"]), dtype=float)
        sig = {"step": steps, **{k: v for k, v in ep.signals.items() if k != "reward"}}
        rew = {"step": steps, "reward": ep.signals["reward"],
               "return so far": np.cumsum(ep.signals["reward"])}
        for chart, series, title in ((signals, sig, "signals"), (rewards, rew, "rewards")):
            chart.options.clear()
            chart.options.update(chart_options(series, f"{ep.env_id} · {ep.controller} · "
                                               f"seed {ep.seed}: {title}"))
            chart.update()
        total.set_text(f"return {ep.total:.4g} over {len(steps)} steps")
        page.say(f"{ep.env_id}: return {ep.total:.4g} ({ep.controller}, seed {ep.seed})")

    button.on_click(page.guard(go))

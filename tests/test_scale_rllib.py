"""RLlib PPO on the native GearSync vector env (local Ray, one remote env runner)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

ray = pytest.importorskip("ray")
pytest.importorskip("ray.rllib")

from jvl_gym.scale.rllib import train_ppo  # noqa: E402


# any gymnasium warning (observation dtype or bounds, a space's precision) fails the test
@pytest.mark.filterwarnings("error::UserWarning:gymnasium")
def test_ppo_two_iterations_on_gearsync(tmp_path: Path, local_ray: None) -> None:
    rows = train_ppo("jvl_gym/GearSync-v0", iterations=2, out=tmp_path, progress=lambda _: None,
                     num_env_runners=1, num_envs_per_runner=4, train_batch_size=512,
                     minibatch_size=128, num_epochs=2)
    assert [r["iteration"] for r in rows] == [1, 2]
    assert rows[0]["env_steps"] >= 512 and rows[1]["env_steps"] >= rows[0]["env_steps"] + 512
    # random GearSync policies break the web within a few hundred steps: episodes end
    assert math.isfinite(rows[1]["episode_return_mean"])
    assert list((tmp_path / "ppo").glob("*/checkpoint_*"))

"""The one way to write a task (``jvl_gym.envs.task``): the families an env runs on follow from
the capabilities its task needs, refusals carry the contract's reason, and the task's state is
named on both sides of the compiled step."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import jvl_gym  # noqa: F401
from jvl_gym.envs import ENV_IDS
from jvl_gym.envs.registration import vector_class
from jvl_gym.envs.task import Task, record
from jvl_gym.families import Capability, UnsupportedOperation, families, family, register_family

FIXTURES = Path(__file__).resolve().parent / "fixtures"


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_an_env_runs_on_exactly_the_families_that_declare_what_its_task_needs(env_id) -> None:
    cls = vector_class(env_id)
    assert cls.task.needs, "every registered task names the capabilities it needs"
    for key in families():
        runs = family(key).capabilities >= cls.task.needs
        assert (key in cls.supported_families()) == runs
        if runs:
            assert cls.task.refusal(key) is None
        else:
            assert isinstance(cls.task.refusal(key), UnsupportedOperation)


@pytest.mark.parametrize(("env_id", "motor_type", "capability"),
                         [("jvl_gym/Positioning-v0", "MIS232", Capability.ANALOG_TORQUE),
                          ("jvl_gym/GearSync-v0", "MIS232", Capability.ANALOG_GEAR),
                          ("jvl_gym/FilterTuning-v0", "MIS232", Capability.SPEED_FILTER),
                          ("jvl_gym/CoilWinding-v0", "MAC800", Capability.COIL_MODE),
                          ("jvl_gym/StepperIndexing-v0", "MAC140", Capability.STEP_INDEXING)])
def test_a_refused_family_gets_the_contracts_reason(env_id, motor_type, capability) -> None:
    fam = next(family(k) for k in families() if motor_type in family(k).motor_types())
    reason = str(UnsupportedOperation(fam.title, capability))
    with pytest.raises(ValueError) as caught:
        gym.make(env_id, motor_type=motor_type)
    assert reason in str(caught.value) and repr(motor_type) in str(caught.value)


def test_a_task_names_only_known_hooks() -> None:
    with pytest.raises(TypeError, match="unknown hooks.*'step'"):
        Task("bad", __file__, step=lambda: None)


def test_a_record_names_its_fields_in_order() -> None:
    dtype = record(target=np.int64, direction=float)
    assert dtype.names == ("target", "direction")
    assert dtype["target"] == np.int64 and dtype["direction"] == np.float64


def test_the_env_reads_and_writes_the_state_the_compiled_step_sees() -> None:
    from jvl_gym.envs.positioning import PositioningVectorEnv

    venv = PositioningVectorEnv(num_envs=2, randomization={"target_turns": (1.0, 1.0)})
    venv.reset(seed=0)
    np.testing.assert_array_equal(venv.target, venv.state.copies["target"])
    assert venv.target.tolist() == [4096, 4096]
    obs_far, *_ = venv.step(np.zeros((2, 1)))
    venv.reset(seed=0)
    venv.target[1] = 0  # the second copy's target is where it stands
    obs, *_ = venv.step(np.zeros((2, 1)))
    assert obs[0, 0] == obs_far[0, 0] and abs(obs[1, 0]) < abs(obs_far[1, 0])


def test_a_fixture_task_that_needs_more_than_its_family_has_is_refused() -> None:
    sys.path.insert(0, str(FIXTURES))
    try:
        register_family("toy", "toy_family")
        speed_env = importlib.import_module("toy_family.speed_env")

        class NeedsTorque(speed_env.ToySpeedVectorEnv):
            task = Task("needs_torque", __file__, needs={Capability.TORQUE},
                        state=speed_env.ToySpeedState)

        assert "toy" in speed_env.ToySpeedVectorEnv.supported_families()
        assert "toy" not in NeedsTorque.supported_families()
        with pytest.raises(ValueError, match=r"NeedsTorque.*'TOY1'.*toy.*torque observable"):
            NeedsTorque(num_envs=1)
    finally:
        sys.path.remove(str(FIXTURES))

"""SHA-256 of every family's registers and state after a few hundred steps (a check, not a
benchmark): ``python benchmarks/kernel_hash.py`` prints one line per case; two source trees
whose compiled code computes the same print the same lines. Arguments: family keys (default:
every family).

Cases per family: a mixed array of 40 motors (every motor type of the family in turn, so the
threaded driver and partly filled blocks run; each motor in another mode, where the family
accepts it, with a velocity and position target and the recording bits of some motors set),
and one single motor of each of the first two types in the same setting as motor 0.

Env cases per family (the first motor type of the family): every env with a compiled step
(:data:`ENV_IDS`; "refused" where the task does not run on the family), as a vector env of 40
copies (threaded, partly filled blocks, autoreset) and as a single env (reset when its episode
ends), stepped with seeded random actions; the digest covers observations, rewards, episode
ends and the motors' registers and state.
"""

from __future__ import annotations

import hashlib
import sys

import gymnasium as gym
import numpy as np

from jvl_gym import MotorArray
from jvl_gym.families import families, family

STEPS = 300
#: the envs whose step is compiled (FilterTuning's step is a commissioning trial in numpy)
ENV_IDS = ("jvl_gym/Positioning-v0", "jvl_gym/GearSync-v0", "jvl_gym/CoilWinding-v0",
           "jvl_gym/StepperIndexing-v0")
ENV_STEPS = 60
TRIES = {"V_SOLL": 800, "P_SOLL": 20000, "A_SOLL": 500, "T_SOLL": 300}


def _try(m: MotorArray, key: str, value: float, index: int) -> None:
    try:
        m.write(key, value, index=index)
    except Exception:  # noqa: BLE001  (a register or value the family does not have or take)
        pass


def _setting(m: MotorArray, offset: int) -> None:
    modes = [int(v) for v in range(0, 20)]
    for i in range(m.n):
        for key, value in TRIES.items():
            _try(m, key, value * (1 + (i + offset) % 3), i)
        _try(m, m.MODE_REGISTER, modes[(i + offset) % len(modes)], i)
        if (i + offset) % 4 == 1:
            _try(m, "CNTRL_BITS", 0xFFFF & ~0x1, i)


def _digest(m: MotorArray) -> str:
    h = hashlib.sha256()
    for a in (m.regs, m.state):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:16]


def _env_digest(env_id: str, motor_type: str, copies: int) -> str:
    """Digest of ``ENV_STEPS`` steps of ``env_id`` on ``motor_type`` (``copies`` = 0: the single
    env), or the name of the error the env's constructor raised (a task that does not run on
    the family)."""
    try:
        if copies:
            env = gym.make_vec(env_id, num_envs=copies, vectorization_mode="vector_entry_point",
                               motor_type=motor_type)
        else:
            env = gym.make(env_id, motor_type=motor_type).unwrapped
    except Exception as exc:  # noqa: BLE001  (printed: the two trees' lines show it)
        return f"refused ({type(exc).__name__})"
    shape = env.action_space.shape
    acts = np.random.default_rng(7).uniform(-1.2, 1.2, (ENV_STEPS, *shape))
    h = hashlib.sha256()
    obs, _ = env.reset(seed=3)
    h.update(np.asarray(obs).tobytes())
    for a in acts:
        obs, reward, term, trunc, _ = env.step(a)
        for x in (obs, reward, term, trunc):
            h.update(np.asarray(x).tobytes())
        if not copies and (term or trunc):
            obs, _ = env.reset()
            h.update(np.asarray(obs).tobytes())
    for a in (env.motors.regs, env.motors.state):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:16]


def env_cases(key: str) -> None:
    """Print the env digests of family ``key``."""
    motor_type = family(key).motor_types()[0]
    for env_id in ENV_IDS:
        for copies in (40, 0):
            what = f"x{copies}" if copies else "single"
            print(f"{key} {env_id} {motor_type} {what}: {_env_digest(env_id, motor_type, copies)}",
                  flush=True)


def main() -> None:
    for key in sys.argv[1:] or families():
        types = family(key).motor_types()
        mixed = [types[i % len(types)] for i in range(40)]
        m = MotorArray(mixed, n=40, seed=1)
        _setting(m, 0)
        for _ in range(STEPS // 50):
            m.step(50)
        print(f"{key} mixed x40: {_digest(m)}", flush=True)
        for t in types[:2]:
            one = MotorArray(t, n=1, seed=1)
            _setting(one, 0)
            for _ in range(STEPS // 50):
                one.step(50)
            print(f"{key} {t} x1: {_digest(one)}", flush=True)
        env_cases(key)


if __name__ == "__main__":
    main()

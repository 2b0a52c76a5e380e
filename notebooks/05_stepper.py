# ---
# jupyter:
#   jupytext:
#     formats: ipynb,py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # 05 · An MIS step motor: profiles, pull-out torque, lost steps, an indexing task
#
# `MotorArray("MIS232")` simulates JVL's MIS integrated step motors register for register, as
# the MIS/SMC user manual describes them (§8.2: 32-bit registers at one number each; positions
# in 1/409 600 rev, velocities in 0.01 RPM, accelerations in RPM/s). This notebook:
#
# 1. runs the manual's V_START example of a velocity profile,
# 2. draws the motor's pull-out torque curve and shows steps lost beyond it,
# 3. runs the `jvl_gym/StepperIndexing-v0` environment with the firmware's default profile and
#    with the shipped trained policy.
#
# Set `JVL_FAST=1` to run everything with short durations (used by the test suite).

# %%
import os

import gymnasium as gym
import matplotlib.pyplot as plt
import numpy as np

import jvl_gym  # noqa: F401  (registers the env ids)
from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c

FAST = os.environ.get("JVL_FAST") == "1"

# %% [markdown]
# ## The profile rules (MIS manual §8.2.12)
# V_START is where a move starts and stops: with V_START = 100 RPM and V_SOLL = 200 RPM the
# motor jumps to 100 RPM and ramps from there with A_SOLL; V_SOLL = 50 RPM then decelerates to
# 100 RPM and stays there (below V_START there is no ramp to run).

# %%
m = MotorArray("MIS232", seed=0)
m.write_many({"V_START": 10000, "A_SOLL": 2000, "V_SOLL": 20000})
m.write("MODE_REG", c.VELOCITY)
speed = []
for v_soll in (20000, 5000):
    m.write("V_SOLL", v_soll)
    for _ in range(150):
        m.step(1)
        speed.append(m.read("V_IST")[0] * c.VELOCITY_RPM_PER_UNIT)
t = np.arange(len(speed)) * 1e-3
plt.figure(figsize=(6, 2.5))
plt.plot(t, speed)
plt.xlabel("time [s]")
plt.ylabel("V_IST [RPM]")
plt.title("V_START 100 RPM: V_SOLL 200 RPM, then 50 RPM")
plt.tight_layout()
print("first sample:", speed[0], "RPM; last:", speed[-1], "RPM")

# %% [markdown]
# ## Pull-out torque and lost steps
# The chopper holds the phase current up to the speed where the back-EMF eats the supply
# voltage; above it the torque the field can hold falls. A load above the pull-out torque at
# the commanded speed makes the rotor slip poles: P_IST (the commanded steps) keeps counting,
# the encoder sees the rotor fall behind, FLWERR grows.

# %%
rpm = np.linspace(50, 3000, 30)
curve = np.array([m.pull_out_torque(float(r))[0] for r in rpm])
plt.figure(figsize=(6, 2.5))
plt.plot(rpm, curve)
plt.xlabel("speed [RPM]")
plt.ylabel("pull-out torque [N·m]")
plt.tight_layout()

seconds = 0.5 if FAST else 2.0
for factor in (0.8, 1.2):
    s = MotorArray("MIS232", seed=0)
    s.set_input(load_torque=factor * s.pull_out_torque(600.0)[0])
    s.write_many({"V_SOLL": 60000, "A_SOLL": 5000})
    s.write("MODE_REG", c.VELOCITY)
    s.step(int(seconds * c.OUTER_HZ))
    print(f"load {factor:.1f} × pull-out at 600 RPM: lost {abs(int(s.lost_steps[0]))} full "
          f"steps, FLWERR {int(s.read('FLWERR')[0])} counts")

# %% [markdown]
# ## StepperIndexing-v0
# Three indexing moves against a random load. The agent sets V_SOLL, A_SOLL and RUN_CURRENT
# every 2 ms; the baseline keeps the firmware's default registers (100 RPM, 1000 RPM/s, half
# current), which is slow and loses steps when the load is above what half current holds.

# %%
def rollout(policy, baseline: bool, seed: int, n: int) -> tuple[np.ndarray, list[str]]:
    """Returns and end reasons of the first episode of ``n`` copies (later ones are ignored)."""
    env = gym.make_vec("jvl_gym/StepperIndexing-v0", num_envs=n,
                       vectorization_mode="vector_entry_point", baseline=baseline)
    obs, _ = env.reset(seed=seed)
    returns, alive, reasons = np.zeros(n), np.ones(n, dtype=bool), [""] * n
    while alive.any():
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        returns += np.where(alive, reward, 0.0)
        ended = alive & (terminated | truncated)
        for i in np.flatnonzero(ended):
            reasons[i] = info["termination_reason"][i]
        alive &= ~ended
    env.close()
    return returns, reasons


n = 8 if FAST else 32
zero = lambda obs: np.zeros((obs.shape[0], 3), dtype=np.float32)  # noqa: E731
base_returns, base_reasons = rollout(zero, True, 100000, n)
print("baseline: mean return %.2f, %d of %d lost steps" % (
    base_returns.mean(), sum("lost" in r for r in base_reasons), n))
try:
    from stable_baselines3 import PPO

    from jvl_gym.rl.train import shipped_model

    model = PPO.load(str(shipped_model("jvl_gym/StepperIndexing-v0")), device="cpu")
    trained = lambda obs: model.predict(obs, deterministic=True)[0]  # noqa: E731
    returns, reasons = rollout(trained, False, 100000, n)
    print("policy:   mean return %.2f, %d of %d lost steps" % (
        returns.mean(), sum("lost" in r for r in reasons), n))
except ImportError:
    print("the trained policy needs the RL extra (make setup-rl)")

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
# # 04 · Coil winding: COIL_MODE and the winding task
#
# COIL_MODE (manual 4.4.20) drives a traverse that lays wire on a spool turned by a spindle. The
# spindle's encoder feeds the pulse input; the traverse follows it like the gear mode (gear factor
# GEARF1/GEARF2 = feed per spindle revolution) and reverses at the *thread positions* P1 and P4.
# The *stop positions* P2 and P3 make the traverse dwell while a turn is laid on the previous one.
# The manual draws two figures; here both are re-drawn from the simulator, with the manual's
# example set-up P1 = 10000, P2 = 12000, P3 = 58000, P4 = 60000, P5 = 12000, P6 = 1.

# %%
import os


import matplotlib.pyplot as plt
import numpy as np

from jvl_gym import MotorArray
from jvl_gym.families.mac050_141 import constants as c

FAST = os.environ.get("JVL_FAST") == "1"
SPINDLE_COUNTS = 20  # spindle encoder counts per outer sample (the pulse input)
SAMPLES = 1400 if FAST else 3200

# %% [markdown]
# Two traverses: figure A without dwell (P2 = P1, P3 = P4) and figure B with the example stop
# positions. The analogue input high first moves both to the start position P5; when it goes
# low they wind in direction P6.

# %%
setups = {
    "A": dict(P1=10000, P2=10000, P3=60000, P4=60000, P5=12000, P6=1),
    "B": dict(P1=10000, P2=12000, P3=58000, P4=60000, P5=12000, P6=1),
}
m = MotorArray("MAC140", n=2, seed=0, load_inertia=10e-6)
m.write("KVOUT", 27.3 / 17.3)
for i, regs in enumerate(setups.values()):
    for name, value in regs.items():
        m.write(name, value, index=[i])
m.write("V_SOLL", 20000)
m.write("A_SOLL", 400)
m.write("GEARF1", 4)  # 4 traverse counts per spindle count
m.write("GEARF2", 1)
m.set_input(analog_volts=10.0)  # start-position command
m.write("MODE_REG", c.COIL_MODE)
m.run(1.0)
print("at the start position:", m.read("P_IST"))

m.set_input(analog_volts=0.0, pulse_counts=SPINDLE_COUNTS)
master, traverse = [], []
for k in range(SAMPLES):
    m.step()
    master.append((k + 1) * SPINDLE_COUNTS)
    traverse.append(m.read("P_IST").copy())
traverse = np.asarray(traverse)

# %%
fig, ax = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
for i, (name, regs) in enumerate(setups.items()):
    ax[i].plot(master, traverse[:, i], lw=1)
    for key in ("P1", "P2", "P3", "P4"):
        ax[i].axhline(regs[key], color="grey", lw=0.6, ls="--")
        ax[i].text(master[-1], regs[key], key, fontsize=8, va="bottom", ha="right")
    ax[i].set_title(f"figure 4.4.20.{name}")
    ax[i].set_xlabel("master (spindle) position [counts]")
ax[0].set_ylabel("MAC position P_IST [counts]")
fig.tight_layout()
plt.show()

# %% [markdown]
# In B the traverse stops at P3 while the (virtual) gear position runs on to P4 and back: the
# dwell lasts 2·(P4 − P3) / (GEARF1/GEARF2 · spindle counts per sample) samples. The finite
# acceleration (A_SOLL) and the speed loop round the corners; at high spindle speed this is
# where turns bunch up against the flanges. Pressing "start" (analogue input high) returns the
# traverse to P5:

# %%
m.set_input(analog_volts=10.0)
m.run(2.0 if not FAST else 1.5)
print("back at P5:", m.read("P_IST"), "mode:", m.mode_name(0))

# %% [markdown]
# The COIL rules P1 ≤ P2 ≤ P3 ≤ P4, P1 ≤ P5 ≤ P4, P6 = ±1 are enforced:

# %%
try:
    m.write("P3", 70000, index=[1])
except Exception as exc:  # noqa: BLE001 - shown on purpose
    print(type(exc).__name__, ":", exc)

# %% [markdown]
# ## The RL task: `jvl_gym/CoilWinding-v0`
# The environment puts this traverse on a real winding problem: the wire is thicker or thinner
# than nominal and varies slowly, the spindle runs up, changes speed and wanders, and every
# spindle revolution lays one turn on a height profile of the coil. The agent trims the pitch
# (gear factor) and the stop positions P2/P3 while winding; the reward penalises gaps and
# uneven layers, especially pile-ups at the flanges. The baseline is the firmware COIL_MODE
# with the nominal registers computed from the nominal wire diameter (zero action).

# %%
import gymnasium as gym  # noqa: E402

import jvl_gym  # noqa: E402,F401

env = gym.make("jvl_gym/CoilWinding-v0", render_mode="rgb_array")
obs, info = env.reset(seed=11)
ret, steps, done = 0.0, 0, False
while not done and steps < (150 if FAST else 1200):
    obs, reward, terminated, truncated, info = env.step(np.zeros(env.action_space.shape))
    ret += float(reward)
    steps += 1
    done = terminated or truncated
print(f"firmware COIL_MODE, nominal registers: return {ret:.2f} after {steps} steps")
plt.figure(figsize=(9, 5))
plt.imshow(env.render())
plt.axis("off")
plt.show()
env.close()

# %% [markdown]
# Training and the policy-versus-baseline table: `jvl-gym train jvl_gym/CoilWinding-v0` and
# `jvl-gym evaluate jvl_gym/CoilWinding-v0` (budget and results in docs/envs.md).

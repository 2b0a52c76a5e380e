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
# # 01 · Quickstart: a MAC140 in the simulator
#
# `jvl_gym.MotorArray` simulates N JVL MAC motors register for register: you talk to it exactly
# as to the real motor, by register name (or number) from the technical manual, chapter 3.
# This notebook:
#
# 1. creates an array of MAC140s and reads/writes registers by name,
# 2. runs a velocity move (V_MODE) and a position move (P_MODE),
# 3. draws a scope plot from the simulation,
# 4. overloads a motor until FNC_ERR trips, and recovers.
#
# Set `JVL_FAST=1` to run everything with short durations (used by the test suite).

# %%
import os


import matplotlib.pyplot as plt
import numpy as np

from jvl_gym import MotorArray
from jvl_gym.families.mac050_141 import constants as c

FAST = os.environ.get("JVL_FAST") == "1"
SECONDS = 0.4 if FAST else 1.5

# %% [markdown]
# ## Registers by name
# Four MAC140s, each with a different load inertia. KVOUT (manual 3.2.13) tells the speed loop
# the inertia ratio `(J_m + J_l)/J_m`; the manual's own example is 3.9 for a 50e-6 kg·m² load.

# %%
loads = np.array([0.0, 17.3e-6, 50e-6, 100e-6])
m = MotorArray("MAC140", n=4, seed=0, load_inertia=loads)
kvout = (17.3e-6 + loads) / 17.3e-6
m.write("KVOUT", kvout)
print("KVOUT  =", m.read("KVOUT"))
print("V_SOLL = register", m.table.lookup("V_SOLL").number, m.table.lookup("V_SOLL").unit)
print("mode   =", [m.mode_name(i) for i in range(m.n)])

# %% [markdown]
# Bad writes raise a clear error naming the register, its range and the manual section, and
# change nothing:

# %%
for key, value in (("T_SOLL", 5000), ("V_IST", 3), ("NO_SUCH_REGISTER", 1)):
    try:
        m.write(key, value)
    except Exception as exc:  # noqa: BLE001 - shown on purpose
        print(type(exc).__name__, ":", exc)

# %% [markdown]
# ## A velocity move and a position move
# V_SOLL = 1600 is 762.9 rpm (manual 3.2.5). We record what a scope would show.

# %%
def scope(m, seconds, log=None):
    log = log if log is not None else {k: [] for k in ("t", "rpm", "profile", "vf", "pos")}
    for _ in range(int(seconds * c.OUTER_HZ)):
        m.step()
        log["t"].append(m.time[0])
        log["rpm"].append(m.speed_rpm.copy())
        log["profile"].append(c.v_soll_to_rpm(m.read("FNC_OUT")))
        log["vf"].append(m.read("VF_OUT").copy())
        log["pos"].append(m.read("P_IST").copy())
    return log


m.write("A_SOLL", 20)
m.write("V_SOLL", 1600)
m.write("MODE_REG", c.V_MODE)
log = scope(m, SECONDS)
print("speed [rpm]:", np.round(m.speed_rpm, 1))

m.write("P_SOLL", m.read("P_IST") + 20000)
m.write("V_SOLL", 3000)
m.write("MODE_REG", c.P_MODE)  # V → P directly: both are regulated modes
log = scope(m, SECONDS, log)
print("position error [counts]:", m.read("P_SOLL") - m.read("P_IST"))
print("IN_POS:", (m.read("ERR_STAT") & c.IN_POS) > 0)

# %%
fig, ax = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
t = np.asarray(log["t"])
for i in range(m.n):
    ax[0].plot(t, np.asarray(log["rpm"])[:, i], lw=1, label=f"KVOUT {kvout[i]:.1f}")
ax[0].plot(t, np.asarray(log["profile"])[:, 0], "k--", lw=1, label="profile")
ax[0].set_ylabel("speed [rpm]")
ax[0].legend(fontsize=7)
ax[1].plot(t, np.asarray(log["vf"]), lw=1)
ax[1].set_ylabel("VF_OUT")
ax[2].plot(t, np.asarray(log["pos"]), lw=1)
ax[2].set_ylabel("P_IST [counts]")
ax[2].set_xlabel("time [s]")
fig.tight_layout()
plt.show()

# %% [markdown]
# ## Overload: FNC_ERR and recovery
# A load the motor cannot accelerate within T_SOLL: the function correction (manual 4.2) holds
# VF_OUT at T_SOLL, FNCERR grows, FNC_ERR trips at FNCERRMAX and the motor goes
# STOP_MODE → INIT_MODE. The error bit must be cleared before leaving INIT (manual 4.4.1).

# %%
m = MotorArray("MAC140", n=1, seed=0, load_inertia=400e-6)
m.write("T_SOLL", 300)
m.write("A_SOLL", 400)
m.write("V_SOLL", 8000)
m.write("FNCERRMAX", 50000)
m.write("P_SOLL", 2_000_000)
m.write("MODE_REG", c.P_MODE)
trace = []
while m.mode_name() != "INIT_MODE" and len(trace) < 5000:
    m.step()
    trace.append((m.read("VF_OUT")[0], m.read("FNCERR")[0], m.mode_name()))
vf, fncerr, modes = zip(*trace)
print("max |VF_OUT| =", max(abs(x) for x in vf), "(T_SOLL = 300)")
print("FNCERR at the trip:", fncerr[-1], " modes seen:", sorted(set(modes)))
print("ERR_STAT FNC_ERR set:", bool(m.read("ERR_STAT")[0] & c.FNC_ERR))

try:
    m.write("MODE_REG", c.P_MODE)
except Exception as exc:  # noqa: BLE001
    print("refused:", exc)

m.write("ERR_STAT", 0)  # clear the error bits
m.write("T_SOLL", 1023)
m.write("A_SOLL", 20)
m.write("P_SOLL", 0)
m.write("MODE_REG", c.P_MODE)
m.run(SECONDS)
print("recovered, mode:", m.mode_name())

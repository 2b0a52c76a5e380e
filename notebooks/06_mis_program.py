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
# # 06 · A stored program on an MIS: pick and place, its trace, and a bug found in it
#
# An MIS step motor runs a program of its own from power-on, with no master (MIS manual
# chapter 9, "eRxP"). jvl_gym writes such a program as text, one line per §9.7 command with the
# fields of its dialogue, stores it in the simulated motor and runs it between the firmware's
# outer samples. Here an MIS232 drives the axis of a pick-and-place station:
#
# - input 1: the start button (a rising edge starts a cycle),
# - input 3: the part sensor, active while the gripper is over the part,
# - output 1: the gripper (high: closed).
#
# The program runs against an I/O script (button presses over time, the sensor at a rotor
# position), we plot its trace, see the gripper open while the axis still moves, and fix it.
#
# Set `JVL_FAST=1` to run with short durations (used by the test suite).

# %%
import os

import matplotlib.pyplot as plt
import numpy as np

from jvl_gym import MotorArray
from jvl_gym.families.mis.program import parse_program, print_program
from jvl_gym.families.mis.program.bench import load_io_script, run_bench

FAST = os.environ.get("JVL_FAST") == "1"
SECONDS = 2.6 if FAST else 4.0
REV = 409600  # motor counts per revolution

# %% [markdown]
# ## The program
# `move_sensor` runs towards the part until input 3 is high, then 8192 counts further (never
# past the safety distance); the gripper closes, the axis returns to 0 and the gripper opens.
# One line is wrong: the return move does not wait until the axis is in position.

# %%
PROGRAM = """\
mode mode=position
remark text="wait for the start button"
wait_input input=1 condition=rising
move_sensor distance=8192 velocity=300 acceleration=3000 safety_distance=819200 input=3 condition=high
set_output output=1 state=high
wait_ms time=100
move_absolute position=0 velocity=600 acceleration=3000 wait=no
set_output output=1 state=low
wait_ms time=100
jump line=3
"""
cmds = parse_program(PROGRAM)
print(print_program(cmds))

# %% [markdown]
# ## The station: an I/O script
# The button is pressed at 0.2 s and at 1.6 s (100 ms each); the part sensor is active while the
# rotor is between 0.73 and 0.78 revolutions from power-on.

# %%
SCRIPT = load_io_script({
    "registers": {"IN_POSITION_COUNT": 0},
    "inputs": [{"t": 0.2, "set": {1: "high"}}, {"t": 0.3, "set": {1: "low"}},
               {"t": 1.6, "set": {1: "high"}}, {"t": 1.7, "set": {1: "low"}}],
    "sensors": [{"input": 3, "from": 0.73 * REV, "to": 0.78 * REV}],
    "load": 0.05,
})


def run(program: str) -> dict[str, np.ndarray]:
    m = MotorArray("MIS232", seed=0)
    m.store_program(program)
    return run_bench(m, SECONDS, SCRIPT)


def plot(trace: dict[str, np.ndarray], title: str) -> None:
    t = trace["t"]
    fig, ax = plt.subplots(4, 1, figsize=(8, 7), sharex=True)
    ax[0].plot(t, trace["P_IST"] / REV)
    ax[0].set_ylabel("P_IST [rev]")
    ax[1].plot(t, trace["V_IST"] / 100)
    ax[1].set_ylabel("V_IST [RPM]")
    inputs, outputs = trace["INPUTS"].astype(int), trace["OUTPUTS"].astype(int)
    ax[2].step(t, inputs & 1, where="post", label="IN1 start")
    ax[2].step(t, (inputs >> 2 & 1) + 1.2, where="post", label="IN3 part sensor")
    ax[2].step(t, (outputs & 1) + 2.4, where="post", label="OUT1 gripper")
    ax[2].set_yticks([])
    ax[2].legend(loc="upper right", fontsize=8)
    ax[3].step(t, trace["line"], where="post")
    ax[3].set_ylabel("program line")
    ax[3].set_xlabel("time [s]")
    fig.suptitle(title)
    fig.tight_layout()
    plt.show()


trace = run(PROGRAM)
plot(trace, "pick and place, first version")

# %% [markdown]
# ## Reading the trace
# The gripper (OUT1) must open only at the place position, with the axis at rest. Where does
# it fall while the axis moves?

# %%
def releases_in_motion(trace: dict[str, np.ndarray]) -> list[tuple[float, float, float]]:
    """(time [s], velocity [RPM], position [rev]) of each opening of the gripper in motion."""
    out = trace["OUTPUTS"].astype(int) & 1
    falls = np.flatnonzero((out[:-1] == 1) & (out[1:] == 0)) + 1
    return [(float(trace["t"][k]), float(trace["V_IST"][k]) / 100, float(trace["P_IST"][k]) / REV)
            for k in falls if trace["V_IST"][k] != 0]


bad = releases_in_motion(trace)
for t_open, v, p in bad:
    print(f"gripper opened at {t_open:.3f} s at {v:.0f} RPM, {p:.3f} rev from the place position")
assert bad, "the first version drops the part on the way"

# %% [markdown]
# The program line in the trace says why: line 7 (`move_absolute … wait=no`) starts the
# return move and goes on at once (§9.7.7: "If this option is not checked, the program will
# start the movement, then immediately start executing the next command"), so line 8 opens the
# gripper a fraction of a millisecond later. The fix: wait for in-position.

# %%
FIXED = PROGRAM.replace("acceleration=3000 wait=no", "acceleration=3000 wait=yes")
fixed = run(FIXED)
plot(fixed, "pick and place, fixed")
assert not releases_in_motion(fixed)
opened = np.flatnonzero(np.diff(fixed["OUTPUTS"].astype(int) & 1) == -1) + 1
print("gripper opens at", [f"{fixed['t'][k]:.3f} s, P_IST = {int(fixed['P_IST'][k])}"
                           for k in opened])
assert all(fixed["P_IST"][k] == 0 for k in opened)

# %% [markdown]
# The same run from the command line writes the trace as CSV and a plot:
#
# ```sh
# jvl-gym program run configs/programs/pick.txt --motor MIS232 --seconds 4 \
#     --io configs/programs/station.yaml --out program_out
# ```

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
# # 07 · From the simulator to the motor: a policy for the motor that was measured
#
# A MAC140 with a load nobody told us about stands behind a MacTalk link. Here it is a digital
# twin served on a loopback TCP port (`jvl-gym serve` does the same from the shell; pointed at a
# serial port or an Ethernet module the same code reaches a real motor):
#
# 1. identify it over MacTalk with the tuning toolkit (`jvl-tune autotune --port … --write`):
#    J, friction with 95 % intervals, and the tuned register set written to the motor;
# 2. build the env of that motor (`jvl_gym.envs.identified`): its type and setup, the load
#    and friction drawn within the identified intervals, behind the MacTalk-over-TCP link model;
# 3. train a small PPO policy on it (`jvl-gym train jvl_gym/Positioning-v0 --variant link
#    --identified DIR` from the shell);
# 4. deploy the policy to the twin in real time with the project's deployment loop (safety
#    supervisor, watchdog; `jvl-gym deploy … --identified DIR`) and put the deployed trace
#    beside the link model's trace of the same episode.
#
# `JVL_FAST=1` runs a few thousand training steps (the policy is poor, the pipeline is whole);
# without it the link variant's budget (`configs/rl/positioning.yml`) trains the policy the
# last cell compares with the firmware's own positioning behind the link.

# %%
import os
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from jvl_gym import MotorArray
from jvl_gym.envs.identified import env_kwargs_from_identification
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.serving.transport import TwinServer

FAST = os.environ.get("JVL_FAST") == "1"
ENV_ID = "jvl_gym/Positioning-v0"
LINK = "mactalk-tcp:10ms,max_step=0.5"  # the deployment's link: 10 ms periods over TCP
ADDRESS, SEED = 19, 100_000  # the motor's MacTalk address; the deployed episode's seed
N_SAMPLES = 32 if FAST else 64  # TESTU/TESTA record length (the toolkit recommends 64)
out = Path(tempfile.mkdtemp(prefix="jvl_policy_to_twin_"))

# the twin's hidden load: what the identification has to find
truth = {"load_inertia": 4.0 * 17.3e-6, "viscous_friction": 2e-6, "coulomb_friction": 0.006}
twin_motor = MotorArray("MAC140", n=1, seed=3, record_length=N_SAMPLES, current_noise=2.0,
                        position_noise=0.85, **truth)

# %% [markdown]
# ## 1 · Identify the twin over MacTalk
# The twin runs 25 times faster than real time for the identification (the toolkit's
# `time_scale` follows it); `write=True` writes the kept register set to the motor, as
# `jvl-tune autotune --write` does. The toolkit's own writers save the result as `jvl-tune
# autotune --out DIR` does: `setup.yaml` and `report.txt`.

# %%
from tuning.pipeline import write_setup  # noqa: E402
from tuning.report import report_text  # noqa: E402
from tuning.serial_source import autotune_over_serial  # noqa: E402
from tuning.strategy import strategy_of  # noqa: E402

server = TwinServer(Twin(twin_motor, [ADDRESS]), speed=25.0, tcp=("127.0.0.1", 0)).start()
try:
    url = server.endpoint("mactalk", "tcp").url
    ident, result = autotune_over_serial(url, "MAC140", address=ADDRESS, time_scale=25.0,
                                         n_coil=N_SAMPLES, n_mech=N_SAMPLES, write=True)
finally:
    server.stop()
write_setup(out / "setup.yaml", "MAC140", result.chosen.registers,
            f"jvl-tune autotune --port {url}: identified J = {ident.mechanics.J:.4g}")
(out / "report.txt").write_text(report_text(strategy_of("MAC140"), result))
print("\n".join((out / "report.txt").read_text().splitlines()[:11]))
J_m = twin_motor.motor_configs[0].rotor_inertia
print(f"\ntrue J {J_m + truth['load_inertia']:.4e} kg·m², true Tc {truth['coulomb_friction']} N·m")

# %% [markdown]
# ## 2 · The env of the measured motor
# `env_kwargs_from_identification` reads the folder (or takes `result` in memory): the motor
# type, the randomisation ranges (the identified 95 % intervals, clipped at 0; the load as
# `inertia_ratio` × J_m, Coulomb friction as `coulomb_ratio` × rated torque) and the setup
# the motor now holds. The env's default ranges are wide (a load of 0–10 rotor inertias);
# these are the motor's. The truth is printed beside them: the intervals are narrow and can
# miss it by a little (a model error they do not count, docs/tuning.md "Intervals"); a
# `randomization` of your own widens a range for a margin.

# %%
kwargs = env_kwargs_from_identification(out, ENV_ID)
for name, (lo, hi) in kwargs["randomization"].items():
    print(f"{name:<18} [{lo:.4g}, {hi:.4g}]")
print(f"true inertia_ratio {truth['load_inertia'] / J_m:.4g}, "
      f"coulomb_ratio {truth['coulomb_friction'] / 0.32:.4g}")

# %% [markdown]
# ## 3 · Train behind the link model
# The link variant of the Positioning config (`configs/rl/positioning.yml`) behind the
# MacTalk-over-TCP link: the policy acts every 6 env steps (11.5 ms), its action lands 4 ms
# after the read and moves at most 0.5 from the one before, as the deployment's supervisor
# bounds it.

# %%
from jvl_gym.envs.registration import vector_class  # noqa: E402
from jvl_gym.rl.deploy import load_policy  # noqa: E402
from jvl_gym.rl.train import train  # noqa: E402

model = train(ENV_ID, out / "runs", total_timesteps=4096 if FAST else None, seed=0,
              progress_bar=False, link=LINK, variant="link", env_kwargs=kwargs)
policy = load_policy(str(model), ENV_ID, 1, vector_class(ENV_ID).step_seconds("MAC140"))

# %% [markdown]
# ## 4 · Deploy to the twin in real time, beside the link model
# The same twin motor (load and tuned setup), now served in real time. `deploy` runs the loop
# `jvl-gym deploy` runs: read the position and speed, the policy under its deadline, the
# supervisor's bounds, each write held to the link model's latency, one row per period in the
# trace. A busy machine may stretch a period: the supervisor then stops the loop and says why
# (a worse episode, not an error). `link_trace` runs the same policy on the identified env
# behind the link model, from the same seed (the same target).

# %%
from jvl_gym.rl.deploy import deploy, link_latency, loop_period  # noqa: E402
from jvl_gym.rl.lockstep import link_trace  # noqa: E402

period = loop_period(ENV_ID, LINK, "MAC140")
server = TwinServer(Twin(twin_motor, [ADDRESS]), speed=1.0, tcp=("127.0.0.1", 0)).start()
try:
    report = deploy(ENV_ID, policy, server.endpoint("mactalk", "tcp").url, ADDRESS, "MAC140",
                    period=period, episodes=1, seed=SEED, max_step=0.5,
                    hold=link_latency(ENV_ID, LINK, "MAC140"), trace=out / "deployed.csv",
                    watchdog_timeout=1.0, env_kwargs=kwargs)
finally:
    server.stop()
print(report.summary())

env_kwargs = {k: v for k, v in kwargs.items() if k != "motor_type"}
model_trace = link_trace(ENV_ID, policy, LINK, "MAC140", SEED, 10_000, **env_kwargs)

# %%
import csv  # noqa: E402

with (out / "deployed.csv").open() as f:
    rows = list(csv.DictReader(f))
deployed_error = np.array([float(r["error_turns"]) for r in rows])
deployed_action = np.array([float(r["action"]) for r in rows])
model_error = 2.0 * model_trace["obs"][:, 0]  # the observation's error is in units of 2 turns
fig, ax = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
ax[0].plot(model_error, ".-", label="link model (identified env)")
ax[0].plot(deployed_error, ".-", label=f"deployed to the twin ({report.reason})")
ax[0].set(ylabel="position error [turns]")
ax[0].legend()
ax[1].step(range(len(model_trace["action"])), model_trace["action"][:, 0], where="post")
ax[1].step(range(len(deployed_action)), deployed_action, where="post")
ax[1].set(xlabel=f"period ({1e3 * period:.1f} ms)", ylabel="torque command [1]")
plt.show()
n = min(len(model_error), len(deployed_error))
print(f"{n} periods side by side; return: link model {model_trace['reward'].sum():.2f}, "
      f"deployed {np.sum(report.returns):.2f}")

# %% [markdown]
# ## Policy against the firmware behind the link
# On held-out seeds of the identified env behind the link: the policy's mean return against
# the baseline's (the firmware's own positioning, P_MODE, with the tuned setup). With
# `JVL_FAST=1` one seed of two episodes, to show the call; the full budget is what it takes to
# win it.

# %%
from jvl_gym.rl.evaluate import evaluate, format_table  # noqa: E402

scores = evaluate(ENV_ID, model, n_seeds=1 if FAST else 5, episodes_per_seed=2 if FAST else 8,
                  progress_bar=False, link=LINK, env_kwargs=kwargs)
print(format_table({ENV_ID: scores}))

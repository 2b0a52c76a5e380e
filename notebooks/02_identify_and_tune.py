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
# # 02 · Identify and tune a MAC140 with an unknown load
#
# Commissioning with the tuning toolkit (`tuning`, CLI `jvl-tune`):
#
# 1. TESTU (manual 4.4.9) → the coil: line-to-line R, L and the PWM delay, with 95 % intervals;
# 2. TESTA (manual 4.4.10) at two torque levels → total inertia J, KVOUT, friction;
# 3. synthesis of the IF/IB current filters and the FF/VB/VF speed filters, quantised to their
#    register formats, with margins, pole radii and robustness checks;
# 4. a step on the simulator with the default and the tuned register set;
# 5. the same procedure over a serial line, against the digital twin (`jvl-gym serve`).
#
# The motor's load is drawn at random and hidden in `truth`; the toolkit sees only records.

# %%
import os
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from jvl_gym import MotorArray
from jvl_gym.families.mac050_141 import constants as c
from tuning.autotune import identify_motors, synthesize, verify_design
from tuning.pipeline import Candidate
from tuning.report import bode_figure, design_table, identification_table
from tuning.strategy import strategy_of

FAST = os.environ.get("JVL_FAST") == "1"
N_SAMPLES = 32 if FAST else 64  # the toolkit recommends 64; the manual records 11
rng = np.random.default_rng(7)
truth = {"load_inertia": float(rng.uniform(0, 10) * 17.3e-6),
         "viscous_friction": 2e-6, "coulomb_friction": 0.004}
motor = MotorArray("MAC140", n=1, seed=1, current_noise=2.0, position_noise=0.85, **truth)
out = Path(tempfile.mkdtemp(prefix="jvl_tune_"))

# %% [markdown]
# ## Identification (TESTU, two-level TESTA)

# %%
ident = identify_motors(motor, n_coil=N_SAMPLES, n_mech=N_SAMPLES, progress=print)[0]
cfg = motor.motor_configs[0]
J_true = cfg.rotor_inertia + truth["load_inertia"]
print(f"R_line {ident.coil.R_line:.4f} Ω  (true {2 * cfg.phase_resistance:.4f}), "
      f"95 % CI {np.round(ident.coil.ci['R_line'], 4)}")
print(f"L_line {ident.coil.L_line * 1e3:.4f} mH (true {2e3 * cfg.phase_inductance:.4f}), "
      f"delay {ident.coil.delay} sample(s)")
print(f"J      {ident.mechanics.J:.4e} kg·m² (true {J_true:.4e}), "
      f"KVOUT {ident.mechanics.kvout:.2f}")

# %%
strategy = strategy_of("MAC140")
strategy.fit_figure(ident)
plt.show()

# %% [markdown]
# ## Synthesis, quantisation and verification

# %%
design = synthesize(ident.motor, ident.mechanics.J, ident.mechanics.coulomb, structure="pi")
tuned = Candidate("pi", design.registers, design)
print("\n".join([*identification_table(strategy, ident),
                 *design_table(strategy, tuned, ident.motor, ident.mechanics.J)]))
print("verification problems:", verify_design(design) or "none")

# %%
bode_figure(strategy.open_loops(tuned, ident.motor, ident.mechanics.J))
plt.show()

# %% [markdown]
# ## Default versus tuned register set on the simulator
# A 30 000-count move with the same hidden load; the tuned set carries the identified KVOUT.

# %%
def move(setup: dict | None) -> np.ndarray:
    m = MotorArray("MAC140", n=1, seed=2, **truth)
    if setup is not None:
        m.load_setup({"registers": setup})
    m.write("A_SOLL", 60)
    m.write("V_SOLL", 4000)
    m.write("P_SOLL", 30000)
    m.write("MODE_REG", c.P_MODE)
    return m.trace(["P_IST"], int((0.5 if FAST else 1.0) * c.OUTER_HZ))["P_IST"][:, 0]


p_default, p_tuned = move(None), move(design.registers)
t = np.arange(p_default.size) * c.OUTER_DT
plt.plot(t, p_default - 30000, label="default setup")
plt.plot(t, p_tuned - 30000, label="tuned (jvl-tune)")
plt.ylim(-400, 400)
plt.ylabel("P_IST − P_SOLL [counts]")
plt.xlabel("time [s]")
plt.legend()
plt.show()

# %% [markdown]
# ## Writing the register set
# `design.registers` maps register names to values in the register formats; written as a setup
# file it is exactly what `families/mac050_141/configs/setups/*.yaml` and `MotorArray.load_setup` take.

# %%
import yaml  # noqa: E402

(out / "setup.yaml").write_text(yaml.safe_dump({"motor": "MAC140", "registers": {
    k: float(v) for k, v in design.registers.items()}}, sort_keys=False))
print((out / "setup.yaml").read_text()[:400])

# %% [markdown]
# ## The same over a serial port: the digital twin
# `jvl-gym serve --motor MAC140 --address 19 --tcp 127.0.0.1:5000` serves simulated motors over
# MacTalk; here it runs in-process on a free localhost port, 25 times faster than real time.
# `jvl-tune autotune --port socket://127.0.0.1:PORT --address 19 --write` does the same from the
# shell; pointed at `/dev/ttyUSB0` it commissions a real motor.

# %%
from jvl_gym.protocol.serving.transport import TwinServer  # noqa: E402
from jvl_gym.protocol.mactalk.twin16 import Twin  # noqa: E402
from tuning.serial_source import autotune_over_serial  # noqa: E402

twin_motor = MotorArray("MAC140", n=1, seed=3, record_length=N_SAMPLES, **truth)
server = TwinServer(Twin(twin_motor, [19]), speed=25.0, tcp=("127.0.0.1", 0)).start()
try:
    url = server.endpoint("mactalk", "tcp").url
    ident_s, result_s = autotune_over_serial(url, "MAC140", address=19, time_scale=25.0,
                                             n_coil=N_SAMPLES, n_mech=N_SAMPLES, write=True)
finally:
    server.stop()
print(f"over {url}: J = {ident_s.mechanics.J:.4e} kg·m² (true {J_true:.4e}), "
      f"KVOUT written to the twin: {twin_motor.read('KVOUT')[0]:.2f}")

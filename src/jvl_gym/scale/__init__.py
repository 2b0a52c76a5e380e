"""Past one machine: training sweeps, fleet autotuning and RLlib on Ray (``scale`` extra).

One concept per module:

- :mod:`.extra`: the ``scale`` extra (Ray) and the one-line message when it is missing;
- :mod:`.errors`: :class:`UserError` and the CLI wrapper that prints it as one line;
- :mod:`.distributions`: scalar distributions of the sweep and fleet files;
- :mod:`.sweep_spec`: the sweep file (``configs/sweeps/*.yml``) and its trials;
- :mod:`.trial`: one trial (train on the native vector env, evaluate on held-out seeds);
- :mod:`.ledger`: finished trials on disk (what a resumed sweep skips);
- :mod:`.sweep`: the sweep on Ray Tune (``jvl-gym sweep``);
- :mod:`.sweep_report`: results table (CSV, markdown) and learning-curve plot;
- :mod:`.fleet_spec`: the fleet file (``configs/fleets/*.yml``) or a folder of records;
- :mod:`.fleet_motor`: autotuning one motor (one Ray task);
- :mod:`.fleet`: the fleet on Ray tasks (``jvl-tune fleet``);
- :mod:`.fleet_report`: the fleet report (table, histograms, flagged motors);
- :mod:`.ray_session`: connecting to local Ray or a cluster (``--address``);
- :mod:`.rllib`: the envs as RLlib environments and a PPO example;
- :mod:`.commands`: the bodies of the two CLI commands.

Importing this package does not import Ray.
"""

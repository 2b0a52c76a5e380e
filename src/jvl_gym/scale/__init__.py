"""Past one machine: training sweeps and RLlib on Ray (``scale`` extra), and the Ray session
the toolkit's fleet autotune uses.

One concept per module:

- :mod:`.extra`: the ``scale`` extra (Ray) and the one-line message when it is missing;
- :mod:`.errors`: :class:`UserError` and the CLI wrapper that prints it as one line;
- :mod:`.distributions`: scalar distributions of the sweep and fleet files;
- :mod:`.sweep_spec`: the sweep file (``configs/sweeps/*.yml``) and its trials;
- :mod:`.trial`: one trial (train on the native vector env, evaluate on held-out seeds);
- :mod:`.ledger`: finished trials on disk (what a resumed sweep skips);
- :mod:`.sweep`: the sweep on Ray Tune (``jvl-gym sweep``);
- :mod:`.sweep_report`: results table (CSV, markdown) and learning-curve plot;
- :mod:`.ray_session`: connecting to local Ray or a cluster (``--address``);
- :mod:`.rllib`: the envs as RLlib environments and a PPO example;
- :mod:`.commands`: the body of ``jvl-gym sweep`` and what ``jvl-tune fleet`` shares with it.

The fleet autotune (``jvl-tune fleet``) is the tuning toolkit's (``tuning.fleet``,
``tuning.fleet_spec``, ``tuning.fleet_motor``, ``tuning.fleet_report``) on this package's Ray
session; nothing here imports the toolkit.

Importing this package does not import Ray.
"""

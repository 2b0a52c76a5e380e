"""Reinforcement learning on the jvl_gym envs (``rl`` extra: stable-baselines3, torch).

:mod:`.sb3_adapter` (an SB3 ``VecEnv`` over a native vector env), :mod:`.config` (the
hyper-parameters in ``configs/rl/*.yml``), :mod:`.train`, :mod:`.evaluate` (policy vs
baseline table) and :mod:`.results` (the results page of every env × family). Importing
this package does not import stable-baselines3.
"""

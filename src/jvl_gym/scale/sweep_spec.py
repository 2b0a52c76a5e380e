"""The sweep file (``configs/sweeps/*.yml``) and the trials it expands to.

Layout (every key but ``env`` and ``parameters`` optional)::

    env: jvl_gym/GearSync-v0      # a registered env id with an entry in configs/rl
    rl_config_dir: null           # directory of the RL *.yml (default configs/rl)
    search: grid                  # grid: every combination; random: `samples` draws
    samples: 4                    # random only: parameter points drawn
    sampler_seed: 0               # random only: seed of the draws
    seeds: [0]                    # training seeds; every parameter point runs once per seed
    parameters:                   # dotted keys of the configs/rl entry
      hyperparams.learning_rate: [0.0001, 0.0003]      # grid: the values
      hyperparams.n_epochs: [5, 10]                    # random: a distribution or a list
    budget: {timesteps: 100000, n_envs: 16}            # per trial
    resources: {cpus_per_trial: 1, max_concurrent: null}
    eval: {n_seeds: 5, episodes_per_seed: 8}           # held-out seeds, as jvl-gym evaluate

Parameter keys: ``n_envs``, ``hyperparams.<name>`` (nested: ``hyperparams.policy_kwargs.
net_arch``) and ``env_kwargs.<name>``. A trial's id is its index and a hash of everything that
determines its result (env, parameters, seed, budget, evaluation), so a resumed sweep
recognises its finished trials, and an edited sweep file does not reuse stale ones.
"""

from __future__ import annotations

import copy
import hashlib
import inspect
import itertools
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .distributions import Distribution, parse_distribution
from .errors import UserError, file_integer, file_mapping, file_number, read_yaml

__all__ = ["SweepSpec", "Trial", "load_sweep", "parse_sweep", "trial_config"]

_KEYS = {"env", "rl_config_dir", "search", "samples", "sampler_seed", "seeds", "parameters",
         "budget", "resources", "eval"}
_BUDGET = {"timesteps", "n_envs"}
_RESOURCES = {"cpus_per_trial", "max_concurrent"}
_EVAL = {"n_seeds", "episodes_per_seed"}


@dataclass(frozen=True)
class Trial:
    """One trial: a parameter point and a training seed.

    Attributes
    ----------
    trial_id : str
        ``t<index>-<hash>``; stable for an unchanged sweep file.
    params : dict
        Dotted key -> value.
    seed : int
        Training seed.
    """

    trial_id: str
    params: dict[str, Any]
    seed: int


@dataclass
class SweepSpec:
    """A parsed, validated sweep file.

    Attributes
    ----------
    path : Path or None
        The file it came from.
    env : str
        Env id.
    rl_config_dir : Path or None
        Directory of the RL ``*.yml`` (``None``: ``configs/rl``).
    search : str
        ``"grid"`` or ``"random"``.
    parameters : dict
        Dotted key -> list of values (grid) or :class:`Distribution` (random).
    seeds : list of int
        Training seeds.
    samples, sampler_seed : int
        Random search only.
    timesteps : int
        Env steps per trial.
    n_envs : int or None
        Vector env copies (``None``: the RL config's).
    cpus_per_trial : float
        CPUs Ray reserves per trial (also the trial's torch/numba threads, at least 1).
    max_concurrent : int or None
        Trials at once (``None``: as many as the CPUs allow).
    eval_seeds, episodes_per_seed : int
        Held-out evaluation.
    base : dict
        The env's configs/rl entry.
    """

    path: Path | None
    env: str
    rl_config_dir: Path | None
    search: str
    parameters: dict[str, Any]
    seeds: list[int]
    samples: int
    sampler_seed: int
    timesteps: int
    n_envs: int | None
    cpus_per_trial: float
    max_concurrent: int | None
    eval_seeds: int
    episodes_per_seed: int
    base: dict[str, Any] = field(repr=False, default_factory=dict)

    def trials(self) -> list[Trial]:
        """Every trial, in a fixed order (grid: row-major over the parameters, then seeds)."""
        if self.search == "grid":
            keys = list(self.parameters)
            points = [dict(zip(keys, combo))
                      for combo in itertools.product(*(self.parameters[k] for k in keys))]
        else:
            rng = np.random.default_rng(self.sampler_seed)
            draws = {k: d.sample(rng, self.samples) for k, d in self.parameters.items()}
            points = [{k: draws[k][i] for k in draws} for i in range(self.samples)]
        out = []
        for point in points:
            for seed in self.seeds:
                idx = len(out)
                out.append(Trial(f"t{idx:03d}-{self._hash(point, seed)}", point, int(seed)))
        return out

    def _hash(self, point: dict[str, Any], seed: int) -> str:
        key = {"env": self.env, "params": point, "seed": seed, "timesteps": self.timesteps,
               "n_envs": self.n_envs, "eval": [self.eval_seeds, self.episodes_per_seed],
               "base": self.base}
        text = json.dumps(key, sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:8]


def _positive_int(value: Any, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise UserError(f"{where}: expected a positive integer, got {value!r}")
    return value


def _check_param_key(key: str, env: str, base: dict[str, Any], where: str) -> None:
    head, _, rest = key.partition(".")
    if key == "n_envs":
        return
    if head not in ("hyperparams", "env_kwargs") or not rest:
        raise UserError(f"{where}: parameter {key!r}: use n_envs, hyperparams.<name> or "
                        "env_kwargs.<name>")
    name = rest.split(".")[0]
    if head == "hyperparams":
        allowed = _algo_arguments(base["algo"])
        if allowed is not None and name not in allowed:
            raise UserError(f"{where}: parameter {key!r}: {base['algo']} has no argument "
                            f"{name!r}")
    else:
        allowed = _env_arguments(env)
        if allowed is not None and name not in allowed:
            raise UserError(f"{where}: parameter {key!r}: {env} takes no argument {name!r}; "
                            f"it takes {', '.join(sorted(allowed))}")


def _env_arguments(env: str) -> set[str] | None:
    """The keyword arguments of the env's vector class: the named parameters of the
    ``__init__`` of each jvl_gym class in its MRO (the base class refuses any other)."""
    import importlib

    import gymnasium as gym

    entry = gym.spec(env).vector_entry_point
    if not isinstance(entry, str) or ":" not in entry:
        return None
    module, _, name = entry.partition(":")
    names: set[str] = set()
    for cls in getattr(importlib.import_module(module), name).__mro__:
        if "__init__" in vars(cls) and cls.__module__.startswith("jvl_gym."):
            params = inspect.signature(vars(cls)["__init__"]).parameters
            names |= {n for n, p in params.items()
                      if p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)}
    return (names - {"self", "num_envs"}) or None


def _algo_arguments(algo: str) -> set[str] | None:
    try:
        import stable_baselines3 as sb3
    except ImportError:
        return None
    cls = getattr(sb3, algo, None)
    if cls is None:
        return None
    return set(inspect.signature(cls.__init__).parameters) - {"self", "policy", "env"}


def parse_sweep(data: Any, path: Path | None = None) -> SweepSpec:
    """Validate a sweep mapping (module docstring) and return a :class:`SweepSpec`.

    Raises
    ------
    UserError
        On any malformed or unknown entry; the message names the file and the key.
    """
    where = str(path) if path is not None else "sweep"
    data = file_mapping(data, where, _KEYS)
    if "env" not in data:
        raise UserError(f"{where}: missing 'env' (a registered id, e.g. jvl_gym/GearSync-v0)")
    env = str(data["env"])
    rl_dir = data.get("rl_config_dir")
    rl_dir = Path(rl_dir) if rl_dir is not None else None
    if rl_dir is not None and path is not None and not rl_dir.is_absolute():
        rl_dir = (path.parent / rl_dir).resolve()
    base = _base_config(env, rl_dir, where)
    search = data.get("search", "grid")
    if search not in ("grid", "random"):
        raise UserError(f"{where}: search: {search!r} is not 'grid' or 'random'")
    params_raw = data.get("parameters") or {}
    if not isinstance(params_raw, dict):
        raise UserError(f"{where}: parameters: expected a mapping of dotted keys to values")
    params: dict[str, Any] = {}
    for key, value in params_raw.items():
        pw = f"{where}: parameters.{key}"
        _check_param_key(str(key), env, base, where)
        if search == "grid":
            if not isinstance(value, list) or not value:
                raise UserError(f"{pw}: a grid needs a non-empty list of values")
            params[str(key)] = value
        else:
            params[str(key)] = (Distribution("choice", tuple(value)) if isinstance(value, list)
                                else parse_distribution(value, pw))
    seeds = data.get("seeds", [base["seed"]])
    if isinstance(seeds, int) and not isinstance(seeds, bool):
        seeds = [seeds]
    if (not isinstance(seeds, list) or not seeds
            or not all(isinstance(s, int) and not isinstance(s, bool) for s in seeds)):
        raise UserError(f"{where}: seeds: expected a list of integers")
    if len(set(seeds)) != len(seeds):
        raise UserError(f"{where}: seeds: {seeds} repeats a seed")
    budget = file_mapping(data.get("budget"), f"{where}: budget", _BUDGET)
    res = file_mapping(data.get("resources"), f"{where}: resources", _RESOURCES)
    ev = file_mapping(data.get("eval"), f"{where}: eval", _EVAL)
    cpus = file_number(res.get("cpus_per_trial", 1), f"{where}: resources.cpus_per_trial",
                       positive=True)
    mc = res.get("max_concurrent")
    spec = SweepSpec(
        path=path, env=env, rl_config_dir=rl_dir, search=search, parameters=params,
        seeds=[int(s) for s in seeds],
        samples=_positive_int(data.get("samples", 1), f"{where}: samples"),
        sampler_seed=file_integer(data.get("sampler_seed", 0), f"{where}: sampler_seed"),
        timesteps=_positive_int(budget.get("timesteps", base["total_timesteps"]),
                                f"{where}: budget.timesteps"),
        n_envs=(_positive_int(budget["n_envs"], f"{where}: budget.n_envs")
                if "n_envs" in budget else None),
        cpus_per_trial=cpus,
        max_concurrent=(_positive_int(mc, f"{where}: resources.max_concurrent")
                        if mc is not None else None),
        eval_seeds=_positive_int(ev.get("n_seeds", base["eval"]["n_seeds"]),
                                 f"{where}: eval.n_seeds"),
        episodes_per_seed=_positive_int(ev.get("episodes_per_seed",
                                               base["eval"]["episodes_per_seed"]),
                                        f"{where}: eval.episodes_per_seed"),
        base=base)
    if search == "random" and "samples" not in data:
        raise UserError(f"{where}: search: random needs 'samples' (parameter points to draw)")
    return spec


def _base_config(env: str, rl_dir: Path | None, where: str) -> dict[str, Any]:
    import gymnasium as gym

    import jvl_gym  # noqa: F401  (registers the ids)
    from jvl_gym.rl.config import rl_config

    try:
        gym.spec(env)
    except gym.error.Error:
        ids = sorted(k for k in gym.registry if k.startswith("jvl_gym/"))
        raise UserError(f"{where}: env: unknown env id {env!r}; registered: "
                        f"{', '.join(ids)}") from None
    if rl_dir is not None and not rl_dir.is_dir():
        raise UserError(f"{where}: rl_config_dir: {rl_dir} is not a directory")
    try:
        return copy.deepcopy(rl_config(env, rl_dir))
    except KeyError as exc:
        raise UserError(f"{where}: env: {exc.args[0]}") from None
    except ValueError as exc:
        raise UserError(f"{where}: rl_config_dir: {exc}") from None


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and validate a sweep file.

    Raises
    ------
    UserError
        Missing file, YAML syntax error, or a malformed entry.
    """
    path = Path(path)
    if not path.is_file():
        raise UserError(f"{path}: no such sweep file; give a YAML file such as "
                        "configs/sweeps/example.yml")
    data = read_yaml(path)
    return parse_sweep(data, path)


def trial_config(spec: SweepSpec, trial: Trial) -> dict[str, Any]:
    """The configs/rl entry a trial trains with: the base entry with the trial's parameters,
    the budget's timesteps and n_envs, and the trial's seed."""
    cfg = copy.deepcopy(spec.base)
    if spec.n_envs is not None:
        cfg["n_envs"] = spec.n_envs
    for key, value in trial.params.items():
        parts = key.split(".")
        node = cfg
        for p in parts[:-1]:
            node = node.setdefault(p, {})
        node[parts[-1]] = value
    cfg["total_timesteps"] = spec.timesteps
    cfg["seed"] = trial.seed
    cfg["eval"] = {**cfg["eval"], "n_seeds": spec.eval_seeds,
                   "episodes_per_seed": spec.episodes_per_seed}
    return cfg

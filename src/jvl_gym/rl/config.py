"""RL hyper-parameters: ``configs/rl/*.yml``, each a mapping keyed by env id.

Each entry holds ``algo`` (PPO, SAC or TD3), ``n_envs``, ``total_timesteps``, ``policy``,
``env_kwargs`` (constructor arguments), ``hyperparams`` (algorithm keyword arguments;
``policy_kwargs.net_arch`` as a list), ``eval`` (``n_seeds``, ``episodes_per_seed``,
``seed_offset``: held-out seeds start there) and ``seed``, and optionally

- ``families``: family key -> overrides of the entry for that family (``{}``: as the entry). A
  family not listed is not configured; an entry without ``families`` configures the env's
  first family only. Without a ``motor_type`` in ``env_kwargs``, a family other than the
  env's first runs its family's default motor type (:func:`family_motor_type`);
  ``motor_type: all`` draws every motor type of the family per episode.
- ``algos``: algorithm name (one of :data:`ALGOS`) -> overrides of the entry for that
  algorithm (its ``hyperparams``, ``n_envs`` ...), trained on every configured family; the
  entry's own ``algo`` is the default one.
- ``variants``: variant name -> overrides of the entry (any key above but ``families``,
  ``algos`` and ``variants``), trained with the entry's algorithm on the families listed in
  the variant's own ``families`` (default: the entry's first), saved under a name of their own
  (``<Env>-<family>-<variant>-<algo>.zip``). ``link`` (default none) trains behind a link
  (``jvl_gym.envs.link``): a variant with a link and one without make the transfer gap's pair
  (:mod:`jvl_gym.rl.transfer`). ``init: shipped`` starts a training from the shipped policy
  of the same env, family and algorithm (a fine-tuning; default: from scratch).

A family's overrides may hold ``algos`` of their own: overrides for that algorithm on that
family only. They apply in this order, each over the one before: the entry, its ``algos``
section of the algorithm, the family's overrides, the family's ``algos`` section of the
algorithm; a variant's overrides come last.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

import yaml

from ..families.config import configs_dir

__all__ = ["ALGOS", "load_rl_configs", "rl_config", "rl_runs", "rl_variants", "env_families",
           "family_motor_type"]

#: the stable-baselines3 algorithms a config may name
ALGOS = ("PPO", "SAC", "TD3")

_DEFAULTS: dict[str, Any] = {
    "algo": "PPO", "n_envs": 16, "total_timesteps": 200_000, "policy": "MlpPolicy",
    "env_kwargs": {}, "hyperparams": {}, "seed": 0,
    "eval": {"n_seeds": 5, "episodes_per_seed": 8, "seed_offset": 100_000}, "link": None,
    "init": None,
}
_NESTED = ("families", "algos", "variants")


def env_families(env_id: str) -> tuple[str, ...]:
    """Keys of the motor families ``env_id`` runs on, its default family first (the
    ``supported_families()`` of its registered vector entry point)."""
    from ..envs.registration import vector_class

    return tuple(vector_class(env_id).supported_families())


def family_motor_type(key: str) -> str:
    """The default motor type of the family ``key`` (``DEFAULT_MOTOR_TYPE`` of its public
    ``task`` module)."""
    from ..families import family

    fam: Any = family(key)
    task = getattr(fam, "task", None)
    if task is None:
        task = importlib.import_module(fam.compiled.__name__.rpartition(".")[0] + ".task")
    return str(task.DEFAULT_MOTOR_TYPE)


def _check_keys(where: str, cfg: Any, allowed: set[str]) -> None:
    if not isinstance(cfg, dict):
        raise ValueError(f"{where}: expected a mapping, got {type(cfg).__name__}")
    unknown = set(cfg) - allowed
    if unknown:
        raise ValueError(f"{where}: unknown keys {sorted(unknown)}")


def _check_algos(where: str, algos: Any, names: tuple[str, ...] = ALGOS) -> None:
    """An ``algos`` section: algorithm names (of ``names``) -> overrides."""
    if algos is None:
        return
    if not isinstance(algos, dict):
        raise ValueError(f"{where}: algos: expected a mapping, got {type(algos).__name__}")
    for name, over in algos.items():
        if str(name).upper() not in names:
            raise ValueError(f"{where}: algos: {name} is not one of {', '.join(names)}")
        _check_keys(f"{where}: algos: {name}", over or {}, set(_DEFAULTS))


def _check_variants(where: str, variants: Any) -> None:
    """A ``variants`` section: name -> overrides (and ``families``, a list of keys)."""
    if variants is None:
        return
    if not isinstance(variants, dict):
        raise ValueError(f"{where}: variants: expected a mapping, got "
                         f"{type(variants).__name__}")
    for name, over in variants.items():
        if not str(name).replace("_", "").isalnum() or str(name).upper() in ALGOS:
            raise ValueError(f"{where}: variants: {name!r} is not a name (letters, digits, "
                             "'_'; not an algorithm's)")
        _check_keys(f"{where}: variants: {name}", over or {}, set(_DEFAULTS) | {"families"})
        fams = (over or {}).get("families")
        if fams is not None and not isinstance(fams, list):
            raise ValueError(f"{where}: variants: {name}: families: expected a list of "
                             "family keys")


def _merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    out = {**base, **over}
    out["eval"] = {**base.get("eval", {}), **over.get("eval", {})}
    return out


def load_rl_configs(directory: str | Path | None = None) -> dict[str, dict[str, Any]]:
    """Every env id's entry from the ``*.yml`` files of ``directory`` (default
    ``configs/rl``), with defaults filled in (``families`` and ``algos`` kept as written)."""
    root = Path(directory) if directory is not None else configs_dir() / "rl"
    out: dict[str, dict[str, Any]] = {}
    for path in sorted(root.glob("*.yml")):
        data = yaml.safe_load(path.read_text()) or {}
        if not isinstance(data, dict):
            raise ValueError(f"{path}: expected a mapping keyed by env id")
        for env_id, cfg in data.items():
            if env_id in out:
                raise ValueError(f"{path}: {env_id} is configured twice")
            _check_keys(f"{path}: {env_id}", cfg, set(_DEFAULTS) | set(_NESTED))
            _check_algos(f"{path}: {env_id}", cfg.get("algos"))
            trained = tuple(str(a).upper() for a in
                            (cfg.get("algo", _DEFAULTS["algo"]), *(cfg.get("algos") or {})))
            for key, over in (cfg.get("families") or {}).items():
                where = f"{path}: {env_id}: families: {key}"
                _check_keys(where, over or {}, set(_DEFAULTS) | {"algos"})
                _check_algos(where, (over or {}).get("algos"), trained)
            _check_variants(f"{path}: {env_id}", cfg.get("variants"))
            if cfg.get("algo", _DEFAULTS["algo"]) not in ALGOS:
                raise ValueError(f"{path}: {env_id}: algo must be one of {', '.join(ALGOS)}")
            out[env_id] = _merge(_DEFAULTS, cfg)
    return out


def _configured_families(env_id: str, entry: dict[str, Any]) -> list[str]:
    listed = entry.get("families")
    return list(listed) if listed else [env_families(env_id)[0]]


def _variant_families(env_id: str, entry: dict[str, Any], name: str) -> list[str]:
    over = (entry.get("variants") or {}).get(name) or {}
    return list(over.get("families") or [env_families(env_id)[0]])


def rl_config(env_id: str, directory: str | Path | None = None, *, family: str | None = None,
              algo: str | None = None, variant: str | None = None) -> dict[str, Any]:
    """The config of one env id on one family (default: the first configured) with one
    algorithm (default: the entry's ``algo``; case-insensitive), or of one of its variants.

    Raises
    ------
    KeyError
        The env, family, algorithm or variant is not configured (the message lists what is).
    """
    configs = load_rl_configs(directory)
    if env_id not in configs:
        raise KeyError(f"no RL config for {env_id!r}; configured: {sorted(configs)}")
    entry = configs[env_id]
    if variant is not None:
        variants = entry.get("variants") or {}
        if variant not in variants:
            raise KeyError(f"no variant {variant!r} of {env_id}; configured: "
                           f"{', '.join(variants) or 'none'}")
        fams = _variant_families(env_id, entry, variant)
        key = fams[0] if family is None else family
        if key not in fams:
            raise KeyError(f"variant {variant} of {env_id} is not configured on family "
                           f"{key!r}; configured: {', '.join(fams)}")
        over = {k: v for k, v in (variants[variant] or {}).items() if k != "families"}
        base = {k: v for k, v in entry.items() if k not in _NESTED}
        return _kwargs(env_id, key, _merge(base, over))
    fams = _configured_families(env_id, entry)
    key = fams[0] if family is None else family
    if key not in fams:
        raise KeyError(f"no RL config for {env_id} on family {key!r}; configured: "
                       f"{', '.join(fams)}")
    algos = {entry["algo"].upper(): {}}
    algos.update({name.upper(): over or {} for name, over in (entry.get("algos") or {}).items()})
    name = entry["algo"].upper() if algo is None else algo.upper()
    if name not in algos:
        raise KeyError(f"no {name} config for {env_id}; configured: {', '.join(algos)}")
    base = {k: v for k, v in entry.items() if k not in _NESTED}
    fam = dict((entry.get("families") or {}).get(key) or {})
    fam_algos = {str(a).upper(): over or {} for a, over in (fam.pop("algos", None) or {}).items()}
    cfg = _merge(_merge(_merge(base, {**algos[name], "algo": name}), fam),
                 fam_algos.get(name, {}))
    return _kwargs(env_id, key, cfg)


def _kwargs(env_id: str, key: str, cfg: dict[str, Any]) -> dict[str, Any]:
    """``cfg`` with its ``env_kwargs`` for family ``key`` (its motor type)."""
    kwargs = dict(cfg["env_kwargs"])
    if kwargs.get("motor_type") == "all":
        from ..families import family as family_record

        kwargs["motor_type"] = list(family_record(key).motor_types())
    elif "motor_type" not in kwargs and key != env_families(env_id)[0]:
        kwargs["motor_type"] = family_motor_type(key)
    cfg["env_kwargs"] = kwargs
    return cfg


def rl_runs(directory: str | Path | None = None) -> list[tuple[str, str, str]]:
    """Every configured training: (env id, family key, algorithm), in config order."""
    out = []
    for env_id, entry in load_rl_configs(directory).items():
        names = [entry["algo"].upper(), *(str(name).upper() for name in entry.get("algos") or {})]
        for key in _configured_families(env_id, entry):
            out.extend((env_id, key, name) for name in names)
    return out


def rl_variants(directory: str | Path | None = None) -> list[tuple[str, str, str]]:
    """Every configured variant's training: (env id, family key, variant), in config order."""
    out = []
    for env_id, entry in load_rl_configs(directory).items():
        for name in entry.get("variants") or {}:
            out.extend((env_id, key, name) for key in _variant_families(env_id, entry, name))
    return out

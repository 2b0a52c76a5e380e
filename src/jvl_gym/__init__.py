"""jvl_gym: a register-faithful simulator, Gymnasium environments and a tuning toolkit for JVL
MAC50/95/140/141 integrated servo motors.

>>> from jvl_gym import MotorArray
>>> m = MotorArray("MAC140", n=4, seed=0)
"""

from __future__ import annotations

from typing import Any

__all__ = ["MotorArray", "ModeError", "__version__"]
__version__ = "0.1.0"


def __getattr__(name: str) -> Any:
    # Lazy: importing a submodule (plant, protocol codecs, ...) does not compile the kernel.
    if name in ("MotorArray", "ModeError"):
        from .motor import array as sim

        return getattr(sim, name)
    raise AttributeError(f"module 'jvl_gym' has no attribute {name!r}")


def _register() -> None:
    # Gymnasium ids (jvl_gym/...-v0); registering imports no kernel code. Before any jvl_gym
    # function can compile, stale compile caches are dropped (jvl_gym.engine.cache) and the
    # compile notice (jvl_gym.engine.notice) is installed (when the compiler is loaded). The
    # previous layout's module names import as deprecated aliases (jvl_gym.compat).
    from pathlib import Path

    from .compat import install as install_old_names
    from .engine.cache import drop_stale_caches
    from .engine.notice import install_on_import
    from .envs.registration import register_envs

    install_old_names()
    drop_stale_caches(Path(__file__).resolve().parent)
    install_on_import()
    register_envs()


_register()

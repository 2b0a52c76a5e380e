"""The ``scale`` extra: Ray (Tune for sweeps, core tasks for fleets, RLlib)."""

from __future__ import annotations

from types import ModuleType

__all__ = ["INSTALL_HINT", "MissingExtraError", "require_ray"]

#: The one line a command prints when Ray is not installed.
INSTALL_HINT = ("Ray is not installed: this command needs the 'scale' extra; "
                "install it with: pip install -e '.[scale]'")


class MissingExtraError(ImportError):
    """Ray (the ``scale`` extra) is not importable."""


def require_ray() -> ModuleType:
    """Import and return :mod:`ray`.

    Raises
    ------
    MissingExtraError
        With :data:`INSTALL_HINT` as its message when Ray is not installed.
    """
    try:
        import ray
    except ImportError as exc:
        raise MissingExtraError(INSTALL_HINT) from exc
    return ray

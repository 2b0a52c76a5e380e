"""The ``--identified`` option of ``jvl-gym train``, ``evaluate`` and ``deploy``: the env of a
motor identified by ``jvl-tune autotune`` (:mod:`jvl_gym.envs.identified`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .app import CliError

__all__ = ["HELP", "identified_kwargs"]

#: the option's help text
HELP = ("the folder `jvl-tune autotune --out` wrote (or its report.txt or setup.yaml): the env "
        "of that motor (its type and setup; the load and friction drawn within the identified "
        "95 % intervals)")


def identified_kwargs(path: Path | None, env_id: str, family: str | None = None
                      ) -> tuple[dict[str, Any] | None, str | None]:
    """The env arguments of the motor identified in ``path`` for ``env_id``
    (:func:`~jvl_gym.envs.identified.env_kwargs_from_identification`) and its family's key;
    ``(None, family)`` without ``path``. A bad file, or a ``family`` other than the motor's,
    is a :class:`~.app.CliError` of one line."""
    if path is None:
        return None, family
    from ..envs.identified import IdentificationError, env_kwargs_from_identification
    from ..families import family_of_motor

    try:
        kwargs = env_kwargs_from_identification(path, env_id)
    except IdentificationError as exc:
        raise CliError(f"--identified: {exc}") from None
    key = family_of_motor(kwargs["motor_type"]).key
    if family is not None and family != key:
        raise CliError(f"--identified: {path} is a {kwargs['motor_type']} (family {key}), not "
                       f"of --family {family}")
    return kwargs, key

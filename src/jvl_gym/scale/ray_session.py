"""Connecting to Ray: a local Ray started for the command (the default) or a cluster.

``address=None`` starts a local Ray with ``num_cpus`` CPUs (default: all of this machine's);
``address="auto"`` joins the cluster this machine belongs to (``ray start --head`` /
``ray start --address``), ``address="ray://host:10001"`` connects through Ray Client. The
workers get ``MPLBACKEND=Agg`` and, on a local Ray, this process's ``PYTHONPATH`` (so a source
checkout on the path is what they import; a cluster's nodes use their own installation) and the
priority of any other process (:data:`LOCAL_WORKER_ENV`).
"""

from __future__ import annotations

import logging
import os
from typing import Any

from .errors import UserError
from .extra import require_ray

__all__ = ["connect", "LOCAL_OBJECT_STORE_BYTES", "LOCAL_WORKER_ENV"]

#: Object store of a local Ray [bytes]: the commands move small results only.
LOCAL_OBJECT_STORE_BYTES = 256 * 1024 * 1024
#: The environment of a local Ray's workers beside the rest: Ray starts its workers at nice 15,
#: which on a machine busy with other work (a compile, a test run) leaves a trial a few percent
#: of a core; the command's own process only waits for them, so they run at normal priority.
LOCAL_WORKER_ENV = {"RAY_worker_niceness": "0"}


def connect(address: str | None = None, num_cpus: int | None = None,
            log_to_driver: bool = False) -> Any:
    """Initialise Ray unless it already is; returns the :mod:`ray` module.

    Parameters
    ----------
    address : str, optional
        ``None`` (local Ray), ``"auto"`` or a ``ray://`` / ``host:port`` address.
    num_cpus : int, optional
        CPUs of the local Ray (ignored with ``address``).
    log_to_driver : bool
        Forward the workers' stdout/stderr to this process.

    Raises
    ------
    UserError
        ``address`` names no reachable cluster (as far as Ray reports it; an address that
        does not answer makes Ray wait and retry).
    """
    ray = require_ray()
    if ray.is_initialized():
        return ray
    env_vars = {"MPLBACKEND": "Agg"}
    if address is None:
        env_vars.update(LOCAL_WORKER_ENV)
        if os.environ.get("PYTHONPATH"):
            env_vars["PYTHONPATH"] = os.environ["PYTHONPATH"]
    kwargs: dict[str, Any] = {"runtime_env": {"env_vars": env_vars},
                              "log_to_driver": log_to_driver, "logging_level": logging.WARNING,
                              "configure_logging": True}
    if address is None:
        kwargs.update(num_cpus=num_cpus, include_dashboard=False,
                      object_store_memory=LOCAL_OBJECT_STORE_BYTES)
        ray.init(**kwargs)
        return ray
    try:
        ray.init(address=address, **kwargs)
    except (ConnectionError, RuntimeError, ValueError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise UserError(f"--address {address}: no Ray cluster reachable ({first}); start one "
                        "with `ray start --head` or leave out --address for a local Ray") \
            from None
    return ray

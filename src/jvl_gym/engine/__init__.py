"""The engine: the batched stepping driver, its views and the specialisation of drivers for
a motor family and a task (docs/architecture.md).

Attributes are imported on first use, so that importing ``jvl_gym`` (which installs
:mod:`jvl_gym.engine.notice`) stays light.
"""

from __future__ import annotations

import importlib
from typing import Any

from .threads import set_wait_policy

__all__ = ["PARALLEL_MIN", "MotorDriver", "TaskDriver", "noop_hook", "noop_step_hook",
           "EngineView", "Episode"]

_WHERE = {"PARALLEL_MIN": "driver", "MotorDriver": "driver", "TaskDriver": "driver",
          "noop_hook": "driver", "noop_step_hook": "driver", "EngineView": "view",
          "Episode": "view"}

set_wait_policy()  # before any threaded step loads the thread pool (jvl_gym.engine.threads)


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

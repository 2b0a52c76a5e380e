"""The motor array: N simulated motors of one family behind one register interface.

:class:`~.array.MotorArray` is the public class (``from jvl_gym import MotorArray``); its parts
are the register bank and its store plan (:mod:`.bank`), flash images (:mod:`.flash`), digital
and analogue inputs (:mod:`.inputs`), the stepping of the compiled kernel (:mod:`.stepping`),
the checks of its arguments (:mod:`.arguments`), the keyword rules of its parameters
(:mod:`.keywords`) and the per-motor random streams (:mod:`.noise`). The families subclass the
array (``families/<key>/motors.py``); everything above (envs, protocol, world, studio, tuning)
uses its public interface only.

Attributes are imported on first use, so that importing a part does not load the kernel.
"""

from __future__ import annotations

from typing import Any

__all__ = ["MotorArray", "ModeError"]


def __getattr__(name: str) -> Any:
    if name in __all__:
        from . import array

        return getattr(array, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

"""The analogue filter settings of each input (MIS manual §8.2.50 AFZUP_WRITEBITS, §8.2.51
AFZUP_READINDEX, §8.2.52–55 the settings).

The firmware filters each of the eight analogue inputs with its own copy of the settings
AFZUP_CONFMIN, AFZUP_CONFMAX, AFZUP_MAXSLOPE and AFZUP_FILTER (registers 102–105; the filter
itself: :mod:`.firmware.inputs`). Writing AFZUP_WRITEBITS with bits 0–7 set copies the four
registers to the inputs those bits select and sets bit 15 ("registers 102-106 are free to
receive new values"); 255 gives every input the same settings. Writing 1 … 8 to
AFZUP_READINDEX loads that input's settings into the four registers and sets bit 15 (the
register then reads 32768 + n, its documented range 32768–32775). A write of the four
registers alone changes no input's filter. At power-up every input takes the four registers'
values (the firmware's start-up copy is not described; ``docs/families/mis-sim.md``, "Analogue
filter settings per input"; the copy is part of the compiled start, :mod:`.firmware.start`).
"""

from __future__ import annotations

import numpy as np

from . import layout as L
from .firmware import regs as R
from .firmware.start import FILTER_SETTINGS

__all__ = ["FilterSetup", "READ_INDEX_VALUES"]

_DONE = 1 << 15  #: bit 15: the firmware has copied / loaded the settings
#: AFZUP_READINDEX's documented values: 0, 1-8, 32768-32775 (§8.2.51)
READ_INDEX_VALUES = frozenset({0, *range(1, 9), *range(_DONE, _DONE + 9)})


def _columns(k: int) -> list[int]:
    """The ``params`` columns of input ``k`` (0 … 7)'s settings."""
    return [L.P_AF0 + L.AF_SETTINGS * k + col for col in range(L.AF_SETTINGS)]


class FilterSetup:
    """AFZUP_WRITEBITS and AFZUP_READINDEX of :class:`~.motors.MisMotorArray` (a mixin over
    its arrays; module docstring)."""

    regs: np.ndarray
    params: np.ndarray

    def _afzup_write_bits(self, idx: np.ndarray, raw: np.ndarray) -> None:
        """AFZUP_WRITEBITS := ``raw``: the registers 102-105 copied to the inputs of bits 0-7,
        bit 15 set when any was."""
        for i, value in zip(idx.tolist(), raw.tolist()):
            chosen = value & 0xFF
            for k in range(8):
                if chosen & (1 << k):
                    self.params[i, _columns(k)] = self.regs[i, FILTER_SETTINGS]
            self.regs[i, R.AFZUP_WRITEBITS] = value | _DONE if chosen else value

    def _afzup_read_index(self, idx: np.ndarray, raw: np.ndarray) -> None:
        """AFZUP_READINDEX := ``raw`` (one of :data:`READ_INDEX_VALUES`): 1-8 load that input's
        settings into the registers 102-105 and set bit 15."""
        for i, value in zip(idx.tolist(), raw.tolist()):
            if 1 <= value <= 8:
                self.regs[i, FILTER_SETTINGS] = self.params[i, _columns(value - 1)]
                value |= _DONE
            self.regs[i, R.AFZUP_READINDEX] = value

"""FLEXREGISTER: 16 bits collected from other registers (MIS manual §8.2.40, §8.2.117).

FLEXREGSETUP1 … 8 (registers 224–231) each set up 2 of FLEXREGISTER's 16 bits. The manual does
not print the layout of one FLEXREGSETUP register; the simulator takes that of FLEXLEDSETUP1
(§8.2.118), which also names a register and a bit twice in one word: bits 0–8 the register and
bits 9–13 the bit of FLEXREGISTER bit 2(k − 1), bits 16–24 and 25–29 those of bit 2(k − 1) + 1
for FLEXREGSETUPk; a register number 0 (the default) or one the table does not have gives 0.
FLEXREGISTER reads as a signed 16-bit value (range −2¹⁵ … 2¹⁵ − 1, §8.2.40), renewed at the end
of every outer sample (``docs/families/mis-sim.md``, "FlexRegister").
"""

from __future__ import annotations

from numba import njit

from . import regs as R


@njit(cache=True, inline="always")
def _source_bit(regs, half: int) -> int:  # pragma: no cover - compiled
    """The bit one half of a FLEXREGSETUP register names (0 for register 0)."""
    num = half & 0x1FF
    if num == 0 or num >= regs.shape[0]:
        return 0
    return (regs[num] >> ((half >> 9) & 0x1F)) & 1


@njit(cache=True)
def flex_register(regs) -> None:  # pragma: no cover - compiled
    """FLEXREGISTER from FLEXREGSETUP1 … 8 (module docstring)."""
    word = 0
    for k in range(8):
        setup = regs[R.FLEXREGSETUP1 + k]
        if setup == 0:
            continue
        word |= _source_bit(regs, setup & 0xFFFF) << (2 * k)
        word |= _source_bit(regs, (setup >> 16) & 0xFFFF) << (2 * k + 1)
    regs[R.FLEXREGISTER] = word - 0x10000 if word & 0x8000 else word

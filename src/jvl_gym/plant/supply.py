"""DC bus: supply source with series resistance behind a diode, bus capacitor, power dump.

``C du/dt = i_src − P_motor/u − i_dump``. The source conducts while ``u < U_src`` (it cannot sink
regenerated energy), the dump resistor switches on above ``U_dump`` and off 1 V below
(MODEL.md §6, §8: the UIT monitor integrates the regenerative power). Implicit Euler, stable
for any step.
"""

from __future__ import annotations

from numba import njit

from ..jit import KERNEL


@njit(**KERNEL)
def bus_step(u: float, p_motor: float, u_src: float, c_bus: float, r_src: float, u_dump: float,
             r_dump: float, dump_on: float, h: float):
    """Advance the bus by ``h`` [s]; returns ``(u1, dump_on1, e_dump, e_supply)`` [V, -, J, J]."""
    if dump_on > 0.5:
        if u < u_dump - 1.0:
            dump_on = 0.0
    elif u > u_dump:
        dump_on = 1.0
    g_src = 1.0 / r_src if u <= u_src else 0.0
    g_dump = 1.0 / r_dump if dump_on > 0.5 else 0.0
    i_motor = p_motor / u if u > 1.0 else p_motor
    k = h / c_bus
    u1 = (u + k * (g_src * u_src - i_motor)) / (1.0 + k * (g_src + g_dump))
    e_dump = g_dump * u1 * u1 * h
    e_supply = g_src * (u_src - u1) * u1 * h
    return u1, dump_on, e_dump, e_supply

"""DC bus: supply source with series resistance behind a diode, bus capacitor, power dump.

``C du/dt = i_src − P_motor/u − i_dump``. The source conducts while ``u < U_src`` (it cannot sink
regenerated energy), the dump resistor switches on above ``U_dump`` and off 1 V below
(docs/model.md §5.4, §10: the UIT monitor integrates the regenerative power). Implicit Euler, stable
for any step.
"""

from __future__ import annotations

from numba import njit

from ..engine.jit import KERNEL, LANE_KERNEL


@njit(cache=True, inline="always")
def bus_constants(c_bus: float, r_src: float, r_dump: float, h: float
                  ) -> tuple[float, float, float, float, float, float, float]:
    """The bus's parameter-only factors for steps of ``h`` [s]: ``k = h/C``, the source and dump
    conductances and ``1/(1 + k·(g_src + g_dump))`` for the four source/dump states (source off
    and dump off, source on, dump on, both), computed once per kernel call for
    :func:`bus_step_prepared` instead of four divisions every 128 µs."""
    k = h / c_bus
    g_src = 1.0 / r_src
    g_dump = 1.0 / r_dump
    return (k, g_src, g_dump, 1.0, 1.0 / (1.0 + k * g_src), 1.0 / (1.0 + k * g_dump),
            1.0 / (1.0 + k * (g_src + g_dump)))


@njit(**KERNEL)
def bus_step(u: float, p_motor: float, u_src: float, c_bus: float, r_src: float, u_dump: float,
             r_dump: float, dump_on: float, h: float):
    """Advance the bus by ``h`` [s]; returns ``(u1, dump_on1, e_dump, e_supply)`` [V, -, J, J]."""
    return bus_step_prepared(u, p_motor, u_src, u_dump, dump_on, h,
                             bus_constants(c_bus, r_src, r_dump, h))


@njit(**LANE_KERNEL, forceinline=True)
def bus_step_prepared(u: float, p_motor: float, u_src: float, u_dump: float, dump_on: float,
                      h: float, kc: tuple[float, float, float, float, float, float, float]):
    """:func:`bus_step` given ``kc = bus_constants(c_bus, r_src, r_dump, h)``; same returns.

    Compiled once and inlined by LLVM into each caller, with numpy's error model
    (``engine.jit.LANE_KERNEL``; docs/architecture.md, "First use and numba's cache").
    """
    k, g_src_on, g_dump_on, inv_den_00, inv_den_10, inv_den_01, inv_den_11 = kc
    if dump_on > 0.5:
        if u < u_dump - 1.0:
            dump_on = 0.0
    elif u > u_dump:
        dump_on = 1.0
    src = u <= u_src
    dump = dump_on > 0.5
    g_src = g_src_on if src else 0.0
    g_dump = g_dump_on if dump else 0.0
    if src:
        inv_den = inv_den_11 if dump else inv_den_10
    else:
        inv_den = inv_den_01 if dump else inv_den_00
    i_motor = p_motor / u if u > 1.0 else p_motor
    u1 = (u + k * (g_src * u_src - i_motor)) * inv_den
    e_dump = g_dump * u1 * u1 * h
    e_supply = g_src * (u_src - u1) * u1 * h
    return u1, dump_on, e_dump, e_supply

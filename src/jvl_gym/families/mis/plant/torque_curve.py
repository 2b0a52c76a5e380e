"""The steady-state pull-out torque of the plant at a speed (its speed–torque curve).

With the rotor turning synchronously at ``ω`` behind the commanded field by the electrical
angle ``δ``, the chopper of ``plant`` settles to the current ``i = (v − e)/(R + jωe·L)`` where
``v`` is its deadbeat voltage limited to the supply and ``e = j·Kt·ω·e^{jδ}`` the back-EMF
(the frame of the commanded angle). The torque ``Kt·Im(i·e^{−jδ})`` is largest at some lag
``δ``; that maximum is the pull-out torque: a steady load above it cannot be carried at this
speed (steps are lost), one below it can. At standstill it is the holding torque at the
current (§5.1.6: "the torque produced is proportional to the current setup at low speeds").
"""

from __future__ import annotations

import math

import numpy as np

from .. import constants as c

__all__ = ["pull_out_torque"]


def pull_out_torque(rpm: float, amplitude: float, kt: float, resistance: float,
                    inductance: float, supply: float, lags: int = 721,
                    iterations: int = 400) -> float:
    """Pull-out torque [N·m] at ``rpm`` with the current amplitude ``amplitude`` [A].

    Parameters
    ----------
    rpm : float
        Synchronous speed [RPM].
    amplitude : float
        Current amplitude the chopper aims at [A] (√2 × the RMS setting).
    kt, resistance, inductance, supply : float
        Torque constant [N·m/A], phase resistance [Ω], inductance [H], supply [V].
    lags, iterations : int
        Grid of lag angles over (−π, 0] and fixed-point iterations of the chopper's steady
        state at each.
    """
    omega = rpm * 2.0 * math.pi / 60.0
    we = c.POLE_PAIRS * omega
    h = c.INNER_DT
    z = resistance + 1j * we * inductance
    a = math.exp(-resistance / inductance * h) * np.exp(-1j * we * h)
    b = (1.0 - a) / z
    delta = np.linspace(-math.pi, 0.0, lags)
    e = 1j * kt * omega * np.exp(1j * delta)
    i = np.full(lags, amplitude, dtype=complex)
    for _ in range(iterations):
        v = (amplitude - a * i) / b + e
        mag = np.abs(v)
        v = v * np.minimum(1.0, supply / np.maximum(mag, 1e-300))
        i = a * i + b * (v - e)
    torque = kt * np.imag(i * np.exp(-1j * delta))
    return float(torque.max())

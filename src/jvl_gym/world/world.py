"""World: the open-loop signal sources of a MotorArray, sampled once per outer sample."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..families.capability import motors_of
from .analog import AnalogInput
from .pulse import PulseInput
from .supply import SupplyEvents

if TYPE_CHECKING:
    from ..motor.array import MotorArray


class World:
    """Sources driving the inputs of a :class:`~jvl_gym.MotorArray`.

    Attach with ``m.world = World(pulse=..., analog=..., supply=...)``; each ``m.step(n)`` then
    asks the world for n samples of every driven input. Inputs without a source keep the value
    set by ``m.set_input``. ``load_torque`` may be a callable ``f(t) -> (N,)`` [N·m].
    """

    def __init__(self, pulse: PulseInput | None = None, analog: AnalogInput | None = None,
                 supply: SupplyEvents | None = None, load_torque=None) -> None:
        self.pulse = pulse
        self.analog = analog
        self.supply = supply
        self.load_torque = load_torque
        self.t = 0.0

    def schedule(self, m: MotorArray, n_outer: int) -> np.ndarray:
        """Inputs for the next ``n_outer`` outer samples, shape (n_outer, N, inputs) (the
        columns of the motors' world inputs, ``MotorArray.INPUTS``)."""
        col = m.INPUTS  # world-input name -> column of the motors' inputs
        for name, source in (("pulse_counts", self.pulse), ("analog_volts", self.analog),
                             ("supply_volts", self.supply), ("load_torque", self.load_torque)):
            if source is not None and name not in col:
                raise ValueError(f"this world drives {name!r}, which {motors_of(m.family.title)} "
                                 f"do not have; their inputs: {', '.join(col)}")
        out = np.repeat(m.inputs[None, :, :], n_outer, axis=0)
        dt = 1.0 / m.OUTER_HZ
        decoding = m.pulse_decoding() if self.pulse is not None else None
        for k in range(n_outer):
            if self.pulse is not None:
                out[k, :, col["pulse_counts"]] = self.pulse.advance(dt, *decoding)
            if self.analog is not None:
                out[k, :, col["analog_volts"]] = self.analog.advance(dt)
            if self.supply is not None:
                out[k, :, col["supply_volts"]] = self.supply.advance(dt)
            if self.load_torque is not None:
                out[k, :, col["load_torque"]] = self.load_torque(self.t)
            self.t += dt
        return out

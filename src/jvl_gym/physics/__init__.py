"""Physics and fixed-point arithmetic that several motor families share (no registers).

:mod:`.fixed` (the firmware's rounding, saturation, 32-bit wrap and fixed-point reads),
:mod:`.coil` (the three-phase PMSM coil), :mod:`.mechanics` (rigid rotor, two-mass coupling,
end stops), :mod:`.bus` (the DC bus with its supply and dump resistor) and :mod:`.profile`
(the braking distance and landing speed of a sampled profile). Every function is a compiled
scalar kernel; a family's firmware and plant import them, and no family imports another.
"""

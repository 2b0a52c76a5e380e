"""Physics of an MIS/SMC step motor and its surroundings: the two-phase hybrid step motor with
its chopper, rotor and load (:mod:`.stepper`) and the steady-state pull-out torque
(:mod:`.torque_curve`)."""

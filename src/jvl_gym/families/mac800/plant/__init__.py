"""Physics of a MAC800 and its surroundings that is its own: encoder (8000 counts/rev, index
pulse) and the winding temperature; the PMSM coil, mechanics and DC bus are the shared kernels
of :mod:`jvl_gym.physics`."""

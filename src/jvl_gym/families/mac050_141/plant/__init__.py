"""Physics of the MAC050–141 that is its own: the encoder and the Hall sensors.

The coil electrics, mechanics and DC bus are the shared kernels of :mod:`jvl_gym.physics`.
Every function here is a compiled scalar kernel for one motor and one inner sample.
"""

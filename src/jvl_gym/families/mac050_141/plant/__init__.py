"""Physics of the motor and its surroundings: coil electrics, mechanics, encoder, supply.

Every function here is a compiled scalar kernel for one motor and one inner sample; the
simulator's kernel calls them for every motor of the array.
"""

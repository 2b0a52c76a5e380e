"""What the CANopen slave needs to know of a motor family: the family's record says it.

The slave (:mod:`.slave`) reads and writes a motor only through the :class:`~jvl_gym.MotorArray`
register API; which registers, bits, modes and commands it uses, and the identity objects it
serves, is the family's :class:`~jvl_gym.families.CanopenSpec` (``Family.canopen``), present
where the family declares :attr:`~jvl_gym.families.Capability.CANOPEN`. :func:`facts_of` gives
it with every register looked up by name in the motors' register table.
"""

from __future__ import annotations

from typing import Any

from ...families import CanopenSpec, Capability

__all__ = ["CanopenFacts", "facts_of", "has_canopen"]

#: a family's CANopen facts with its registers by number (:meth:`CanopenSpec.numbered`)
CanopenFacts = CanopenSpec


def has_canopen(motors: Any) -> bool:
    """Whether ``motors``' family declares a CANopen slave (:attr:`Capability.CANOPEN`)."""
    return bool(motors.family.supports(Capability.CANOPEN))


def facts_of(motors: Any) -> CanopenFacts:
    """The CANopen facts of ``motors`` (a :class:`~jvl_gym.MotorArray`), registers by number.

    Raises
    ------
    UnsupportedOperation
        The family declares no CANopen slave.
    ValueError
        Its table lacks a register the slave uses (one line).
    """
    fam = motors.family
    fam.require(Capability.CANOPEN)
    if fam.canopen is None:
        raise ValueError(f"the {fam.title} declare Capability.CANOPEN but state no "
                         "CanopenSpec (Family.canopen)")
    spec: CanopenFacts = fam.canopen.numbered(motors.table)
    return spec

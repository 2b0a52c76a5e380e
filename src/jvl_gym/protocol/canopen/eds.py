"""The EDS file (electronic data sheet, MIS manual §11.2.3) of a family's simulated motors,
written from the same object dictionary the slave serves (:func:`~.objects.build_dictionary`).

A family with a CANopen slave ships it where its record says (``Family.canopen.eds``,
:func:`shipped_path`); :func:`eds_text` writes it afresh, with a fixed file date so that the same
dictionary always gives the same bytes, and ``tests/test_canopen_eds.py`` checks that the
shipped file is that text and loads in the ``canopen`` package without warnings.
``python -m jvl_gym.protocol.canopen.eds`` rewrites the file of every such family.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import TYPE_CHECKING, Any

from canopen.objectdictionary import ObjectDictionary
from canopen.objectdictionary.eds import export_eds

if TYPE_CHECKING:
    from ...families import Family

__all__ = ["eds_text", "shipped_path", "served_dictionary", "FILE_INFO", "write_shipped"]

#: the [FileInfo] of a generated file (fixed, so the text depends on the dictionary alone;
#: ``FileName`` and ``Description`` come from the family)
FILE_INFO = {"FileVersion": 1, "FileRevision": 0, "EdsVersion": "4.0",
             "CreationDate": "12-03-2026", "CreationTime": "12:00PM",
             "ModificationDate": "12-03-2026", "ModificationTime": "12:00PM",
             "CreatedBy": "jvl_gym", "ModifiedBy": "jvl_gym"}


def _family(family: Family | None) -> Family:
    from ...families import Capability, families_with

    if family is None:
        return families_with(Capability.CANOPEN)[0]
    family.require(Capability.CANOPEN)
    return family


def eds_text(od: ObjectDictionary, family: Family | None = None) -> str:
    """The EDS text of ``od``, the dictionary of ``family``'s slave (default: the first
    registered family with a CANopen slave)."""
    fam = _family(family)
    out = io.StringIO()
    info = {"FileName": shipped_path(fam).name,
            "Description": f"JVL {fam.title}, simulated by jvl_gym", **FILE_INFO}
    export_eds(od, out, file_info=info)
    return out.getvalue()


def shipped_path(family: Family | None = None) -> Path:
    """Path of the EDS file ``family`` ships (``Family.canopen.eds``; default: the first
    registered family with a CANopen slave).

    Raises
    ------
    UnsupportedOperation
        The family has no CANopen slave.
    ValueError
        It ships no EDS file.
    """
    fam = _family(family)
    assert fam.canopen is not None  # a family declaring CANOPEN states its CanopenSpec
    if fam.canopen.eds is None:
        raise ValueError(f"the {fam.title} ship no EDS file")
    return fam.canopen.eds


def served_dictionary(family: Family | None = None) -> ObjectDictionary:
    """The object dictionary a slave of ``family``'s first motor type serves."""
    from ...motor.array import MotorArray
    from .facts import facts_of
    from .objects import build_dictionary

    fam = _family(family)
    m: Any = MotorArray(fam.motor_types()[0], n=1)
    return build_dictionary(m.table, facts_of(m))


def write_shipped(family: Family | None = None) -> Path:
    """Write ``family``'s EDS file afresh from its served dictionary; its path."""
    fam = _family(family)
    path = shipped_path(fam)
    path.write_text(eds_text(served_dictionary(fam), fam), encoding="utf-8")
    return path


if __name__ == "__main__":  # pragma: no cover
    from ...families import Capability, families_with

    for fam in families_with(Capability.CANOPEN):
        print(write_shipped(fam))

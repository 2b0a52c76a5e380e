"""The EDS file (electronic data sheet, MIS manual §11.2.3) of the simulated MIS, written from
the same object dictionary the slave serves (:func:`~.objects.build_dictionary`).

The package ships it as ``mis.eds`` (:func:`shipped_path`); :func:`eds_text` writes it afresh,
with a fixed file date so that the same dictionary always gives the same bytes, and
``tests/test_canopen_eds.py`` checks that the shipped file is that text and loads in the
``canopen`` package without warnings. ``python -m jvl_gym.protocol.canopen.eds`` rewrites it.
"""

from __future__ import annotations

import io
from importlib import resources
from pathlib import Path
from typing import Any

from canopen.objectdictionary import ObjectDictionary
from canopen.objectdictionary.eds import export_eds

__all__ = ["eds_text", "shipped_path", "FILE_INFO", "write_shipped"]

#: the [FileInfo] of the generated file (fixed, so the text depends on the dictionary alone)
FILE_INFO = {"FileName": "mis.eds", "FileVersion": 1, "FileRevision": 0, "EdsVersion": "4.0",
             "Description": "JVL MIS/SMC integrated step motor, simulated by jvl_gym",
             "CreationDate": "12-03-2026", "CreationTime": "12:00PM",
             "ModificationDate": "12-03-2026", "ModificationTime": "12:00PM",
             "CreatedBy": "jvl_gym", "ModifiedBy": "jvl_gym"}


def eds_text(od: ObjectDictionary) -> str:
    """The EDS text of ``od``."""
    out = io.StringIO()
    export_eds(od, out, file_info=dict(FILE_INFO))
    return out.getvalue()


def shipped_path() -> Path:
    """Path of the EDS file shipped in this package."""
    return Path(str(resources.files(__package__).joinpath("mis.eds")))


def _mis_dictionary() -> ObjectDictionary:
    from ...sim import MotorArray
    from .facts import facts_of
    from .objects import build_dictionary

    m: Any = MotorArray("MIS232", n=1)
    return build_dictionary(m.table, facts_of(m))


def write_shipped() -> Path:
    """Write the shipped EDS file afresh from the dictionary of an MIS232; its path."""
    path = shipped_path()
    path.write_text(eds_text(_mis_dictionary()), encoding="utf-8")
    return path


if __name__ == "__main__":  # pragma: no cover
    print(write_shipped())

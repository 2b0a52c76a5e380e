"""The EDS file shipped with the simulated MIS (MIS manual §11.2.3): the text generated from
the dictionary the slave serves, loaded by ``canopen`` without warnings, entry for entry the
served dictionary."""

from __future__ import annotations

import logging
import warnings

import canopen
import pytest

from jvl_gym import MotorArray
from jvl_gym.protocol.canopen.eds import eds_text, shipped_path
from jvl_gym.protocol.canopen.facts import facts_of
from jvl_gym.protocol.canopen.objects import build_dictionary


@pytest.fixture(scope="module")
def served() -> canopen.ObjectDictionary:
    m = MotorArray("MIS232", n=1)
    return build_dictionary(m.table, facts_of(m))


def test_shipped_file_is_a_fresh_generation(served: canopen.ObjectDictionary) -> None:
    assert shipped_path().read_text(encoding="utf-8") == eds_text(served)


def test_shipped_file_loads_without_warnings_and_matches(
        served: canopen.ObjectDictionary, caplog: pytest.LogCaptureFixture) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with caplog.at_level(logging.WARNING):
            od = canopen.import_od(str(shipped_path()), 5)
    assert not [r for r in caplog.records if r.levelno >= logging.WARNING]
    assert sorted(od) == sorted(served)
    count = 0
    for index in served:
        a, b = served[index], od[index]
        assert a.name == b.name
        for va, vb in ([(a, b)] if hasattr(a, "data_type") else
                       [(a[s], b[s]) for s in a]):
            assert (va.name, va.data_type, va.access_type, va.pdo_mappable, va.min, va.max) == \
                   (vb.name, vb.data_type, vb.access_type, vb.pdo_mappable, vb.min, vb.max)
            assert vb.default == (va.default + 5 if va.relative else va.default)
            count += 1
    assert count > 1000
    info = od.device_information
    assert info.vendor_number == 0x117 and info.LSS_supported


def test_eds_names_the_registers(served: canopen.ObjectDictionary) -> None:
    """2012h sub n is register n, by its name in the register table (§11.4.6)."""
    assert served[0x2012][3].name == "P_SOLL" and served[0x2014][35].name == "ERR_BITS"
    assert served[0x2018][1].name == "Register 257"

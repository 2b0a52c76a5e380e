"""The conformance matrix of every family (``families/<key>/conformance.yaml``): every register
has an entry, every documented bit and value the family's constants name has one, every
*modelled* entry names tests that exist and touch its register, and writing a value other than
the default to a *not modelled* register or bit warns once, is logged, and is stored."""

from __future__ import annotations

import ast
import logging
import re
import warnings
from functools import cache
from pathlib import Path

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mac050_141 import constants as c050
from jvl_gym.families.mac050_141.table import CONFORMANCE as C050
from jvl_gym.families.mac800 import constants as c800
from jvl_gym.families.mac800.table import CONFORMANCE as C800
from jvl_gym.families.mis import constants as cmis
from jvl_gym.families.mis.table import CONFORMANCE as CMIS
from jvl_gym.registers import (
    Conformance,
    ConformanceError,
    NotModelledWarning,
    Register,
    load_packaged_conformance,
)
from jvl_gym.registers.conformance import MODELLED, NOT_MODELLED, STORED_ONLY

TESTS = Path(__file__).parent
FAMILIES = {"mac050_141": C050, "mac800": C800, "mis": CMIS}


@cache
def _test_sources(filename: str) -> dict[str, str]:
    """Test name → its source with its decorators and the module-level helpers and constants
    it uses."""
    src = (TESTS / filename).read_text(encoding="utf-8")
    tree = ast.parse(src)
    helpers = {n.name: ast.get_source_segment(src, n) or "" for n in tree.body
               if isinstance(n, ast.FunctionDef) and not n.name.startswith("test_")}
    for n in tree.body:
        if isinstance(n, (ast.Assign, ast.AnnAssign)):
            for target in (n.targets if isinstance(n, ast.Assign) else [n.target]):
                if isinstance(target, ast.Name):
                    helpers[target.id] = ast.get_source_segment(src, n) or ""
    out = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name.startswith("test_"):
            used = {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}
            out[node.name] = "".join(
                [*(ast.get_source_segment(src, d) or "" for d in node.decorator_list),
                 ast.get_source_segment(src, node) or "",
                 *(helpers[h] for h in sorted(used) if h in helpers)])
    return out


def _touches(test_id: str, reg: Register) -> bool:
    filename, _, name = test_id.partition("::")
    if not (TESTS / filename).is_file():
        return False
    src = _test_sources(filename).get(name)
    if src is None:
        return False
    names = [reg.name] + ([reg.alias] if reg.alias and reg.alias.isidentifier() else [])
    return any(re.search(rf"\b{re.escape(n)}\b", src) for n in names) or bool(
        re.search(rf"(?<![\w.]){reg.number}(?![\w.])", src))


@pytest.mark.parametrize("key", list(FAMILIES))
def test_every_register_has_an_entry(key: str) -> None:
    conf = FAMILIES[key]
    assert conf.missing() == []
    assert conf.reserved is not None and conf.reserved.status == NOT_MODELLED


@pytest.mark.parametrize("key", list(FAMILIES))
def test_every_modelled_entry_names_tests_that_touch_its_register(key: str) -> None:
    conf = FAMILIES[key]
    bad = []
    for num, entry in conf.entries.items():
        reg = conf.table.lookup(num)
        subs = [(f"{reg.name}", entry)] + [
            (f"{reg.name} {kind} {k}", sub) for kind, group in
            (("bit", entry.bits), ("value", entry.values)) for k, sub in group.items()]
        for what, e in subs:
            if e.status != MODELLED:
                continue
            assert e.tests, what
            bad += [f"{what}: {t}" for t in e.tests if not _touches(t, reg)]
    assert bad == []


def _bits(module, names: list[str]) -> set[int]:
    return {getattr(module, n).bit_length() - 1 for n in names}


#: the bits and values each family's constants name, by register (the documented ones the
#: firmware knows): each must be in the matrix
_NAMED = {
    ("mis", "STATUSBITS"): _bits(cmis, [n for n in dir(cmis) if n.startswith("ST_")]),
    ("mis", "ERR_BITS"): _bits(cmis, [n for n in dir(cmis) if n.startswith("ERR_")]),
    ("mis", "WARN_BITS"): _bits(cmis, [n for n in dir(cmis) if n.startswith("WARN_")]),
    ("mis", "SETUP_BITS"): _bits(cmis, [n for n in dir(cmis) if n.startswith("SETUP_")]),
    ("mis", "MODE_REG"): set(cmis.MODE_NAMES),
    ("mis", "COMMAND"): {getattr(cmis, n) for n in dir(cmis) if n.startswith("CMD_")
                         and isinstance(getattr(cmis, n), int)}
    | set(cmis.CMD_REGISTER_SET) | set(cmis.CMD_RELATIVE),
    ("mis", "TURNTABLE_MODE"): {cmis.TT_OFF, cmis.TT_CW, cmis.TT_CCW, cmis.TT_SHORTEST,
                                cmis.TT_MULTI_CW, cmis.TT_MULTI_CCW},
    ("mac800", "ERR_STAT"): _bits(c800, [n for n in dir(c800) if n.endswith(("_ERR", "_FLAG"))]
                                  + ["IN_POS", "UV_DETECT", "DIS_P_LIM"]),
    ("mac800", "CNTRL_BITS"): _bits(c800, ["RECORDBIT", "REWINDBIT", "RECINNERBIT",
                                           "RELPOSPSOLL", "RELPOSPFNC", "SYNCPOSAUTO",
                                           "SYNCPOSMAN", "MAN_NO_BRAKE", "SYNCPOSREL",
                                           "INDEX_HOME"]),
    ("mac800", "UV_HANDLE"): _bits(c800, ["SET_UV_ERR", "UV_GO_PASSIVE", "UV_VSOLL0"]),
    ("mac800", "HW_SETUP"): _bits(c800, ["DIRAWR", "DIRBWR", "PULSEOUT", "XSEL1", "XPRINP",
                                         "NOFILT", "INVXDIR"]),
    ("mac800", "HOME_MODE"): _bits(c800, ["HOME_DONE"]),
    ("mac800", "MODE_REG"): set(c800.MODE_NAMES),
    ("mac050_141", "MODE_REG"): set(c050.MODE_NAMES),
    ("mac050_141", "ERR_STAT"): _bits(c050, ["I2T_ERR", "FLW_ERR", "FNC_ERR", "UIT_ERR",
                                             "IN_POS", "ACC_FLAG", "DEC_FLAG", "PLIM_ERR",
                                             "FRAME_ERR_TX", "RELPOSPSOLL", "RELPOSPFNC",
                                             "IX_ERR", "UV_ERR", "UV_DETECT", "DIS_P_LIM"]),
    ("mac050_141", "CNTRL_BITS"): _bits(c050, ["PULSEDIR", "INPSIGN", "HICLK", "HALL_INT",
                                               "RECORDBIT", "REWINDBIT", "RECINNERBIT",
                                               "AUTO_RESYNC", "MAN_RESYNC", "INDEX_HOME",
                                               "REL_RESYNC"]),
}


@pytest.mark.parametrize("key, name", list(_NAMED))
def test_every_named_bit_and_value_has_an_entry(key: str, name: str) -> None:
    conf = FAMILIES[key]
    entry = conf.entries[conf.table.lookup(name).number]
    documented = set(entry.bits) | set(entry.values)
    assert _NAMED[key, name] - documented == set()


def test_counts_per_family() -> None:
    """Every register is counted once; the reference pages show the same statuses."""
    for conf in FAMILIES.values():
        counts = conf.counts()
        assert sum(counts.values()) == len(conf.entries)
        assert counts[MODELLED] > 0 and counts[STORED_ONLY] > 0


def test_a_modelled_entry_without_tests_or_a_bad_status_is_refused() -> None:
    table = CMIS.table
    for data, match in (({"registers": {"V_SOLL": {"status": "modelled"}}}, "names its tests"),
                        ({"registers": {"V_SOLL": {"status": "maybe"}}}, "status"),
                        ({"registers": {"V_SOLL": {"status": "not modelled"}}}, "says why"),
                        ({"registers": {"NO_SUCH": {"status": "modelled"}}}, "NO_SUCH"),
                        ({"registers": {"SETUP_BITS": {"status": "stored only", "why": "x",
                                                       "bits": {40: {"status": "modelled",
                                                                     "tests": ["a.py::b"]}}}}},
                         "bit number")):
        with pytest.raises(ConformanceError, match=match):
            Conformance(table, data, "<test>")
    assert load_packaged_conformance("jvl_gym.families.mis", table).counts() == CMIS.counts()


# --- writing a not-modelled register or bit -------------------------------------------------
def test_a_non_default_write_to_a_not_modelled_register_warns_once_logs_and_is_stored(
        caplog) -> None:
    m = MotorArray("MIS232", n=2, seed=0)
    assert CMIS.entries[m.table.lookup("CONTROL_WORD").number].status == NOT_MODELLED
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m.write("CONTROL_WORD", 0)  # the default: no warning
        m.write("SETUP_BITS", cmis.SETUP_INVERT_DIRECTION)  # a modelled bit: no warning
    with caplog.at_level(logging.WARNING, logger="jvl_gym.conformance"), \
            pytest.warns(NotModelledWarning, match=r"CONTROL_WORD \(register 180\).*8\.2\.1"):
        m.write("CONTROL_WORD", 0x0501)
    assert m.read("CONTROL_WORD").tolist() == [0x0501, 0x0501]
    assert any("CONTROL_WORD" in r.getMessage() for r in caplog.records)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m.write("CONTROL_WORD", 0x0702)  # once per register
    mac = MotorArray("MAC050", n=1)
    with pytest.warns(NotModelledWarning, match="CNTRL_BITS"):
        mac.write_many({"V_SOLL": 200, "CNTRL_BITS": 1 << 4})  # a bit not modelled
    assert int(mac.read_raw("CNTRL_BITS")[0]) & 1 << 4
    with pytest.warns(NotModelledWarning, match="IA_OFFSET"):
        MotorArray("MAC050", n=1).write("IA_OFFSET", 1000)


def test_the_twin_logs_a_not_modelled_write(caplog) -> None:
    from jvl_gym.protocol.mactalk import codec32 as m32
    from jvl_gym.protocol.mactalk.twin16 import Twin

    m = MotorArray("MIS232", n=1, seed=0)
    twin = Twin(m)
    frame = m32.encode_write_value(int(m.read("MY_ADDR")[0]), 180, 0x0301)
    with caplog.at_level(logging.WARNING), warnings.catch_warnings():
        warnings.simplefilter("ignore", NotModelledWarning)
        twin.session().feed(frame)
    assert m.read("CONTROL_WORD")[0] == 0x0301
    assert any("CONTROL_WORD" in r.getMessage() and "not modelled" in r.getMessage()
               for r in caplog.records)


def test_default_setups_and_the_envs_registers_do_not_warn() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", NotModelledWarning)
        for motor in ("MAC140", "MAC800", "MAC400", "MIS232"):
            m = MotorArray(motor, n=1, seed=0)
            m.write_many({"V_SOLL": int(m.read("V_SOLL")[0]) + 1})
            assert np.isfinite(m.read("V_SOLL")).all()

"""The layers keep to their interfaces (docs/architecture.md), checked over the whole tree: the
generic code (every module of ``src/jvl_gym`` outside a family folder, and ``tuning``) imports
no family module (``importlib`` loads included), compares against no family key or motor-type
name (the registry's data aside) and uses no private ``MotorArray`` member; no family imports
another family; nothing of ``jvl_gym`` imports ``tuning``. The rules are
``tests/architecture_rules.py``; a planted violation under ``tests/fixtures/architecture`` shows
that each one fires."""

from __future__ import annotations

from pathlib import Path

import pytest

from architecture_rules import (
    ARRAY_PARTS,
    REGISTRY,
    ROOT,
    Violation,
    check_family_imports,
    check_generic_imports,
    check_names,
    check_private_members,
    family_files,
    family_keys,
    generic_files,
)
from jvl_gym.families import families, family

FIXTURES = Path(__file__).resolve().parent / "fixtures" / "architecture"

#: generic modules that still break a rule while the work that removes the breach is under
#: way, with that work; an entry whose file keeps to every rule fails
#: :func:`test_the_pending_list_holds_only_files_that_break_a_rule`, so the list only shrinks
PENDING: dict[str, str] = {}


def _names() -> frozenset[str]:
    """The registered families' keys and motor-type names."""
    return frozenset(families()) | frozenset(t for k in families()
                                             for t in family(k).motor_types())


def _violations(path: Path) -> list[Violation]:
    out = check_generic_imports(path)
    if path not in REGISTRY:
        out += check_names(path, _names())
    if path not in ARRAY_PARTS:
        out += check_private_members(path)
    return out


def _rel(path: Path) -> str:
    return str(path.relative_to(ROOT))


@pytest.mark.parametrize("path", [p for p in generic_files() if _rel(p) not in PENDING],
                         ids=_rel)
def test_generic_code_knows_no_family(path: Path) -> None:
    found = _violations(path)
    assert not found, "\n".join(map(str, found))


@pytest.mark.parametrize("key", family_keys())
def test_no_family_imports_another_family(key: str) -> None:
    found = [v for path in family_files(key) for v in check_family_imports(path, key)]
    assert not found, "\n".join(map(str, found))


def test_the_pending_list_holds_only_files_that_break_a_rule() -> None:
    for name in PENDING:
        path = ROOT / name
        assert path.is_file() and _violations(path), (
            f"{name} keeps to every rule now: remove it from PENDING")


def test_the_tree_is_covered() -> None:
    """Every package of jvl_gym outside the family folders is scanned, and tuning."""
    scanned = {p.relative_to(ROOT).parts[:3] for p in generic_files()}
    for layer in ("envs", "protocol", "scale", "rl", "world", "engine", "registers", "physics"):
        assert ("src", "jvl_gym", layer) in scanned, layer
    assert any(p.name == "sim.py" for p in generic_files())
    assert any(p.parts[-2] == "tuning" for p in generic_files())
    assert not any("mac050_141" in p.parts for p in generic_files())


# ------------------------------------------------------------------ the rules fire
def test_a_planted_generic_violation_is_caught() -> None:
    bad = FIXTURES / "bad_layer.py"
    found = {v.what for v in check_generic_imports(bad, "jvl_gym.envs")}
    assert any("jvl_gym.families.mac050_141.kernel" in w for w in found)
    assert any("jvl_gym.families.mis.firmware.regs" in w for w in found)  # an importlib load
    assert any("tuning.synthesis" in w for w in found)
    compared = {v.what.split("'")[1] for v in check_names(bad, _names())}
    assert compared == {"mac800", "MAC140", "MIS232", "mis"}
    assert [v.what for v in check_private_members(bad)] == [
        "uses motors._store, a private MotorArray member"]


def test_a_planted_cross_family_import_is_caught() -> None:
    bad = FIXTURES / "bad_family.py"
    found = check_family_imports(bad, "mac800", "jvl_gym.families.mac800.firmware")
    assert [v.what for v in found] == [
        "imports jvl_gym.families.mac050_141.firmware.blocks: family mac800 imports family "
        "mac050_141",
        "imports jvl_gym.families.mac050_141.firmware.blocks.max_landing_speed: family mac800 "
        "imports family mac050_141"]
    assert not check_family_imports(bad, "mac050_141", "jvl_gym.families.mac050_141.firmware")

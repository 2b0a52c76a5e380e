"""The layers keep to their interfaces (docs/architecture.md), checked over the whole tree: the
generic code (every module of ``src/jvl_gym`` outside a family folder, and ``tuning``) imports
no family module (``importlib`` loads included), compares against no family key or motor-type
name (the registry's data aside) and uses no private ``MotorArray`` member; no family imports
another family; nothing of ``jvl_gym`` imports ``tuning``. The layout is by concept: the top of
``src/jvl_gym`` holds packages only; no bus's folder imports another bus's; the motor array's
package imports none of the layers that use it; and there is no import circle in ``src`` and
``tuning`` (every import counts: in a function, under ``TYPE_CHECKING``, by ``importlib``). The
rules are ``tests/architecture_rules.py``; a planted violation under
``tests/fixtures/architecture`` shows that each one fires."""

from __future__ import annotations

from pathlib import Path

import pytest

from architecture_rules import (
    ARRAY_PARTS,
    MOTOR,
    PACKAGE,
    REGISTRY,
    ROOT,
    Violation,
    bus_files,
    check_bus_imports,
    check_family_imports,
    check_generic_imports,
    check_motor_imports,
    check_names,
    check_private_members,
    family_files,
    family_keys,
    generic_files,
    import_cycles,
    import_graph,
    source_files,
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
    for layer in ("envs", "protocol", "scale", "rl", "world", "engine", "registers", "physics",
                  "motor", "cli", "studio"):
        assert ("src", "jvl_gym", layer) in scanned, layer
    assert MOTOR / "array.py" in generic_files()
    assert any(p.parts[-2] == "tuning" for p in generic_files())
    assert not any("mac050_141" in p.parts for p in generic_files())


def test_the_top_level_holds_packages_only() -> None:
    """``src/jvl_gym`` holds ``__init__.py`` and packages (docs/architecture.md)."""
    assert sorted(p.name for p in PACKAGE.glob("*.py")) == ["__init__.py"]
    assert all((p / "__init__.py").is_file() for p in PACKAGE.iterdir()
               if p.is_dir() and p.name != "__pycache__")


def test_no_import_circles() -> None:
    cycles = import_cycles(import_graph(source_files()))
    assert not cycles, "import circles:\n" + "\n".join(" ↔ ".join(c) for c in cycles)


@pytest.mark.parametrize("path", bus_files(), ids=_rel)
def test_no_bus_imports_another_bus(path: Path) -> None:
    found = check_bus_imports(path)
    assert not found, "\n".join(map(str, found))


@pytest.mark.parametrize("path", sorted(MOTOR.rglob("*.py")), ids=_rel)
def test_the_motor_array_is_below_its_users(path: Path) -> None:
    found = check_motor_imports(path)
    assert not found, "\n".join(map(str, found))


# ------------------------------------------------------------------ the rules fire
def test_a_planted_import_circle_is_caught() -> None:
    circle = sorted((FIXTURES / "circle").glob("*.py"))
    graph = import_graph(circle)
    assert import_cycles(graph) == [[f"tests.fixtures.architecture.circle.{m}"
                                     for m in ("a", "b", "c")]]
    # without the module that closes it, no circle
    assert import_cycles(import_graph([p for p in circle if p.stem != "c"])) == []


def test_a_planted_bus_and_motor_violation_is_caught() -> None:
    bad = FIXTURES / "bad_bus.py"
    found = [v.what for v in check_bus_imports(bad, "jvl_gym.protocol.modbus")]
    assert found == ["imports jvl_gym.protocol.mactalk.twin32.MacTalk32Unit: bus modbus imports "
                     "bus mactalk"]
    found = [v.what for v in check_motor_imports(bad, "jvl_gym.motor")]
    assert found == ["imports jvl_gym.protocol.errors.FrameError: the motor array is below "
                     "jvl_gym.protocol, which uses it",
                     "imports jvl_gym.protocol.mactalk.twin32.MacTalk32Unit: the motor array is "
                     "below jvl_gym.protocol, which uses it",
                     "imports jvl_gym.protocol.serving.twin.MotorTwin: the motor array is below "
                     "jvl_gym.protocol, which uses it",
                     "imports jvl_gym.envs.base.MotorVectorEnv: the motor array is below "
                     "jvl_gym.envs, which uses it"]
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

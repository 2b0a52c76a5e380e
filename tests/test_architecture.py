"""The layers keep to their interfaces (docs/architecture.md): the generic layers reach a motor
family only through its public modules, and nothing outside the simulator calls a private
``MotorArray`` method."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
#: layers that must not know a family's internals
GENERIC = [SRC / "jvl_gym" / "envs", SRC / "jvl_gym" / "protocol", SRC / "jvl_gym" / "world",
           SRC / "jvl_gym" / "studio", ROOT / "tuning"]
#: what a family shows the other layers: its package, units and constants, register table,
#: task interface
PUBLIC = {"constants", "table", "task", "config"}
#: names under which the generic layers hold a MotorArray
ARRAY_NAMES = re.compile(r"\b(?:motors|m|sim|array)\._[a-z]\w*\b")


def _files() -> list[Path]:
    return sorted(p for folder in GENERIC for p in folder.rglob("*.py"))


def _imported_modules(path: Path, package: str | None = None) -> list[str]:
    """Absolute names of the modules ``path`` imports (relative imports resolved from
    ``package``, by default the package of ``path``)."""
    tree = ast.parse(path.read_text())
    if package is None and path.is_relative_to(SRC):
        package = ".".join(path.relative_to(SRC).with_suffix("").parts[:-1])
    elif package is None:
        package = "tuning"
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            base = package.split(".")
            if node.level:
                base = base[: len(base) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            out.append(module)
            out.extend(f"{module}.{a.name}" for a in node.names)
        elif isinstance(node, ast.Import):
            out.extend(a.name for a in node.names)
    return out


@pytest.mark.parametrize("path", _files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_generic_layers_use_only_a_familys_public_modules(path: Path) -> None:
    for module in _imported_modules(path):
        parts = module.split(".")
        if parts[:2] == ["jvl_gym", "families"] and len(parts) > 3:
            assert parts[3] in PUBLIC, f"{path.name} imports {module}, a family's internals"
        assert parts[:2] not in (["jvl_gym", "kernel"], ["jvl_gym", "lanes"]), module


@pytest.mark.parametrize("path", _files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_generic_layers_call_no_private_motor_array_method(path: Path) -> None:
    found = ARRAY_NAMES.findall(path.read_text())
    assert not found, f"{path.name} uses private MotorArray members: {sorted(set(found))}"


def test_the_rule_sees_a_violation(tmp_path: Path) -> None:
    """The checks above fail on a module that breaks them."""
    bad = tmp_path / "probe.py"
    bad.write_text("from ..families.mac050_141.kernel import outer_firmware\n"
                   "def f(motors):\n    return motors._store\n")
    assert any(m.split(".")[3] not in PUBLIC for m in _imported_modules(bad, "jvl_gym.envs")
               if m.startswith("jvl_gym.families.mac050_141."))
    assert ARRAY_NAMES.findall(bad.read_text())


#: layers that serve every family alike and so name no family at all
FAMILY_BLIND = [SRC / "jvl_gym" / "world", SRC / "jvl_gym" / "engine"]


@pytest.mark.parametrize("path", sorted(p for f in FAMILY_BLIND for p in f.rglob("*.py")),
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_family_blind_layers_import_no_family(path: Path) -> None:
    for module in _imported_modules(path):
        parts = module.split(".")
        assert not (parts[:2] == ["jvl_gym", "families"] and len(parts) > 2
                    and parts[2] not in ("Family", "family", "families")), (
            f"{path.name} imports {module}: a family-blind layer names a family")

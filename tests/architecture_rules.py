"""The rules of docs/architecture.md as checks on source files (used by test_architecture.py).

A source file is read as Python (``ast``), never imported. What a file imports includes the
modules it loads by ``importlib.import_module("<literal>")``. The generic code is every module
of ``src/jvl_gym`` outside a family folder (``families/<key>/``) and the ``tuning`` package;
the registry (``families/__init__.py``) holds the registration data.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
PACKAGE = SRC / "jvl_gym"
FAMILIES = PACKAGE / "families"
#: the modules that hold registration data (family keys by name)
REGISTRY = {FAMILIES / "__init__.py"}
#: the motor array's package (docs/architecture.md, "The motor array")
MOTOR = PACKAGE / "motor"
#: MotorArray's own parts, which may use its private members
ARRAY_PARTS = {MOTOR / name for name in ("array.py", "bank.py", "flash.py", "stepping.py")}
#: the buses, each a folder of ``protocol`` (its codec, client and serving side)
BUSES = ("mactalk", "modbus", "canopen", "sae_j1939", "dmx512")
#: the layers that use the motor array, which it never imports
MOTOR_USERS = ("jvl_gym.envs", "jvl_gym.protocol", "jvl_gym.world", "jvl_gym.studio",
               "jvl_gym.scale", "jvl_gym.rl", "jvl_gym.cli", "tuning")
#: a private member of a MotorArray under the names the generic code holds one by
ARRAY_NAMES = re.compile(r"\b(?:motors|m|sim|array|self\.m|twin\.m|t\.m)\._[a-z]\w*\b")


@dataclass(frozen=True)
class Violation:
    """One broken rule: the file, the line and what is wrong."""

    path: Path
    line: int
    what: str

    def __str__(self) -> str:
        where = self.path.relative_to(ROOT) if self.path.is_relative_to(ROOT) else self.path
        return f"{where}:{self.line}: {self.what}"


def family_keys() -> tuple[str, ...]:
    """The family folders of the package (``families/<key>/__init__.py``)."""
    return tuple(sorted(p.parent.name for p in FAMILIES.glob("*/__init__.py")))


def family_of_path(path: Path) -> str | None:
    """The family whose folder holds ``path``, or None."""
    if path.is_relative_to(FAMILIES):
        parts = path.relative_to(FAMILIES).parts
        if len(parts) > 1 and parts[0] in family_keys():
            return parts[0]
    return None


def generic_files() -> list[Path]:
    """Every module outside a family folder: ``src/jvl_gym`` and the ``tuning`` package."""
    files = [*PACKAGE.rglob("*.py"), *(ROOT / "tuning").rglob("*.py")]
    return sorted(p for p in files if family_of_path(p) is None)


def family_files(key: str) -> list[Path]:
    """The modules of the family folder ``key``."""
    return sorted((FAMILIES / key).rglob("*.py"))


def module_package(path: Path) -> str:
    """The dotted package of the module at ``path`` (``src/`` or the repository root)."""
    base = SRC if path.is_relative_to(SRC) else ROOT
    parts = path.relative_to(base).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] != "__init__" else parts[:-1])


def imports(path: Path, package: str | None = None, *,
            names_only: bool = False) -> Iterator[tuple[int, str]]:
    """(line, absolute module name) of every import of ``path``, relative imports resolved from
    ``package`` (default: the file's own package), each imported name as ``module.name`` too
    (with ``names_only``, only that: ``from m import a`` yields ``m.a`` alone), and every
    ``importlib.import_module("<literal>")`` / ``import_module("<literal>")``."""
    package = module_package(path) if package is None else package
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            if not names_only:
                yield node.lineno, module
            for alias in node.names:
                yield node.lineno, f"{module}.{alias.name}"
        elif isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif (isinstance(node, ast.Call) and node.args
              and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str)
              and (isinstance(node.func, ast.Attribute) and node.func.attr == "import_module"
                   or isinstance(node.func, ast.Name) and node.func.id == "import_module")):
            name = node.args[0].value
            if name.startswith("."):
                pkg = node.args[1].value if len(node.args) > 1 and isinstance(
                    node.args[1], ast.Constant) else package
                level = len(name) - len(name.lstrip("."))
                name = ".".join(pkg.split(".")[: len(pkg.split(".")) - level + 1]
                                + [name.lstrip(".")])
            yield node.lineno, name


def family_imported(module: str) -> str | None:
    """The family a module name belongs to (``jvl_gym.families.<key>…``), or None."""
    parts = module.split(".")
    if parts[:2] == ["jvl_gym", "families"] and len(parts) > 2 and parts[2] in family_keys():
        return parts[2]
    return None


def check_generic_imports(path: Path, package: str | None = None) -> list[Violation]:
    """A generic module imports no family module, and nothing of ``jvl_gym`` imports the
    ``tuning`` package."""
    out = []
    in_package = path.is_relative_to(PACKAGE) if package is None else package.startswith(
        "jvl_gym")
    for line, module in imports(path, package):
        key = family_imported(module)
        if key is not None:
            out.append(Violation(path, line, f"imports {module}: the {key} family's module"))
        if in_package and module.split(".")[0] == "tuning":
            out.append(Violation(path, line, f"imports {module}: jvl_gym never imports tuning"))
    return out


def check_family_imports(path: Path, key: str, package: str | None = None) -> list[Violation]:
    """A module of family ``key`` imports nothing of another family."""
    out = []
    for line, module in imports(path, package):
        other = family_imported(module)
        if other is not None and other != key:
            out.append(Violation(path, line, f"imports {module}: family {key} imports family "
                                             f"{other}"))
    return out


def check_names(path: Path, names: frozenset[str]) -> list[Violation]:
    """No comparison (``==``, ``!=``, ``in``, ``not in``, a ``match`` case) of anything with a
    string constant of ``names`` (family keys and motor-type names)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        consts: list[ast.AST] = []
        if isinstance(node, ast.Compare):
            for side in (node.left, *node.comparators):
                consts.append(side)
                if isinstance(side, (ast.Tuple, ast.List, ast.Set)):
                    consts.extend(side.elts)
        elif isinstance(node, ast.MatchValue):
            consts.append(node.value)
        for c in consts:
            if isinstance(c, ast.Constant) and isinstance(c.value, str) and c.value in names:
                out.append(Violation(path, node.lineno,
                                     f"compares against {c.value!r}, a family key or motor "
                                     "type name"))
    return out


def check_private_members(path: Path) -> list[Violation]:
    """No private member of a MotorArray outside MotorArray's own parts and the families."""
    out = []
    for n, text in enumerate(path.read_text().splitlines(), start=1):
        for found in ARRAY_NAMES.findall(text):
            out.append(Violation(path, n, f"uses {found}, a private MotorArray member"))
    return out


def module_of(path: Path) -> str:
    """The dotted module name of the source file ``path`` (``src/`` or the repository root)."""
    base = SRC if path.is_relative_to(SRC) else ROOT
    parts = path.relative_to(base).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def import_graph(paths: list[Path]) -> dict[str, set[str]]:
    """Module → the modules of ``paths`` it imports: at the top, in a function, under
    ``TYPE_CHECKING`` or by ``import_module("<literal>")`` — every import is a dependency. A
    name imported from a package is its submodule when it has one of that name, else the
    package itself."""
    modules = {module_of(p): p for p in paths}
    graph: dict[str, set[str]] = {name: set() for name in modules}
    for name, path in modules.items():
        for _, imported in imports(path, module_package(path), names_only=True):
            target = imported
            while target and target not in modules:
                target = target.rpartition(".")[0]
            if target and target != name:
                graph[name].add(target)
    return graph


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The import circles of ``graph``: its strongly connected components of more than one
    module (Tarjan), each sorted, and any module that imports itself."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        work = [(v, iter(sorted(graph[v])))]
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        while work:
            node, children = work[-1]
            for w in children:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    break
                if w in on_stack:
                    low[node] = min(low[node], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        component.append(w)
                        if w == node:
                            break
                    if len(component) > 1:
                        cycles.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(cycles)


def source_files() -> list[Path]:
    """Every module of ``src/jvl_gym`` and of the ``tuning`` package."""
    files = [*PACKAGE.rglob("*.py"), *(ROOT / "tuning").rglob("*.py")]
    return sorted(p for p in files if "__pycache__" not in p.parts)


def bus_of(module: str) -> str | None:
    """The bus whose folder holds ``module`` (``jvl_gym.protocol.<bus>…``), or None."""
    parts = module.split(".")
    if parts[:2] == ["jvl_gym", "protocol"] and len(parts) > 2 and parts[2] in BUSES:
        return parts[2]
    return None


def check_bus_imports(path: Path, package: str | None = None) -> list[Violation]:
    """A module of a bus's folder imports nothing of another bus's folder (the shared
    ``protocol.serving`` and ``protocol.errors`` are no bus)."""
    package = module_package(path) if package is None else package
    own = bus_of(package + ".")
    out = []
    for line, module in imports(path, package, names_only=True):
        other = bus_of(module)
        if own is not None and other is not None and other != own:
            out.append(Violation(path, line, f"imports {module}: bus {own} imports bus {other}"))
    return out


def check_motor_imports(path: Path, package: str | None = None) -> list[Violation]:
    """A module of the motor array's package imports none of the layers that use it."""
    package = module_package(path) if package is None else package
    out = []
    for line, module in imports(path, package, names_only=True):
        for user in MOTOR_USERS:
            if module == user or module.startswith(user + "."):
                out.append(Violation(path, line, f"imports {module}: the motor array is below "
                                                 f"{user}, which uses it"))
    return out


def bus_files() -> list[Path]:
    """The modules of every bus's folder."""
    return sorted(p for bus in BUSES for p in (PACKAGE / "protocol" / bus).rglob("*.py"))

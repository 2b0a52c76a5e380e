"""The ``pytest.mark.statements`` markers of the tests, read as source (``ast``, never imported),
and the checks that tie a family's statements (``statements.yaml``) to them and to the docs
(used by test_families_statements.py).

A test is a function ``test_*`` of a module ``test_*.py``, or a method ``test_*`` of a class
``Test*`` in one; its id is ``file.py::name`` (``file.py::Class::name`` for a method). It
carries the ids of its own ``@pytest.mark.statements(...)`` decorators, of its class's, and of
a ``pytestmark = pytest.mark.statements(...)`` (or a list of marks) in its module or class.
"""

from __future__ import annotations

import ast
import re
import unicodedata
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from jvl_gym.registers.statements import Statements


@dataclass
class Markers:
    """The tests of a test tree and the statement ids each carries.

    Attributes
    ----------
    tests : dict
        Test id → the statement ids it carries (empty: a test without the marker).
    problems : list of str
        Markers that cannot be read (an argument that is not a string), as ``file:line: …``.
    """

    tests: dict[str, frozenset[str]] = field(default_factory=dict)
    problems: list[str] = field(default_factory=list)


def _is_marker(node: ast.AST) -> bool:
    """Whether ``node`` is ``pytest.mark.statements(...)`` or ``mark.statements(...)``."""
    if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
            and node.func.attr == "statements"):
        return False
    owner = node.func.value
    return (isinstance(owner, ast.Attribute) and owner.attr == "mark"
            or isinstance(owner, ast.Name) and owner.id == "mark")


def _ids(nodes: Iterable[ast.AST], where: str, out: Markers) -> frozenset[str]:
    """The statement ids of the markers among ``nodes`` (decorators or marks)."""
    ids: set[str] = set()
    for node in nodes:
        if not _is_marker(node):
            continue
        assert isinstance(node, ast.Call)
        for arg in (*node.args, *(k.value for k in node.keywords)):
            if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                ids.add(arg.value)
            else:
                out.problems.append(f"{where}:{node.lineno}: a statements marker takes the ids "
                                    f"as string literals, got {ast.unparse(arg)}")
    return frozenset(ids)


def _pytestmark(body: list[ast.stmt]) -> list[ast.AST]:
    """The marks of a ``pytestmark = …`` assignment in ``body``."""
    marks: list[ast.AST] = []
    for node in body:
        if (isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "pytestmark"
                                                 for t in node.targets)):
            value = node.value
            marks.extend(value.elts if isinstance(value, (ast.List, ast.Tuple)) else [value])
    return marks


def _scan_body(body: list[ast.stmt], prefix: str, inherited: frozenset[str], where: str,
               out: Markers) -> None:
    inherited = inherited | _ids(_pytestmark(body), where, out)
    for node in body:
        if (isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
                and node.name.startswith("test")):
            out.tests[f"{prefix}::{node.name}"] = inherited | _ids(node.decorator_list, where,
                                                                   out)
        elif isinstance(node, ast.ClassDef) and node.name.startswith("Test"):
            _scan_body(node.body, f"{prefix}::{node.name}",
                       inherited | _ids(node.decorator_list, where, out), where, out)


def scan_markers(root: Path) -> Markers:
    """Read every test module ``root/test_*.py`` and the statement ids its tests carry.

    Parameters
    ----------
    root : Path
        The test folder.

    Returns
    -------
    Markers
    """
    out = Markers()
    for path in sorted(root.glob("test_*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        _scan_body(tree.body, path.name, frozenset(), path.name, out)
    return out


def named_test_problems(statements: Statements, markers: Markers) -> list[str]:
    """Every test a statement names that does not exist or does not carry its id."""
    out = []
    for s in statements:
        for t in s.tests:
            if t not in markers.tests:
                out.append(f"{s.id}: test {t} does not exist")
            elif s.id not in markers.tests[t]:
                out.append(f"{s.id}: test {t} does not carry the id in its statements marker")
    return out


def unknown_ids(all_statements: Iterable[Statements], markers: Markers) -> list[str]:
    """Every marker id in no statements file: an id of a family whose file exists but has no
    such statement, or an id of no family (ids of a family without a file are left alone)."""
    families = {st.key: st for st in all_statements}
    out = []
    for test, ids in sorted(markers.tests.items()):
        for sid in sorted(ids):
            st = families.get(sid.split(":", 1)[0])
            if st is None:
                out.append(f"{test}: marker id {sid!r} is of no family ({', '.join(families)})")
            elif st.present and sid not in st.by_id:
                out.append(f"{test}: marker id {sid!r} is in no statement of {st.source}")
    return out


# --- the docs' anchors ------------------------------------------------------------------------
def slug(heading: str) -> str:
    """The anchor mkdocs gives a heading (Python-Markdown's ``toc`` slugify, after the inline
    code, emphasis and links of the heading are rendered to text)."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)
    text = re.sub(r"(?<!\w)[*_]+|[*_]+(?!\w)|`", "", text)
    text = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode("ascii")
    text = re.sub(r"[^\w\s-]", "", text).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def anchors(page: Path) -> set[str]:
    """The anchors of a Markdown page: its headings' (a repeated one as mkdocs numbers it:
    ``name``, ``name_1``, …) and the explicit ones (``<a id="s18"></a>``); fenced code is
    skipped."""
    out: set[str] = set()
    fenced = False
    for line in page.read_text(encoding="utf-8").splitlines():
        if line.lstrip().startswith(("```", "~~~")):
            fenced = not fenced
        if not fenced:
            out.update(re.findall(r"<a\s+(?:id|name)=\"([^\"]+)\"", line))
        m = None if fenced else re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            base = anchor = slug(m.group(1))
            n = 0
            while anchor in out:
                n += 1
                anchor = f"{base}_{n}"
            out.add(anchor)
    return out


def decision_problems(statements: Statements, docs: Path) -> list[str]:
    """Every decision whose doc section (``file.md#anchor``, a path under ``docs``) does not
    exist."""
    out = []
    for s in statements:
        if not s.decision:
            continue
        page, _, anchor = s.decision.partition("#")
        path = docs / page
        if not path.is_file():
            out.append(f"{s.id}: decision page {page} does not exist")
        elif anchor not in anchors(path):
            out.append(f"{s.id}: {page} has no heading with the anchor #{anchor}")
    return out

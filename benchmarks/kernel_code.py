"""Machine code numba cached in two source trees, compared function by function (a check, not a
benchmark): ``python benchmarks/kernel_code.py OLD_TREE NEW_TREE [PATTERN]``.

Before timing a speed difference between two trees on a shared machine, ask whether the code
differs at all: each ``cache=True`` function's cache file (``__pycache__/*.nbc``) holds the
object code of its compiled signatures. This script extracts that object code, disassembles it
(``objdump``), drops what does not run (addresses, symbol names, which change when a module
moves) and prints, per cached function found in both trees, whether the instructions are the
same (``subset``: one tree compiled further signatures, and those both compiled are the same),
with the instruction counts (of every compiled signature, callees linked into the object
included). Both trees must have run the same code first (their caches
warm); ``PATTERN`` keeps the functions whose cache name contains it (e.g. ``_run_`` or
``lanes``).
"""

from __future__ import annotations

import hashlib
import pickle
import re
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

_ADDRESS = re.compile(r"^\s*[0-9a-f]+:\s*")
_SYMBOL = re.compile(r"<[^>]*>")


def objects(nbc: Path) -> list[bytes]:
    """The ELF object files inside a numba cache data file."""
    raw = nbc.read_bytes()
    out, i = [], 0
    while (i := raw.find(b"\x7fELF", i)) >= 0:
        (shoff,) = struct.unpack_from("<Q", raw, i + 0x28)
        shentsize, shnum = struct.unpack_from("<HH", raw, i + 0x3A)
        end = i + shoff + shentsize * shnum
        out.append(raw[i:end])
        i = end
    return out


def instructions(obj: bytes) -> list[str]:
    """The instructions of an object file, without addresses and symbol names."""
    with tempfile.NamedTemporaryFile(suffix=".o") as f:
        f.write(obj)
        f.flush()
        text = subprocess.run(["objdump", "-d", "--no-show-raw-insn", f.name],
                              capture_output=True, text=True, check=True).stdout
    lines = []
    for line in text.splitlines():
        if _ADDRESS.match(line):
            lines.append(_SYMBOL.sub("", _ADDRESS.sub("", line)).strip())
    return lines


def data_files(nbi: Path) -> list[Path]:
    """The data files a numba cache index names (stale data files of older sources are not
    named)."""
    with nbi.open("rb") as f:
        pickle.load(f)  # numba's version
        _, overloads = pickle.loads(f.read())
    return [nbi.with_name(name) for name in sorted(overloads.values())]


def cached(tree: Path, pattern: str) -> dict[str, list[list[str]]]:
    """{module path and function name (without the line number): [instructions per compiled
    signature]} of the cache files under ``tree/src``."""
    out: dict[str, list[list[str]]] = {}
    for nbi in sorted(tree.glob("src/**/__pycache__/*.nbi")):
        folder = nbi.parent.parent.relative_to(tree / "src").as_posix()
        name = f"{folder}/{re.sub(r'-[0-9]+[.]py[0-9]+[.]nbi$', '', nbi.name)}"
        if pattern in name:
            out[name] = [instructions(o) for nbc in data_files(nbi) if nbc.exists()
                         for o in objects(nbc)]
    return out


def main() -> None:
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__.splitlines()[1].strip())
    old_tree, new_tree = Path(sys.argv[1]), Path(sys.argv[2])
    pattern = sys.argv[3] if len(sys.argv) == 4 else ""
    old, new = cached(old_tree, pattern), cached(new_tree, pattern)
    same = 0
    for name in sorted(old.keys() & new.keys()):
        a = sorted(hashlib.sha256("\n".join(x).encode()).hexdigest() for x in old[name])
        b = sorted(hashlib.sha256("\n".join(x).encode()).hexdigest() for x in new[name])
        counts = (f"{sum(map(len, old[name])):7d} {sum(map(len, new[name])):7d} "
                  "instructions")
        if a == b:
            same += 1
            verdict = "same   "
        elif set(a) <= set(b) or set(b) <= set(a):
            verdict = "subset "  # one tree compiled further signatures; the shared ones agree
        else:
            verdict = "DIFFERS"
        print(f"{verdict} {name:72s} {counts}")
    for label, only in (("old", old.keys() - new.keys()), ("new", new.keys() - old.keys())):
        for name in sorted(only):
            print(f"only in {label} tree: {name}")
    print(f"{same} of {len(old.keys() & new.keys())} functions found in both trees compile to "
          "the same instructions")


if __name__ == "__main__":
    main()

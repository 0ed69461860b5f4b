"""The package's architecture: layers import only downwards, no import cycles, quiet imports.

The import graph is read from the source (every ``import`` statement, also those inside functions),
so a cycle hidden behind a lazy import is a cycle here too.
"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
from pathlib import Path

import emdm

PACKAGE = Path(emdm.__file__).parent

LAYERS = {
    "emdm.errors": 0,
    "emdm.core": 1,
    "emdm.solvers": 2,
    "emdm.sim": 3,
    "emdm": 3,  # the public API (emdm.simulate, ...): a facade over core, solvers and sim
    "emdm.studies": 4,
    "emdm.outputs": 5,
    "emdm.play": 6,
    "emdm.cli": 7,  # the entry point: may start the playground
    "emdm.entry": 8,  # the executable's first lines: signal handlers, then the command line
    "emdm.__main__": 8,  # python -m emdm
}
"""Rank of each layer: a module may import modules of its own layer or of lower ranks."""


def modules() -> dict[str, Path]:
    """Every module of the package, by dotted name (a package is its ``__init__``)."""
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def imports(name: str, path: Path, known: set[str]) -> set[str]:
    """The emdm modules ``name`` imports anywhere in its source."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{base}.{node.module}" if node.module else base
            else:
                base = node.module or ""
            # ``from pkg import sub`` imports the submodule; ``from mod import name`` the module
            targets = [
                f"{base}.{alias.name}" if f"{base}.{alias.name}" in known else base
                for alias in node.names
            ]
        else:
            continue
        for target in targets:
            while target and target not in known:  # ``import emdm.core.arm.x`` -> the module
                target = target.rpartition(".")[0]
            if target and target != name:
                found.add(target)
    return found


def graph() -> dict[str, set[str]]:
    known = modules()
    return {name: imports(name, path, set(known)) for name, path in known.items()}


def layer(module: str) -> int:
    prefix = max((p for p in LAYERS if module == p or module.startswith(p + ".")), key=len)
    return LAYERS[prefix]


def test_every_module_belongs_to_a_layer():
    for name in modules():
        assert any(name == p or name.startswith(p + ".") for p in LAYERS), name


def test_layers_import_only_downwards():
    upward = [
        f"{a} imports {b}"
        for a, targets in graph().items()
        for b in sorted(targets)
        if layer(b) > layer(a)
    ]
    assert not upward, upward


def test_no_import_cycles():
    edges = graph()
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    cycles = []

    def visit(node: str, path: list[str]) -> None:
        state[node] = 1
        for nxt in sorted(edges[node]):
            if state.get(nxt) == 1:
                cycles.append(" -> ".join([*path[path.index(nxt) :], nxt]))
            elif nxt not in state:
                visit(nxt, [*path, nxt])
        state[node] = 2

    for start in sorted(edges):
        if start not in state:
            visit(start, [start])
    assert not cycles, cycles


def test_the_graph_sees_lazy_and_relative_imports():
    edges = graph()
    assert "emdm.studies.dask_engine" in edges["emdm.studies.montecarlo"]  # inside a function
    assert "emdm.core.scenario" in edges["emdm.studies.montecarlo"]
    assert "emdm" in edges["emdm.studies.bench"]  # from .. import __version__


IMPORT_ALL = """
import importlib, json, sys
import matplotlib
rc = matplotlib.rcParams
def settings():  # the stored values, without resolving the backend (which would load pyplot)
    return {k: dict.__getitem__(rc, k) for k in dict.keys(rc)}
before = settings()
skipped = []
for name in json.loads(sys.argv[1]):
    try:
        importlib.import_module(name)
    except ModuleNotFoundError as exc:  # an optional extra that is not installed
        if (exc.name or "").startswith("emdm"):
            raise
        skipped.append(name)
changed = sorted(k for k, v in settings().items() if before.get(k) != v)
print(json.dumps({"pyplot": "matplotlib.pyplot" in sys.modules, "changed": changed,
                  "skipped": skipped}))
"""


def test_every_module_imports_without_side_effects():
    """Importing any module loads no pyplot and changes no matplotlib setting (the backend)."""
    names = [n for n in modules() if n not in ("emdm.cli.__main__", "emdm.__main__")]  # they run
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    proc = subprocess.run(
        [sys.executable, "-c", IMPORT_ALL, json.dumps(names)],
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout.splitlines()[-1])
    assert result == {"pyplot": False, "changed": [], "skipped": result["skipped"]}
    assert len(result["skipped"]) < len(names) // 4, result["skipped"]

"""The package's layers: imports only run downward, no module imports one that imports it back, and the mechanics
never load the code generator.

Layers, bottom to top (DESIGN.md's module table, grouped): ``errors`` and ``collector`` (the garbage
collector paused); ``model`` (readers, the immutable model)
and ``core`` (straight-line programs, backends), which do not know each other; ``mechanics`` (the book's
recursions); ``contract`` (the routines, signatures, manifest); ``twin`` and ``symbolic`` (floats, SymPy);
``codegen`` (printers, templates, compiling); ``cli``.
"""
import ast
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "aggsym"
LAYERS = {"errors": 0, "collector": 0, "model": 1, "core": 1, "mechanics": 2, "contract": 3, "twin": 4, "symbolic": 4,
          "codegen": 5, "cli": 6, "__main__": 7}
# modules whose import must not bring the code generator (or jinja2) along
LIGHT = ["aggsym", "aggsym.errors", "aggsym.contract", "aggsym.twin", "aggsym.symbolic"] + sorted(
    f"aggsym.{p.parent.name}.{p.stem}" for folder in ("core", "mechanics", "model")
    for p in (PACKAGE / folder).glob("*.py") if p.stem != "__init__")


def module_name(path: Path, root: Path = PACKAGE) -> str:
    parts = path.relative_to(root.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path, root: Path = PACKAGE) -> set:
    """The aggsym modules a file imports, at any depth of its code (function-level imports included)."""
    name = module_name(path, root)
    package = name if path.stem == "__init__" else name.rsplit(".", 1)[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.startswith("aggsym")}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.startswith("aggsym"):
                out.add(target)
                out |= {f"{target}.{a.name}" for a in node.names}
    return out


GRAPH = {module_name(p): imports(p) for p in PACKAGE.rglob("*.py")}
for name in GRAPH:  # keep only edges to modules (not to names inside them), and never a module to itself
    GRAPH[name] = {m for m in GRAPH[name] if m in GRAPH and m != name}


def layer(name: str) -> int:
    parts = name.split(".")
    return -1 if len(parts) == 1 else LAYERS[parts[1]]


def test_every_module_has_a_layer():
    assert all(layer(m) >= -1 for m in GRAPH)


def test_imports_run_downward():
    """A module imports only modules of its own layer or below (the package's __init__ imports lazily, by name)."""
    upward = [(m, t) for m, targets in GRAPH.items() for t in targets
              if m != "aggsym" and layer(t) > layer(m) and t != "aggsym"]
    assert not upward, upward


def test_no_import_cycles():
    """No module imports a module that (directly or not) imports it back."""
    def reach(start):
        seen, stack = set(), [start]
        while stack:
            for t in GRAPH[stack.pop()]:
                if t not in seen and t != "aggsym":  # the package itself: every module's parent, imported lazily
                    seen.add(t)
                    stack.append(t)
        return seen

    cycles = [m for m in GRAPH if m != "aggsym" and m in reach(m)]
    assert not cycles, cycles


def test_the_checks_see_a_bad_import(tmp_path):
    """The graph reader resolves relative imports, so an upward import would be caught."""
    bad = PACKAGE / "mechanics" / "inertia.py"
    text = bad.read_text() + "\nfrom ..codegen import printing\n"
    copy = tmp_path / "aggsym" / "mechanics" / "inertia.py"
    copy.parent.mkdir(parents=True)
    copy.write_text(text)
    found = imports(copy, tmp_path / "aggsym")
    assert "aggsym.codegen.printing" in found and layer("aggsym.codegen.printing") > layer("aggsym.mechanics.inertia")


@pytest.mark.parametrize("module", LIGHT)
def test_mechanics_do_not_load_the_code_generator(module):
    """In a fresh interpreter, importing the module leaves aggsym.codegen and jinja2 unloaded."""
    code = (f"import sys, importlib; importlib.import_module({module!r}); "
            "bad = sorted(m for m in sys.modules if m.startswith('aggsym.codegen') or m == 'jinja2'); "
            "print(bad); sys.exit(1 if bad else 0)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=PACKAGE.parent)
    assert proc.returncode == 0, proc.stdout + proc.stderr

"""The package's layers: imports only run downward, no module imports one that imports it back, and the mechanics
never load the code generator; the same for the benchmark (``benchmarks/``), which sits above the package.

Layers, bottom to top (docs/architecture.md, "The layers"): ``errors``, ``suggest`` ("did you mean") and ``collector``
(the garbage collector paused); ``core`` (straight-line programs, backends); ``model`` (the immutable model, which
holds its numbers as the core's expressions), in wings of its own, bottom to top: the types and the tree, the
transforms of a model, the readers, then the package's face; ``mechanics`` (the book's recursions); ``contract`` (a
package: the registry, the routines by domain, shapes, analyses, manifest); ``twin`` and ``symbolic`` (floats,
SymPy); ``codegen`` (printers, emission, targets, compiling); ``pipeline`` (a file to the model generated from, every
option applied); ``cli``.

The benchmark's layers: what the sections share (``harness/``: measuring a child process, the chains, the host, the
robots, building the C harnesses); the sections, in subpackages by what they measure (``generation/``, ``runtime/``,
``batch/``, ``mjcf/``), each importing its own modules and the harness alone; the report, which reads back some
sections' JSON; ``run``, which runs them all.
"""
import ast
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "aggsym"
BENCHMARKS = PACKAGE.parent / "benchmarks"
LAYERS = {"errors": 0, "collector": 0, "suggest": 0, "core": 1, "model": 2, "mechanics": 3, "contract": 4, "twin": 5,
          "symbolic": 5, "codegen": 6, "pipeline": 7, "cli": 8, "__main__": 9}
# model/'s wings, bottom to top: the model's types, its transforms, its readers
MODEL_WINGS = {"types": 0, "tree": 0, "transforms": 1, "readers": 2}
def module_name(path: Path, root: Path = PACKAGE) -> str:
    parts = path.relative_to(root.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path, root: Path = PACKAGE) -> set:
    """The modules of ``root``'s package (aggsym unless told) a file imports, at any depth of its code
    (function-level imports included)."""
    top = root.name
    name = module_name(path, root)
    package = name if path.stem == "__init__" else name.rsplit(".", 1)[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.split(".")[0] == top}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] == top:
                out.add(target)
                out |= {f"{target}.{a.name}" for a in node.names}
    return out


def graph(root: Path) -> dict:
    """module -> the modules of the same package it imports (not names inside them, never itself); what the
    benchmark writes under ``build/`` (generated modules, git-ignored) is not part of the package."""
    out = {module_name(p, root): imports(p, root) for p in root.rglob("*.py")
           if "build" not in p.relative_to(root).parts}
    return {name: {m for m in targets if m in out and m != name} for name, targets in out.items()}


# modules whose import must not bring the code generator (or jinja2) along
LIGHT = ["aggsym", "aggsym.errors", "aggsym.contract", "aggsym.twin", "aggsym.symbolic"] + sorted(
    module_name(p) for folder in ("core", "mechanics", "model", "contract")
    for p in (PACKAGE / folder).rglob("*.py") if p.stem != "__init__")
GRAPH = graph(PACKAGE)
BENCH_GRAPH = graph(BENCHMARKS)
# the benchmark, bottom to top: the harness (0), the sections (1), the tops of the batched section and the report (2),
# the runner (3); a module of a subpackage is named by its path below benchmarks/ ("runtime.casadi_peer"), a
# subpackage by its folder (its __init__ holds its docstring alone: 0)
BENCH_LAYERS = {
    "harness": 0, "generation": 0, "runtime": 0, "batch": 0, "mjcf": 0,
    **{f"harness.{m}": 0 for m in ("paths", "measure", "generate", "environment", "robots", "chain", "tables", "plots",
                                    "cli", "build")},
    **{f"generation.{m}": 1 for m in ("measured", "kane", "opcounts", "inputs", "scaling", "compile_split",
                                       "derivative_counts")},
    **{f"runtime.{m}": 1 for m in ("pinocchio_cpp", "constrained", "casadi_peer", "constrained_derivatives",
                                    "python_call", "slicing", "trig", "casadi_target")},
    **{f"mjcf.{m}": 1 for m in ("mujoco_reference", "mujoco_poses", "corpus")},
    "batch.peers": 1, "batch.engines": 1, "batch.report": 1, "batch.worker": 2, "batch.orchestrator": 2,
    "batch.__main__": 2,
    "report_plots": 1, "report_derivatives": 1, "report": 2, "run": 3,
}


def layer(name: str) -> int:
    parts = name.split(".")
    return -1 if len(parts) == 1 else LAYERS[parts[1]]


def wing(name: str) -> int:
    """The wing of a module of aggsym.model (the model package itself: above them all)."""
    parts = name.split(".")
    return MODEL_WINGS[parts[2]] if len(parts) > 2 else max(MODEL_WINGS.values()) + 1


def test_every_module_has_a_layer():
    assert all(layer(m) >= -1 for m in GRAPH)
    assert all(wing(m) >= 0 for m in GRAPH if m.startswith("aggsym.model"))


def test_the_model_wings_import_downward():
    """Within aggsym.model, the types and the tree import no wing, and a transform never imports a reader."""
    upward = [(m, t) for m, targets in GRAPH.items() if m.startswith("aggsym.model.") for t in targets
              if t.startswith("aggsym.model.") and wing(t) > wing(m)]
    assert not upward, upward


def test_the_wing_check_sees_a_transform_reading_a_file(tmp_path):
    """A transform that imports a reader is an upward import between the wings."""
    copy = tmp_path / "aggsym" / "model" / "transforms" / "gravity.py"
    copy.parent.mkdir(parents=True)
    copy.write_text((PACKAGE / "model" / "transforms" / "gravity.py").read_text()
                    + "\nfrom ..readers.urdf_reader import load_urdf\n")
    found = imports(copy, tmp_path / "aggsym")
    assert "aggsym.model.readers.urdf_reader" in found
    assert wing("aggsym.model.readers.urdf_reader") > wing("aggsym.model.transforms.gravity")


def test_imports_run_downward():
    """A module imports only modules of its own layer or below (the package's __init__ imports lazily, by name)."""
    upward = [(m, t) for m, targets in GRAPH.items() for t in targets
              if m != "aggsym" and layer(t) > layer(m) and t != "aggsym"]
    assert not upward, upward


def cycles(graph: dict, package: str) -> list:
    """The modules of ``graph`` that import (directly or not) a module that imports them back."""
    def reach(start):
        seen, stack = set(), [start]
        while stack:
            for t in graph[stack.pop()]:
                if t not in seen and t != package:  # the package itself: every module's parent, imported lazily
                    seen.add(t)
                    stack.append(t)
        return seen

    return [m for m in graph if m != package and m in reach(m)]


@pytest.mark.parametrize("package", ["aggsym", "benchmarks"])
def test_no_import_cycles(package):
    """No module imports a module that (directly or not) imports it back, in the package nor in the benchmark."""
    found = cycles(GRAPH if package == "aggsym" else BENCH_GRAPH, package)
    assert not found, found


def test_the_cycle_check_sees_a_cycle():
    """A two-module loop, and a longer one through a function-level import, are both reported."""
    assert sorted(cycles({"p": set(), "p.a": {"p.b"}, "p.b": {"p.a"}, "p.c": set()}, "p")) == ["p.a", "p.b"]
    assert sorted(cycles({"p": set(), "p.run": {"p.report"}, "p.report": {"p.split"}, "p.split": {"p.run"}},
                         "p")) == ["p.report", "p.run", "p.split"]


def test_every_benchmark_module_has_a_layer():
    assert sorted(m.split(".", 1)[1] for m in BENCH_GRAPH if m != "benchmarks") == sorted(BENCH_LAYERS)


def test_benchmark_imports_run_downward():
    """A benchmark module imports only benchmark modules of its own layer or below."""
    def level(name):
        return BENCH_LAYERS[name.split(".", 1)[1]]

    upward = [(m, t) for m, targets in BENCH_GRAPH.items() if m != "benchmarks" for t in targets
              if t != "benchmarks" and level(t) > level(m)]
    assert not upward, upward


def bench_folder(name: str) -> str | None:
    """The subpackage of benchmarks/ a module is in, or is ("benchmarks.runtime.trig", "benchmarks.runtime":
    runtime); None for the modules at the top (report, run) and the benchmark itself."""
    parts = name.split(".")
    return parts[1] if len(parts) > 1 and (BENCHMARKS / parts[1]).is_dir() else None


def test_benchmark_sections_import_only_their_own_modules_and_the_harness():
    """A subpackage's modules import their own subpackage's and the harness' alone (the harness its own alone): no
    section reads another's code; the report and the runner, at the top, read them all."""
    sideways = [(m, t) for m, targets in BENCH_GRAPH.items() if bench_folder(m) for t in targets
                if t != "benchmarks" and bench_folder(t) not in {bench_folder(m), "harness"}]
    assert not sideways, sideways


def test_the_package_does_not_import_the_benchmark():
    """aggsym is below the benchmark: none of its modules imports ``benchmarks``."""
    bad = sorted(module_name(p) for p in PACKAGE.rglob("*.py") if imports(p, BENCHMARKS))
    assert not bad, bad


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

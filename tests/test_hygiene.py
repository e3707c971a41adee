"""The repository's hygiene: the suite collects where Pinocchio does not import (and the tests that need neither
Pinocchio nor a compiler pass there), every document a file cites exists, and docs/architecture.md names every module.
"""
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def without_pinocchio(tmp_path) -> dict:
    """An environment in which ``import pinocchio`` fails: a ``pinocchio.py`` first on PYTHONPATH that raises
    ModuleNotFoundError, as an interpreter without the package would."""
    blocker = tmp_path / "blocker"
    blocker.mkdir()
    (blocker / "pinocchio.py").write_text('raise ModuleNotFoundError("No module named \'pinocchio\'", name="pinocchio")\n')
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(blocker), str(ROOT)] + [p for p in [env.get("PYTHONPATH")] if p])
    check = subprocess.run([sys.executable, "-c", "import pinocchio"], env=env, capture_output=True, text=True)
    assert check.returncode != 0 and "No module named 'pinocchio'" in check.stderr, check.stderr
    return env


@pytest.mark.slow
def test_the_suite_collects_without_pinocchio(tmp_path):
    """``python -m pytest --collect-only`` succeeds without Pinocchio: the modules that use it are not collected
    (tests/conftest.py says so at the end), every other test is; and the tests marked neither pinocchio nor compiler
    of a few modules (the layers among them) pass there."""
    env = without_pinocchio(tmp_path)
    pytest_ = [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-p", "no:xdist"]
    proc = subprocess.run([*pytest_, "--collect-only", "-q"], cwd=ROOT, env=env, capture_output=True, text=True)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out[-3000:]
    summary = out.strip().splitlines()[-1]
    assert re.match(r"\d+ tests collected in ", summary), out[-3000:]  # no "N errors" in it
    assert "needs Pinocchio (PyPI pin), which does not import here" in out, out[-3000:]
    assert "skipped" not in summary, out[-3000:]
    collected = {line.split("::")[0] for line in proc.stdout.splitlines() if "::" in line}
    assert "tests/test_architecture.py" in collected and "tests/test_mimic.py" not in collected

    subset = ["tests/test_architecture.py", "tests/test_yaml_validation.py"]
    proc = subprocess.run([*pytest_, "-q", "-m", "not pinocchio and not compiler", "-k",
                           "not test_mechanics_do_not_load_the_code_generator", *subset],
                          cwd=ROOT, env=env, capture_output=True, text=True)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out[-3000:]
    summary = out.strip().splitlines()[-1]
    assert re.search(r"\d+ passed", summary) and not re.search(r"failed|error", summary), out[-3000:]


# a cited document: a Markdown file anywhere, or a Python file named by a path into the repository or the package
CITED = re.compile(r"(?<![\w/.-])((?:[\w-]+/)*[\w-]+\.(?:md|py))(?!\.?\w)")
PACKAGE_FOLDERS = {"aggsym", "tests", "benchmarks", "docs", "core", "model", "mechanics", "codegen"}


SKIPPED_FOLDERS = {".git", ".venv", "build", "generated", "__pycache__", ".pytest_cache", ".hypothesis"}


def repository_files() -> list:
    """The project's files (relative paths), generated/ left out: git's list in a checkout, else the tree less the
    folders that tools write (.venv, build, caches)."""
    proc = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True)
    if proc.returncode == 0:
        lines = proc.stdout.splitlines()
    else:
        lines = [p.relative_to(ROOT).as_posix() for p in ROOT.rglob("*")
                 if not SKIPPED_FOLDERS & set(p.relative_to(ROOT).parts) and not p.name.endswith(".egg-info")]
    return [Path(line) for line in lines if not line.startswith("generated/") and (ROOT / line).is_file()]


def test_every_cited_document_exists():
    """Every .md a file names, and every .py path into the repository (aggsym/..., tests/..., codegen/...), exists:
    beside the citing file, from the root, or inside aggsym/."""
    files = repository_files()
    names = {p.name for p in files}
    missing = []
    for f in files:
        if f.suffix not in {".py", ".md", ".yaml", ".j2", ".toml", ".txt", ""}:
            continue
        try:
            text = (ROOT / f).read_text()
        except UnicodeDecodeError:
            continue
        for cited in set(CITED.findall(text)):
            path = Path(cited)
            if path.suffix == ".py" and (len(path.parts) == 1 or path.parts[0] not in PACKAGE_FOLDERS):
                continue  # a generated module (NAME.py) or a file of another project
            if len(path.parts) == 1 and path.name in names:
                continue
            if not any((base / path).is_file() for base in (ROOT, ROOT / f.parent, ROOT / "aggsym")):
                missing.append((str(f), cited))
    assert not missing, missing


def heading_anchors(path: Path) -> set:
    """The anchors a Markdown renderer gives the headings of ``path`` (GitHub's rule: lower case, punctuation
    dropped, spaces to hyphens), code blocks left out."""
    out, fence = set(), False
    for line in path.read_text().splitlines():
        if line.startswith("```"):
            fence = not fence
        elif not fence and line.startswith("#"):
            out.add(re.sub(r"[^\w\- ]", "", line.lstrip("#").strip().lower()).replace(" ", "-"))
    return out


def test_every_link_of_the_readme_and_docs_reaches_its_file_and_heading():
    """A relative link (text in brackets, then a file and an optional ``#heading`` in parentheses) of README.md
    or docs/ names a file that exists and, with an anchor, a heading of that file (the README's reference moved
    to docs/: links must follow)."""
    broken = []
    for doc in [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md")):
        for target in re.findall(r"\]\(([^)\s]+)\)", doc.read_text()):
            if re.match(r"[a-z]+:", target):
                continue
            path, _, anchor = target.partition("#")
            linked = (doc.parent / path) if path else doc
            if not linked.exists():
                broken.append((doc.name, target, "no such file"))
            elif anchor and linked.suffix == ".md" and anchor not in heading_anchors(linked):
                broken.append((doc.name, target, "no such heading"))
    assert not broken, broken


def test_the_architecture_page_names_every_module():
    """docs/architecture.md names every module of aggsym/ by its path (a subpackage's __init__ aside when it holds
    no more than a docstring and re-exports)."""
    page = (ROOT / "docs" / "architecture.md").read_text()
    modules = sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "aggsym").rglob("*.py")
                     if not (p.name == "__init__.py" and p.parent.name != "aggsym" and len(p.read_text().splitlines()) < 20))
    unnamed = [m for m in modules if f"`{m}`" not in page]
    assert not unnamed, unnamed

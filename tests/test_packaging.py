"""The package as users install it: the wheel holds every package and the templates (the top-level templates/,
installed as aggsym.templates), and an aggsym installed from it into a fresh virtual environment, run from another
folder, writes the same files as this checkout."""
import filecmp
import os
import subprocess
import sys
import sysconfig
import tomllib
import zipfile
from pathlib import Path

from conftest import ROOT, model_path

from aggsym.codegen.generate import generate, write
from aggsym.pipeline import prepare

PACKAGE = ROOT / "aggsym"
TEMPLATES = ROOT / "templates"


def test_every_package_and_template_folder_is_listed():
    """pyproject.toml lists the packages by hand (the templates live outside aggsym/): every folder of Python
    modules under aggsym/ and every target's folder under templates/ is one of them."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(config["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in PACKAGE.rglob("__init__.py")}
    found |= {"aggsym.templates"} | {f"aggsym.templates.{d.name}" for d in TEMPLATES.iterdir()
                                     if d.is_dir() and any(d.glob("*.j2"))}
    assert listed == found, (sorted(listed - found), sorted(found - listed))
    assert config["package-dir"] == {"aggsym.templates": "templates"}


def test_the_wheel_installed_in_a_fresh_venv_generates_from_another_folder(tmp_path):
    wheel_dir = tmp_path / "wheel"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w",
                    str(wheel_dir), str(ROOT)], check=True, capture_output=True, cwd=tmp_path)
    wheel = next(wheel_dir.glob("aggsym-*.whl"))
    names = set(zipfile.ZipFile(wheel).namelist())
    shipped = {f"aggsym/templates/{p.relative_to(TEMPLATES).as_posix()}" for p in TEMPLATES.rglob("*.j2")}
    modules = {f"aggsym/{p.relative_to(PACKAGE).as_posix()}" for p in PACKAGE.rglob("*.py")}
    assert shipped <= names and modules <= names and len(shipped) >= 14
    assert not any(n.startswith("templates/") for n in names)
    # a fresh venv: aggsym from the wheel alone; its dependencies (sympy, numpy, jinja2, pyyaml) seen through a .pth
    # line naming this interpreter's site-packages (a .pth line adds a folder without running the .pth files in
    # it, so this checkout's editable install is not seen)
    venv = tmp_path / "fresh"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, capture_output=True)
    python = venv / "bin" / "python"
    site = Path(subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               check=True, capture_output=True, text=True).stdout.strip())
    (site / "dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps", "--no-index", "-q",
                    str(wheel)], check=True, capture_output=True)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    model = model_path("planar_2link")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    proc = subprocess.run([str(venv / "bin" / "aggsym"), "generate", str(model), "-q", "--targets",
                           "c,numpy,manifest,latex,jax,torch"], cwd=elsewhere, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    where = subprocess.run([str(python), "-c", "import aggsym, importlib.resources as r; print(aggsym.__file__); "
                            "print(r.files('aggsym.templates'))"], cwd=elsewhere, env=env, capture_output=True,
                           text=True, check=True).stdout.split()
    assert all(w.startswith(str(site)) for w in where), where
    out = elsewhere / "generated" / "planar_2link"
    here = tmp_path / "here"
    prepared = prepare(model)
    write(generate(prepared.model, targets="c,numpy,manifest,latex,jax,torch"), here, prepared.name_origin)
    files = sorted(p.name for p in here.iterdir())
    assert sorted(p.name for p in out.iterdir()) == files
    _, mismatch, errors = filecmp.cmpfiles(out, here, files, shallow=False)
    assert not mismatch and not errors

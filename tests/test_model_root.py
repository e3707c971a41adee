"""The model root (aggsym/model/readers/model_root.py): every file a model names resolves inside one folder, the
model's own by default, ``--model-root DIR`` (``root=``) to widen it.  A scene library that shares a scene between
folders (``objects/TASK.xml`` including ``../scene/basic_scene.xml``, meshes in ``../meshes``) generates with the
option and agrees with MuJoCo; without it the refusal names the file, the element, the resolved path and the
option that would admit it; meshes, textures, height fields and symbolic links are screened the same way, in MJCF
and xacro alike."""
from __future__ import annotations

import warnings
from pathlib import Path

import pytest

import aggsym
from aggsym import cli
from aggsym.codegen.compile import import_module

mujoco = pytest.importorskip("mujoco")
pytestmark = pytest.mark.mujoco

from benchmarks.mjcf.mujoco_reference import Module, compare  # noqa: E402

# a tetrahedron with a corner cut (not symmetric: its inertia tensor has products), in metres
MESH = """v 0 0 0
v 0.31831 0 0
v 0 0.27183 0
v 0 0 0.14142
v 0.11 0.07 0.05
f 1 3 2
f 1 2 4
f 1 4 3
f 2 3 5
f 3 4 5
f 2 5 4
"""

SCENE = """<mujoco>
  <compiler meshdir="../meshes" angle="radian"/>
  <option gravity="0.1 -0.2 -9.80665"/>
  <asset><mesh name="shard" file="shard.obj"/></asset>
  <default><joint damping="0.0371" stiffness="1.2345"/></default>
  <worldbody><light pos="0 0 3"/><geom name="floor" type="plane" size="2 2 .1"/></worldbody>
</mujoco>
"""

TASK = """<mujoco model="task">
  <include file="../scene/basic_scene.xml"/>
  <worldbody>
    <body name="base" pos="0.1 0 0.4">
      <joint name="j1" axis="0.26726 0.53452 0.80178"/>
      <geom type="mesh" mesh="shard" density="2700"/>
      <body name="arm" pos="0.3 0.02 0" euler="0.31416 -0.2 1.0472">
        <joint name="j2" type="slide" axis="1 0.5 -0.25" springref="0.05"/>
        <geom type="capsule" size="0.03" fromto="0 0 0 0.25 0 0" mass="0.0031"/>
        <body name="tip" pos="0.25 0 0">
          <joint name="j3" axis="0 1 0" ref="0.12345"/>
          <geom type="mesh" mesh="shard" mass="1834.5"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def library(folder: Path) -> Path:
    """A scene library laid out as the benchmark suites do: assets/objects/task.xml, assets/scene, assets/meshes."""
    for sub in ("objects", "scene", "meshes"):
        (folder / "assets" / sub).mkdir(parents=True, exist_ok=True)
    (folder / "assets" / "meshes" / "shard.obj").write_text(MESH)
    (folder / "assets" / "scene" / "basic_scene.xml").write_text(SCENE)
    path = folder / "assets" / "objects" / "task.xml"
    path.write_text(TASK)
    return path


def generate(args, capsys):
    code = cli.main(["generate", *map(str, args), "-q"])
    return code, capsys.readouterr().err


def refused(args, capsys, *fragments, out=None):
    code, err = generate(args, capsys)
    assert code == 2, err
    assert "Traceback" not in err and err.startswith("aggsym: error: "), err
    for fragment in fragments:
        assert fragment in err, f"{fragment!r} not in {err!r}"
    if out is not None:
        assert not Path(out).exists()
    return err


def test_a_shared_scene_with_the_model_root_agrees_with_mujoco(tmp_path, capsys):
    path = library(tmp_path)
    root = tmp_path / "assets"
    out = tmp_path / "out"
    code, err = generate([path, "--model-root", root, "-o", out, "--targets", "numpy,manifest"], capsys)
    assert code == 0, err
    module = import_module(out / "task.py")
    model = aggsym.load(path, root=root)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        worst = compare(path, model=model, samples=4, seed=3, evaluators=[Module(module)])
    assert model.has_damping and max(worst.values()) <= 1e-9, worst
    # the mesh's inertia is the compiled model's (the mesh was read): the tip's mass is the file's, the base's by
    # the mesh's volume and its density
    m = mujoco.MjModel.from_xml_path(str(path))
    assert m.body_mass[3] == pytest.approx(1834.5) and m.body_mass[1] > 0


def test_without_the_model_root_the_refusal_names_the_option(tmp_path, capsys):
    path = library(tmp_path)
    out = tmp_path / "out"
    refused([path, "-o", out], capsys, f"{path}:2:", '<include file="../scene/basic_scene.xml">',
            str(tmp_path / "assets" / "scene" / "basic_scene.xml"), "outside the model's folder",
            f"--model-root {tmp_path / 'assets'} admits it", out=out)
    with pytest.raises(aggsym.ModelError, match="--model-root"):
        aggsym.load(path)


def test_a_root_too_narrow_for_the_meshes_names_the_mesh(tmp_path, capsys):
    """The include admitted by a root that does not hold the meshes' folder: the mesh is refused, by its element,
    in the file that names it (the scene), with the meshdir applied as MuJoCo applies it."""
    path = library(tmp_path)
    (tmp_path / "assets" / "meshes").rename(tmp_path / "meshes")
    scene = tmp_path / "assets" / "scene" / "basic_scene.xml"
    scene.write_text(SCENE.replace('meshdir="../meshes"', 'meshdir="../../meshes"'))
    refused([path, "--model-root", tmp_path / "assets", "-o", tmp_path / "out"], capsys,
            f"{scene}:4:", '<mesh file="shard.obj">', "the mesh file resolves to",
            str(tmp_path / "meshes" / "shard.obj"), "outside the model root", f"--model-root {tmp_path} admits")
    code, err = generate([path, "--model-root", tmp_path, "-o", tmp_path / "out"], capsys)
    assert code == 0, err


@pytest.mark.parametrize("element", [
    '<mesh name="x" file="../outside.obj"/>',
    '<texture name="t" type="2d" file="../outside.png"/>',
    '<texture name="t" type="cube" fileright="ok.png" fileleft="ok.png" fileup="../outside.png" filedown="ok.png" '
    'filefront="ok.png" fileback="ok.png"/>',
    '<hfield name="h" file="../outside.png" size="1 1 1 0.1"/>',
    '<skin file="../outside.skn"/>',
])
def test_asset_files_outside_are_refused_before_mujoco_reads_them(tmp_path, capsys, element):
    (tmp_path / "model").mkdir()
    path = tmp_path / "model" / "m.xml"
    path.write_text(f'<mujoco><asset>{element}</asset><worldbody><body name="b"><joint name="j"/>'
                    f'<geom size=".1"/></body></worldbody></mujoco>')
    refused([path, "-o", tmp_path / "out"], capsys, "outside the model's folder", str(tmp_path / "outside."),
            f"--model-root {tmp_path} admits it", out=tmp_path / "out")


def test_texturedir_assetdir_and_strippath_as_mujoco_resolves_them(tmp_path, capsys):
    (tmp_path / "model").mkdir()
    path = tmp_path / "model" / "m.xml"
    body = '<worldbody><body name="b"><joint name="j"/><geom size=".1"/></body></worldbody>'
    # a texture in texturedir (outside); the mesh folder is irrelevant to it
    path.write_text(f'<mujoco><compiler meshdir="." texturedir="../tex"/><asset><texture name="t" type="2d" '
                    f'file="a.png"/></asset>{body}</mujoco>')
    refused([path, "-o", tmp_path / "out"], capsys, '<texture file="a.png">', str(tmp_path / "tex" / "a.png"))
    # assetdir stands for both when they are not set
    path.write_text(f'<mujoco><compiler assetdir="../a"/><asset><mesh name="x" file="x.obj"/></asset>{body}</mujoco>')
    refused([path, "-o", tmp_path / "out"], capsys, '<mesh file="x.obj">', str(tmp_path / "a" / "x.obj"))
    # strippath: only the file's name is kept, so a path leading out is read from inside (and MuJoCo reads it so)
    (tmp_path / "model" / "x.obj").write_text(MESH)
    path.write_text(f'<mujoco><compiler strippath="true"/><asset><mesh name="x" file="../../x.obj"/></asset>'
                    f'<worldbody><body name="b"><joint name="j"/><geom type="mesh" mesh="x"/></body></worldbody>'
                    f'</mujoco>')
    code, err = generate([path, "-o", tmp_path / "out", "--targets", "manifest"], capsys)
    assert code == 0, err


def test_symbolic_links_leaving_the_root_are_refused(tmp_path, capsys):
    path = library(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (tmp_path / "assets" / "meshes" / "shard.obj").rename(elsewhere / "shard.obj")
    (tmp_path / "assets" / "meshes" / "shard.obj").symlink_to(elsewhere / "shard.obj")
    refused([path, "--model-root", tmp_path / "assets", "-o", tmp_path / "out"], capsys,
            "the mesh file resolves to", str(elsewhere / "shard.obj"), "through a symbolic link",
            f"--model-root {tmp_path} admits it", out=tmp_path / "out")
    # a linked folder inside the root is fine
    (tmp_path / "assets" / "meshes" / "shard.obj").unlink()
    (elsewhere / "shard.obj").rename(tmp_path / "assets" / "meshes" / "shard.obj")
    (tmp_path / "assets" / "linked").symlink_to(tmp_path / "assets" / "objects")
    code, err = generate([tmp_path / "assets" / "linked" / "task.xml", "--model-root", tmp_path / "assets",
                          "-o", tmp_path / "out", "--targets", "manifest"], capsys)
    assert code == 0, err


def test_a_root_must_hold_the_model(tmp_path, capsys):
    path = library(tmp_path)
    (tmp_path / "other").mkdir()
    refused([path, "--model-root", tmp_path / "other", "-o", tmp_path / "out"], capsys,
            "--model-root", "is not inside it")
    refused([path, "--model-root", tmp_path / "missing", "-o", tmp_path / "out"], capsys, "no such folder")
    with pytest.raises(aggsym.ModelError, match="not inside it"):
        aggsym.load(path, root=tmp_path / "other")


def test_an_attached_model_resolves_its_meshes_in_its_own_folder(tmp_path, capsys):
    arm = tmp_path / "model" / "arm"
    (arm / "meshes").mkdir(parents=True)
    (arm / "meshes" / "shard.obj").write_text(MESH)
    (arm / "arm.xml").write_text('<mujoco><compiler meshdir="meshes"/><asset><mesh name="s" file="shard.obj"/>'
                                 '</asset><worldbody><body name="b"><joint name="j"/><geom type="mesh" mesh="s"/>'
                                 '</body></worldbody></mujoco>')
    path = tmp_path / "model" / "scene.xml"
    path.write_text('<mujoco><asset><model name="arm" file="arm/arm.xml"/></asset><worldbody><body name="base">'
                    '<attach model="arm" body="b" prefix="a_"/></body></worldbody></mujoco>')
    code, err = generate([path, "-o", tmp_path / "out", "--targets", "manifest"], capsys)
    assert code == 0, err
    (arm / "arm.xml").write_text((arm / "arm.xml").read_text().replace('meshdir="meshes"', 'meshdir="../../m"'))
    refused([path, "-o", tmp_path / "out2"], capsys, str(arm / "arm.xml"), '<mesh file="shard.obj">',
            str(tmp_path / "m" / "shard.obj"))


XACRO = '<?xml version="1.0"?>\n<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="r">\n{}\n</robot>\n'
LINKS = """<link name="base"/><link name="l1"><inertial><mass value="1.2"/><origin xyz="0.1 0 0"/>
<inertia ixx="0.01" iyy="0.02" izz="0.03" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
<limit effort="1" velocity="1" lower="-1" upper="1"/></joint>"""


def test_xacro_includes_follow_the_same_root(tmp_path, capsys):
    (tmp_path / "robots" / "shared").mkdir(parents=True)
    (tmp_path / "robots" / "arm").mkdir()
    (tmp_path / "robots" / "shared" / "links.xacro").write_text(XACRO.format(LINKS))
    path = tmp_path / "robots" / "arm" / "arm.urdf.xacro"
    path.write_text(XACRO.format('<xacro:include filename="../shared/links.xacro"/>'))
    refused([path, "-o", tmp_path / "out"], capsys, "outside the model's folder",
            str(tmp_path / "robots" / "shared" / "links.xacro"), f"--model-root {tmp_path / 'robots'} admits it",
            out=tmp_path / "out")
    code, err = generate([path, "--model-root", tmp_path / "robots", "-o", tmp_path / "out", "--targets",
                          "manifest"], capsys)
    assert code == 0, err
    assert aggsym.load(path, root=tmp_path / "robots").nv == 1


def test_a_urdf_takes_the_option_and_reads_no_other_file(tmp_path, capsys):
    """A URDF's meshes (package://, file://) are visuals and collisions that aggsym never opens: the root only has
    to hold the file."""
    path = tmp_path / "r" / "r.urdf"
    path.parent.mkdir()
    path.write_text('<?xml version="1.0"?>\n<robot name="r">' + LINKS.replace(
        '<link name="base"/>', '<link name="base"><visual><geometry><mesh filename="file:///etc/shadow"/>'
                               '</geometry></visual></link>') + '</robot>\n')
    code, err = generate([path, "--model-root", tmp_path, "-o", tmp_path / "out", "--targets", "manifest"], capsys)
    assert code == 0, err
    refused([path, "--model-root", tmp_path / "nowhere", "-o", tmp_path / "o2"], capsys, "no such folder")


def test_the_generated_code_does_not_depend_on_the_root(tmp_path, capsys):
    """Widening the root changes what may be read, not what is generated."""
    path = library(tmp_path)
    outs = []
    for root in (tmp_path / "assets", tmp_path):
        out = tmp_path / f"out_{len(outs)}"
        code, err = generate([path, "--model-root", root, "-o", out, "--targets", "c,numpy"], capsys)
        assert code == 0, err
        outs.append({p.name: p.read_bytes() for p in out.iterdir()})
    assert sorted(outs[0]) == ["task.c", "task.h", "task.py"] and outs[0] == outs[1]

"""Issue 35, item 5: the command line a newcomer meets.

Routine names as ``--list-routines`` prints them (``NAME_forward_dynamics``) are taken by ``--routines`` as the
bare ones are; a misspelled routine, YAML key, link or frame gets the closest names ("did you mean"); the files
of a URDF robot are named after the file, not its ``<robot name>``, unless ``--name`` says otherwise.
"""
from __future__ import annotations

import json

import pytest

from aggsym import cli
from aggsym.suggest import close_names, did_you_mean
from conftest import model_path
from helpers import written
from robot_builder import chain, segment

URDF = chain("plane",  # two links turning about y
             segment("shoulder", "upper_arm", axis="0 1 0", mass=1.0, com="0.1 0 0", inertia=(0.01, 0.02, 0.03)),
             segment("elbow", "fore_arm", xyz="0.3 0 0", axis="0 1 0", mass=0.5, com="0.2 0 0",
                     inertia=(0.01, 0.02, 0.02)), base="base_link")


def run(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def arm(tmp_path):
    return written(tmp_path / "two_link_arm.urdf", URDF)


def test_files_are_named_after_the_model_file_not_the_robot_name(arm, tmp_path, capsys):
    code, out, err = run(capsys, "generate", arm, "-o", tmp_path / "o", "-q")
    assert code == 0, err
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == [
        "two_link_arm.c", "two_link_arm.h", "two_link_arm.json", "two_link_arm.py", "two_link_arm.tex"]
    assert json.loads((tmp_path / "o" / "two_link_arm.json").read_text())["name"] == "two_link_arm"
    assert "void two_link_arm_inertia(" in (tmp_path / "o" / "two_link_arm.h").read_text()


def test_name_still_chooses_the_name(arm, tmp_path, capsys):
    code, _, err = run(capsys, "generate", arm, "-o", tmp_path / "o", "-q", "--name", "plane")
    assert code == 0, err
    assert (tmp_path / "o" / "plane.h").exists() and not (tmp_path / "o" / "two_link_arm.h").exists()


def test_a_file_name_that_is_no_identifier_is_made_one(tmp_path, capsys):
    for file, name in (("2-link arm.urdf", "model_2_link_arm"), ("arm.v2.urdf", "arm_v2")):
        path = tmp_path / file
        path.write_text(URDF)
        code, out, err = run(capsys, "generate", path, "--list-routines")
        assert code == 0, err
        assert out.splitlines()[0].startswith(f"{name}_inertia "), out
    # a standard module's name (`import math` would not find the generated module), a C library function, a C
    # keyword: the file's name with _model after it, and a warning naming the original and --name (issue 53)
    for stem in ("math", "floor", "int"):
        path = tmp_path / f"{stem}.urdf"
        path.write_text(URDF)
        out_dir = tmp_path / f"o_{stem}"
        code, _, err = run(capsys, "generate", path, "-o", out_dir, "-q")
        assert code == 0, err
        assert "named after the file" in err and f"'{stem}_model'" in err and "--name NAME" in err, err
        assert (out_dir / f"{stem}_model.h").exists() and not (out_dir / f"{stem}.h").exists()
        assert (out_dir / f"{stem}_model.py").exists()
    path = tmp_path / "floor.xml"  # the same for MJCF (the file of the issue)
    path.write_text('<mujoco><worldbody><body name="b"><joint name="h" type="hinge" axis="0 1 0"/>'
                    '<geom type="sphere" size="0.1" pos="0 0 -0.5" mass="1"/></body></worldbody></mujoco>')
    code, out, err = run(capsys, "generate", path, "--list-routines")
    assert code == 0 and out.startswith("floor_model_inertia "), (out, err)
    assert "'floor_model'" in err, err


def test_a_yaml_model_keeps_its_name(tmp_path, capsys):
    path = tmp_path / "other_file.yaml"
    path.write_text(model_path("planar_2link").read_text())
    code, out, err = run(capsys, "generate", path, "--list-routines")
    assert code == 0 and out.startswith("planar_2link_inertia "), (out, err)


def test_routines_take_the_names_list_routines_prints(arm, tmp_path, capsys):
    code, listing, _ = run(capsys, "generate", arm, "--list-routines")
    assert code == 0
    printed = [line.split()[0] for line in listing.splitlines()][:3]
    assert printed == ["two_link_arm_inertia", "two_link_arm_bias", "two_link_arm_coriolis"]
    code, _, err = run(capsys, "generate", arm, "-o", tmp_path / "o", "-q", "--targets", "manifest",
                       "--routines", ",".join(printed + ["forward_dynamics"]))  # prefixed and bare together
    assert code == 0, err
    functions = json.loads((tmp_path / "o" / "two_link_arm.json").read_text())["functions"]
    assert list(functions) == ["inertia", "bias", "coriolis", "forward_dynamics"]
    code, out, err = run(capsys, "generate", arm, "--name", "arm", "--routines", "arm_gravity", "--list-routines")
    assert code == 0 and out.startswith("arm_gravity "), (out, err)  # the prefix is the name in force


@pytest.mark.parametrize("wrong, meant", [("forwad_dynamics", "forward_dynamics"),
                                          ("two_link_arm_inertia_inverze", "inertia_inverse"),
                                          ("Gravity", "gravity")])
def test_a_misspelled_routine_gets_did_you_mean(arm, capsys, wrong, meant):
    code, _, err = run(capsys, "generate", arm, "--routines", wrong, "--list-routines")
    assert code == 2 and f"no routine named {wrong!r}; did you mean {meant!r}" in err, err
    assert "(the routines are inertia, bias" in err  # the full list stays


def test_a_misspelled_link_gets_did_you_mean(arm, capsys):
    code, _, err = run(capsys, "generate", arm, "--payload", "forearm", "--list-routines")
    assert code == 2 and "no link named 'forearm'; did you mean 'fore_arm'?" in err, err
    code, _, err = run(capsys, "generate", arm, "--inertial-parameters", "upper_arm,uper_arm", "--list-routines")
    assert code == 2 and "no link named 'uper_arm'; did you mean 'upper_arm'?" in err, err


def test_a_misspelled_frame_gets_did_you_mean(arm, capsys):
    code, _, err = run(capsys, "generate", arm, "--frames", "fore_arn", "--list-routines")
    assert code == 2 and "--frames: no link named 'fore_arn'; did you mean 'fore_arm'" in err, err
    code, _, err = run(capsys, "generate", model_path("double_pendulum"), "--frames", "arm4", "--list-routines")
    assert code == 2 and "no body or frame named 'arm4'; did you mean 'arm2' or 'arm3'?" in err, err


def test_a_misspelled_yaml_key_gets_did_you_mean(tmp_path, capsys):
    path = tmp_path / "planar_2link.yaml"
    path.write_text(model_path("planar_2link").read_text().replace("parameters:", "paramters:", 1))
    code, _, err = run(capsys, "generate", path, "--list-routines")
    assert code == 2 and "unknown key 'paramters'; did you mean 'parameters'?" in err, err
    assert "(allowed: " in err and str(path) in err


def test_nothing_close_means_no_suggestion():
    assert close_names("zzzz", ["inertia", "bias"]) == []
    assert did_you_mean("zzzz", ["inertia", "bias"]) == ""
    assert did_you_mean("bais", ["inertia", "bias"]) == "; did you mean 'bias'?"
    assert close_names("GRAVITY", ["gravity", "gravity_x"])[0] == "gravity"  # letter case alone comes first


def test_a_misspelled_parent_or_constraint_link_gets_did_you_mean(arm, tmp_path, capsys):
    path = tmp_path / "planar_2link.yaml"
    path.write_text(model_path("planar_2link").read_text().replace("parent: link1", "parent: lnk1", 1))
    code, _, err = run(capsys, "generate", path, "--list-routines")
    assert code == 2 and "unknown parent 'lnk1'; did you mean 'link1'?" in err, err
    side = tmp_path / "constraints.yaml"
    side.write_text("constraints:\n  - {name: tip, body: forearm, block: point}\n")
    code, _, err = run(capsys, "generate", arm, "--constraints", side, "--list-routines")
    assert code == 2 and "unknown body 'forearm'; did you mean 'fore_arm'?" in err, err


@pytest.mark.parametrize("spelling", [["--opt", "-O1"], ["--opt", "O1"], ["--opt=-O1"], ["--opt=O1"]])
def test_check_takes_the_optimization_level_as_its_usage_line_shows(spelling, capsys):
    """``--opt -O1`` is what the help suggests; argparse alone reads ``-O1`` as an option and stops with
    "expected one argument"."""
    args = cli._parser().parse_args(cli._joined_opt(["check", "model.yaml", *spelling]))
    assert args.opt == "-O1"
    with pytest.raises(SystemExit):
        cli.main(["check", "--help"])
    assert "--opt O0|O1|O2|O3" in capsys.readouterr().out


def test_a_wrong_optimization_level_is_refused(capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["check", "model.yaml", "--opt", "-O7"])
    assert exc.value.code == 2
    assert "--opt" in capsys.readouterr().err

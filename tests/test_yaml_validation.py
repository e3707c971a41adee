"""Bad YAML models: one clear message naming the file, the YAML path and line, and what is wrong; the CLI
exits 2 without a traceback and writes nothing."""
import subprocess
import sys
import textwrap

import pytest

import aggsym
from aggsym.errors import ModelError

GOOD_BODY = """
  - name: arm
    parent: world
    pair: {functional: {theta6: q1}}
    mass: 1.0
    com: [0.1, 0, 0]
    inertia: {xx: 0.01, yy: 0.02, zz: 0.02}
"""

CASES = {
    # name: (file text, expected YAML path, expected line, words the message must contain)
    "not_yaml": ("name: x\nbodies: [\n  - name: a\n", "", 3, ["not valid YAML"]),
    "not_a_mapping": ("- 1\n- 2\n", "", 1, ["expected a mapping", "a list"]),
    "unknown_top_key": ("name: x\ngravty: [0, 0, -9.81]\nbodies:" + GOOD_BODY, "gravty", 2,
                        ["unknown key 'gravty'", "gravity"]),
    "unknown_body_key": ("name: x\nbodies:" + GOOD_BODY + "    colour: red\n", "bodies[0].colour", 9,
                         ["unknown key 'colour'"]),
    "unknown_pair_key": ("name: x\nbodies:\n  - name: a\n    pair: {funtional: {theta6: q}}\n",
                         "bodies[0].pair.funtional", 4, ["unknown key 'funtional'"]),
    "wrong_type_mass": ("name: x\nbodies:\n  - name: a\n    mass: [1, 2]\n", "bodies[0].mass", 4,
                        ["expected a number or an expression", "list"]),
    "wrong_type_com": ("name: x\nbodies:\n  - name: a\n    mass: 1\n    com: 0.5\n", "bodies[0].com", 5,
                       ["expected a list"]),
    "wrong_length": ("name: x\nbodies:\n  - name: a\n    mass: 1\n    com: [0, 1]\n", "bodies[0].com", 5,
                     ["expected 3 entries, got 2"]),
    "wrong_type_bodies": ("name: x\nbodies: {a: 1}\n", "bodies", 2, ["expected a list"]),
    "missing_bodies": ("name: x\ngravity: [0, 0, -9.81]\n", "", 1, ["missing field 'bodies'"]),
    "missing_body_name": ("name: x\nbodies:\n  - parent: world\n    mass: 1\n", "bodies[0]", 3,
                          ["missing field 'name'"]),
    "unknown_parent": ("name: x\nbodies:" + GOOD_BODY + "  - name: b\n    parent: armm\n", "bodies[1].parent", 10,
                       ["unknown parent 'armm'"]),
    "cycle": ("name: x\nbodies:" + GOOD_BODY + "  - name: b\n    parent: c\n  - name: c\n    parent: b\n",
              "bodies[1].parent", 10, ["cycle in the tree", "b -> c -> b"]),
    "two_roots": ("name: x\nbodies:" + GOOD_BODY + "  - name: b\n    parent: world\n", "bodies[1].parent", 10,
                  ["two roots", "'arm'", "'b'"]),
    "duplicate_body": ("name: x\nbodies:" + GOOD_BODY + "  - name: arm\n    parent: arm\n", "bodies[1].name", 9,
                       ["duplicate body name 'arm'"]),
    "duplicate_coordinate": ("name: x\nbodies:" + GOOD_BODY
                             + "  - name: b\n    parent: arm\n    pair: {functional: {theta4: q1}}\n",
                             "bodies[1].pair.functional.theta4", 11, ["duplicate coordinate name 'q1'"]),
    "duplicate_joint": ("name: x\nbodies:" + GOOD_BODY
                        + "  - name: b\n    parent: arm\n    pair: {name: arm, functional: {theta4: q2}}\n",
                        "bodies[1].pair.name", 11, ["duplicate joint name 'arm'"]),
    "duplicate_key": ("name: x\nname: y\nbodies:" + GOOD_BODY, "name", 2, ["duplicate key 'name'"]),
    "bad_coordinate_code": ("name: x\nbodies:\n  - name: a\n    pair: {functional: {theta7: q}}\n",
                            "bodies[0].pair.functional.theta7", 4,
                            ["'theta7' is not a coordinate", "o1, o2, o3, theta4, theta5, theta6"]),
    "negative_mass": ("name: x\nbodies:\n  - name: a\n    mass: -2\n", "bodies[0].mass", 4,
                      ["mass must be positive", "-2"]),
    "zero_mass": ("name: x\nbodies:\n  - name: a\n    mass: 0\n", "bodies[0].mass", 4,
                  ["mass must be positive", "massless frame"]),
    "inertia_not_symmetric": ("name: x\nbodies:\n  - name: a\n    mass: 1\n    inertia: [[1, 0.1, 0], [0, 1, 0], [0, 0, 1]]\n",
                              "bodies[0].inertia", 5, ["not symmetric"]),
    "inertia_not_psd": ("name: x\nbodies:\n  - name: a\n    mass: 1\n    inertia: {xx: 1, yy: 1, zz: 1, xy: 2}\n",
                        "bodies[0].inertia", 5, ["not positive semi-definite"]),
    "inertia_triangle": ("name: x\nbodies:\n  - name: a\n    mass: 1\n    inertia: {xx: 1, yy: 1, zz: 2.5}\n",
                         "bodies[0].inertia", 5, ["triangle inequality", "2.5 > 1 + 1"]),
    "undefined_parameter": ("name: x\nparameters: {m: 1.0}\nbodies:\n  - name: a\n    mass: m\n    com: [l, 0, 0]\n",
                            "bodies[0].com[0]", 6, ["undefined parameter 'l'", "parameters"]),
    "parameter_default_not_number": ("name: x\nparameters: {m: heavy}\nbodies:" + GOOD_BODY, "parameters.m", 2,
                                     ["must be a number"]),
    "bad_expression": ("name: x\nbodies:\n  - name: a\n    mass: 1\n    com: ['import os', 0, 0]\n",
                       "bodies[0].com[0]", 5, ["cannot parse"]),
    "mises_not_rigid": ("name: x\nbodies:\n  - name: a\n    mises: [[1,0,0,0,0,0],[0,2,0,0,0,0],[0,0,1,0,0,0],"
                        "[0,0,0,1,0,0],[0,0,0,0,1,0],[0,0,0,0,0,1]]\n", "bodies[0].mises", 4, ["m E"]),
    "bad_name": ("name: 3d-arm\nbodies:" + GOOD_BODY, "name", 1, ["C identifier"]),
    "stiffness_not_symmetric": ("name: x\nbodies:\n  - name: a\n    pair: {functional: {o1: x, o2: y}, "
                                "stiffness: [[1, 2], [0, 1]]}\n    mass: 1\n", "bodies[0].pair.stiffness", 4,
                                ["not symmetric"]),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_bad_model_is_reported_precisely(case, tmp_path):
    text, where, line, words = CASES[case]
    path = tmp_path / f"{case}.yaml"
    path.write_text(text)
    with pytest.raises(ModelError) as info:
        aggsym.load(path)
    err = info.value
    assert err.file == str(path)
    assert err.where == where, str(err)
    assert err.line == line, str(err)
    message = str(err)
    assert message.startswith(f"{path}:{line}:"), message
    for w in words:
        assert w in message, message


def test_cli_reports_bad_model_with_exit_2_and_writes_nothing(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(CASES["cycle"][0])
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "aggsym", "generate", str(path), "-o", str(out)],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert proc.stderr.startswith("aggsym: error: ") and "bad.yaml:10:" in proc.stderr and "cycle" in proc.stderr
    assert proc.stdout == ""
    assert not out.exists()


def test_missing_file_and_unknown_type(tmp_path):
    with pytest.raises(ModelError, match="cannot read the file"):
        aggsym.load(tmp_path / "nothing.yaml")
    other = tmp_path / "model.json"
    other.write_text("{}")
    with pytest.raises(ModelError, match="unknown model type"):
        aggsym.load(other)


def test_good_model_loads(tmp_path):
    path = tmp_path / "ok.yaml"
    path.write_text(textwrap.dedent("""\
        name: ok
        parameters: {L: 0.5}
        gravity: [0, 0, -9.81]
        bodies:
          - name: a
            pair: {rotation: [[z, 90 deg], [x, pi/2]], functional: {theta6: q1}}
            mass: 2
            com: [L/2, 0, 0]
            inertia: [[0.1, 0, 0], [0, 0.2, 0], [0, 0, 0.2]]
        """))
    model = aggsym.load(path)
    assert model.nq == 1 and model.parameters[0].name == "L"
    c = model.bodies[0].pair.constructive_rotation()
    assert all(x in (0, 1, -1) for x in c)  # exact right angles fold to exact zeros and ones


def test_readme_example_is_a_valid_model(tmp_path):
    """The annotated example of docs/model-format.md loads, and gives the equations of models/double_pendulum.yaml."""
    import re

    from conftest import ROOT, model_path

    text = (ROOT / "docs/model-format.md").read_text()
    block = re.search(r"# The model format.*?```yaml\n(.*?)```", text, re.S).group(1)
    path = tmp_path / "example.yaml"
    path.write_text(block)
    model = aggsym.load(path)
    assert model.name == "double_pendulum_example" and model.nq == 3
    reference = aggsym.load(model_path("double_pendulum"))
    import numpy as np

    ours, theirs = aggsym.NumericTwin(model), aggsym.NumericTwin(reference)
    q, qd = np.array([0.1, -0.4, 0.7]), np.array([0.3, 0.2, -0.5])
    assert np.allclose(ours.inertia(q), theirs.inertia(q), rtol=1e-14)
    assert np.allclose(ours.bias(q, qd), theirs.bias(q, qd), rtol=1e-14)

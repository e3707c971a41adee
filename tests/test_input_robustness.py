"""Inputs from the wild (issue 30, points 2 and 5): URDF quirks the common parser (urdfdom) reads are accepted with
a warning where their meaning is unambiguous, and broken inputs are clear errors (exit 2, the file, the place, the
fix; never a traceback) that leave the output folder as it was."""
import os
import warnings

import numpy as np
import pytest

import aggsym
from aggsym import cli
from aggsym.errors import ModelError, ModelWarning
from conftest import model_path


def run(capsys, *argv) -> tuple:
    """(exit code, stderr) of ``aggsym ARGV``, warnings shown as the command line shows them."""
    with warnings.catch_warnings():
        warnings.simplefilter("always", ModelWarning)
        code = cli.main([str(a) for a in argv])
    return code, capsys.readouterr().err


def assert_clean_error(code, err, *fragments):
    assert code == 2, err
    assert "Traceback" not in err and "internal error" not in err, err
    for fragment in fragments:
        assert fragment in err, err


def listing(folder) -> dict:
    """Every entry under ``folder`` (recursively) with its bytes (None for a folder): what a run may not change."""
    out = {}
    for root, dirs, files in os.walk(folder):
        for d in dirs:
            out[os.path.relpath(os.path.join(root, d), folder)] = None
        for f in files:
            with open(os.path.join(root, f), "rb") as fh:
                out[os.path.relpath(os.path.join(root, f), folder)] = fh.read()
    return out


# numbers beyond every double ------------------------------------------------------------------------------

HUGE = "1" + "0" * 4999  # 5,000 digits: Python will not even convert it from text (sys.get_int_max_str_digits)


@pytest.mark.parametrize("literal", [HUGE, "-" + HUGE, "0x1" + "0" * 4999, "1" + "0" * 309])
def test_a_yaml_integer_beyond_every_double_is_a_clear_error(literal, tmp_path, capsys):
    text = model_path("double_pendulum").read_text()
    assert "\n  m2: 1.0\n" in text
    path = tmp_path / "huge.yaml"
    path.write_text(text.replace("\n  m2: 1.0\n", f"\n  m2: {literal}\n", 1))
    line = path.read_text().splitlines().index(f"  m2: {literal}") + 1
    out = tmp_path / "out"
    code, err = run(capsys, "generate", path, "-o", out, "-q")
    assert_clean_error(code, err, f"{path}:{line}: at parameters.m2:", "larger than any finite double",
                       "as a float with an exponent")
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["huge.yaml"]


def test_the_largest_yaml_integers_a_double_holds_are_read(tmp_path):
    text = model_path("double_pendulum").read_text()
    path = tmp_path / "large.yaml"
    path.write_text(text.replace("\n  m2: 1.0\n", f"\n  m2: {10 ** 300}\n", 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = aggsym.load(path)
    assert [p.value for p in model.parameters if p.name == "m2"] == [1e300]


@pytest.mark.parametrize("where, element", [
    ("mass", '<mass value="{n}"/>'),
    ("version", None),
])
def test_urdf_numbers_beyond_every_double_are_clear_errors(where, element, tmp_path, capsys):
    text = URDF.replace('<mass value="1"/>', element.format(n=HUGE), 1) if element else \
        URDF.replace('<robot name="r">', f'<robot name="r" version="{HUGE}.0">', 1)
    path = tmp_path / "huge.urdf"
    path.write_text(text)
    out = tmp_path / "out"
    code, err = run(capsys, "generate", path, "-o", out, "-q")
    assert_clean_error(code, err, f"{path}:", "finite" if where == "mass" else "version")
    assert not out.exists()


URDF = """<?xml version="1.0"?>
<robot name="r">
  <link name="base"/>
  <link name="upper">
    <inertial><origin xyz="0.1 0 0.2" rpy="0.1 0.2 0.3"/><mass value="1"/>
      <inertia ixx="0.01" iyy="0.02" izz="0.03" ixy="0.001" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="lower">
    <inertial><origin xyz="0 0.1 0"/><mass value="0.5"/>
      <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.3" rpy="0 0.5 0"/>
    <axis xyz="0 0.6 0.8"/>
    <limit lower="-2" upper="2" velocity="3" effort="40"/>
  </joint>
  <joint name="elbow" type="revolute">
    <parent link="upper"/><child link="lower"/>
    <origin xyz="0.4 0 0"/>
    <axis xyz="0 0 1"/>
    <dynamics damping="0.5" friction="0.1"/>
  </joint>
</robot>
"""


# URDF quirks that urdfdom reads --------------------------------------------------------------------------


def dynamics(model, rng=None) -> list:
    """A(q), the inverse dynamics and the joint friction's parameters at fixed random states: what two files
    that mean the same robot must agree on exactly."""
    from aggsym.twin import NumericTwin

    rng = rng or np.random.default_rng(30)
    twin = NumericTwin(model)
    out = [[(p.name, p.value) for p in model.parameters], model.limits]
    for _ in range(3):
        q, qd, qdd = (rng.uniform(-2, 2, model.nq) for _ in range(3))
        out += [twin.call("inertia", q), twin.call("inverse_dynamics", q, qd, qdd)]
    return out


def assert_same_dynamics(a, b):
    da, db = dynamics(a), dynamics(b)
    assert da[:2] == db[:2]
    for x, y in zip(da[2:], db[2:]):
        assert np.array_equal(x, y)


def load_warned(path) -> tuple:
    """(model, warning texts) of a URDF."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ModelWarning)
        model = aggsym.load(path)
    return model, [str(w.message) for w in caught if issubclass(w.category, ModelWarning)]


@pytest.mark.parametrize("before", ["\n", "\n\n  \t", "   ", "\r\n", "\ufeff\n"])
def test_an_xml_declaration_after_white_space_is_read_with_a_warning(before, tmp_path, capsys):
    plain, quirk = tmp_path / "plain.urdf", tmp_path / "quirk.urdf"
    plain.write_text(URDF)
    quirk.write_bytes((before + URDF).encode("utf-8"))
    model, said = load_warned(quirk)
    line = 1 + before.count("\n")
    assert [w for w in said if w.startswith(f"{quirk}:{line}: at <?xml?>:") and "preceded by white space" in w
            and "Remove what comes before <?xml" in w] == said and len(said) == 1, said
    assert model.meta["warnings"] == said
    assert_same_dynamics(model, aggsym.load(plain))
    out = tmp_path / "out"
    code, err = run(capsys, "generate", quirk, "-o", out, "-q")
    assert code == 0 and "preceded by white space" in err and str(quirk) in err and (out / "quirk.c").exists(), err


def test_lines_keep_their_numbers_after_a_moved_declaration(tmp_path):
    """Errors after the declaration point at the file's own lines."""
    text = "\n\n\n" + URDF.replace('<mass value="0.5"/>', '<mass value="-0.5"/>')
    path = tmp_path / "quirk.urdf"
    path.write_text(text)
    with pytest.raises(ModelError) as info, warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        aggsym.load(path)
    assert info.value.line == text.splitlines().index(next(x for x in text.splitlines() if "-0.5" in x)) + 1
    assert "negative mass" in info.value.message


def test_white_space_before_other_content_is_still_refused(tmp_path):
    """Only the declaration moves: a processing instruction named like it (<?xml-stylesheet?>) is not one."""
    path = tmp_path / "pi.urdf"
    path.write_text("\n<?xml-stylesheet href='a'?>\n" + URDF)
    with pytest.raises(ModelError) as info:
        aggsym.load(path)
    assert "not XML" in info.value.message


def lines_of(text, element, again) -> tuple:
    """(line of the element, line of its repeat: the last line of ``again``) in ``text``."""
    start = text.index(element + again)
    return text.count("\n", 0, start) + 1, text.count("\n", 0, start + len(element) + again.rindex("\n")) + 2


REPEATS = {  # the element, written once, and again identically (other spellings of the same numbers)
    "axis": ('<axis xyz="0 0.6 0.8"/>', '\n    <axis xyz="0.0 0.60 8e-1"/>', '<joint name="shoulder"> <axis>'),
    "joint origin": ('<origin xyz="0 0 0.3" rpy="0 0.5 0"/>', '\n    <origin rpy="0 .5 0" xyz="0 0 0.30"/>',
                     '<joint name="shoulder"> <origin>'),
    "origin with defaults": ('<origin xyz="0.4 0 0"/>', '\n    <origin xyz="0.4 0 0" rpy="0 0 -0"/>',
                             '<joint name="elbow"> <origin>'),
    "parent": ('<parent link="base"/>', '\n    <parent link="base"/>', '<joint name="shoulder"> <parent>'),
    "child": ('<child link="lower"/>', '\n    <child link="lower"/>', '<joint name="elbow"> <child>'),
    "limit": ('<limit lower="-2" upper="2" velocity="3" effort="40"/>',
              '\n    <limit effort="4e1" velocity="3.0" upper="+2" lower="-2.0"/>', '<joint name="shoulder"> <limit>'),
    "dynamics": ('<dynamics damping="0.5" friction="0.1"/>', '\n    <dynamics friction=".1" damping="0.50"/>',
                 '<joint name="elbow"> <dynamics>'),
    "inertial origin": ('<origin xyz="0.1 0 0.2" rpy="0.1 0.2 0.3"/>',
                        '\n      <origin xyz="0.1 0 0.2" rpy="0.1 0.2 0.3"/>',
                        '<link name="upper"> <inertial> <origin>'),
    "mass": ('<mass value="0.5"/>', '\n      <mass value="0.50"/>', '<link name="lower"> <inertial> <mass>'),
    "inertia": ('<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>',
                '\n      <inertia ixx="0.01" iyy="0.01" izz="0.01"  ixy="0" ixz="0" iyz="-0"/>',
                '<link name="lower"> <inertial> <inertia>'),
    "inertial": ('<inertial><origin xyz="0 0.1 0"/>',
                 '<mass value="0.5"/>\n      <inertia ixx="0.01" iyy="0.01" '
                 'izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>\n    <inertial><origin xyz="0 0.1 0"/>',
                 '<link name="lower"> <inertial>'),
}


@pytest.mark.parametrize("what", sorted(REPEATS))
def test_an_identical_repeat_is_read_with_a_warning_naming_file_element_and_line(what, tmp_path):
    element, again, where = REPEATS[what]
    assert URDF.count(element) == 1
    plain, quirk = tmp_path / "plain.urdf", tmp_path / "quirk.urdf"
    plain.write_text(URDF)
    text = URDF.replace(element, element + again)
    quirk.write_text(text)
    model, said = load_warned(quirk)
    tag = where.split()[-1]
    first, repeat = lines_of(text, element, again)
    ours = [w for w in said if "identical to the first" in w]
    assert ours == [f"{quirk}:{repeat}: at {where}: a second {tag} identical to the first (line {first}) is "
                    f"ignored; give one"], said
    assert ours[0] in model.meta["warnings"]
    assert_same_dynamics(model, aggsym.load(plain))


DIFFERENT = {  # the element, and a second one that differs from it
    "axis": ('<axis xyz="0 0.6 0.8"/>', '\n    <axis xyz="0 0.8 0.6"/>', '<joint name="shoulder"> <axis>'),
    "axis, scaled": ('<axis xyz="0 0 1"/>', '\n    <axis xyz="0 0 2"/>', '<joint name="elbow"> <axis>'),
    "joint origin": ('<origin xyz="0.4 0 0"/>', '\n    <origin xyz="0.4 0 0" rpy="0 0 0.1"/>',
                     '<joint name="elbow"> <origin>'),
    "parent": ('<parent link="upper"/>', '\n    <parent link="base"/>', '<joint name="elbow"> <parent>'),
    "limit": ('<limit lower="-2" upper="2" velocity="3" effort="40"/>',
              '\n    <limit lower="-2" upper="2" velocity="3"/>', '<joint name="shoulder"> <limit>'),
    "mass": ('<mass value="0.5"/>', '\n      <mass value="0.6"/>', '<link name="lower"> <inertial> <mass>'),
    "inertial": ('<inertial><origin xyz="0 0.1 0"/>',
                 '<mass value="0.5"/>\n      <inertia ixx="0.01" iyy="0.01" '
                 'izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>\n    <inertial><origin xyz="0 0.2 0"/>',
                 '<link name="lower"> <inertial>'),
    "after an identical one": ('<axis xyz="0 0 1"/>', '\n    <axis xyz="0 0 1.0"/>\n    <axis xyz="0 1 0"/>',
                               '<joint name="elbow"> <axis>'),
}


@pytest.mark.parametrize("what", sorted(DIFFERENT))
def test_a_repeat_that_differs_is_refused_naming_file_element_and_line(what, tmp_path, capsys):
    element, again, where = DIFFERENT[what]
    assert URDF.count(element) == 1
    text = URDF.replace(element, element + again)
    path = tmp_path / "two.urdf"
    path.write_text(text)
    tag = where.split()[-1]
    first, second = lines_of(text, element, again)
    out = tmp_path / "out"
    code, err = run(capsys, "generate", path, "-o", out, "-q")
    assert_clean_error(code, err, f"{path}:{second}: at {where}: a second {tag} that differs from the first "
                                  f"(line {first})", "give one")
    assert not out.exists()


# output folders: all or nothing --------------------------------------------------------------------------


def test_a_folder_where_a_file_goes_is_a_clear_error_and_nothing_changes(tmp_path, capsys):
    out = tmp_path / "out"
    assert run(capsys, "generate", model_path("planar_2link"), "-o", out, "-q")[0] == 0
    (out / "planar_2link.c").unlink()
    (out / "planar_2link.c").mkdir()
    (out / "notes.txt").write_text("mine")
    before = listing(out)
    code, err = run(capsys, "generate", model_path("planar_2link"), "-o", out, "-q")
    assert_clean_error(code, err, f"{out / 'planar_2link.c'}: a folder stands where", "move or remove it",
                       "-o OUTDIR")
    assert listing(out) == before and sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_a_failure_while_files_take_their_place_puts_the_earlier_generation_back(tmp_path, capsys, monkeypatch):
    """An earlier --split generation; the next (one file) fails at its third file: every earlier file (the stale
    split ones too) is back as it was, and nothing of the new run is left."""
    out = tmp_path / "out"
    assert run(capsys, "generate", model_path("planar_2link"), "-o", out, "-q", "--split")[0] == 0
    (out / "notes.txt").write_text("mine")
    before = listing(out)
    assert "planar_2link_inertia.c" in before and "planar_2link.c" not in before
    replace, calls = os.replace, []

    def failing(src, dst):
        calls.append((src, dst))
        if len(calls) == 5:  # the third file's move into place (each existing file is first put aside)
            raise PermissionError(13, "Permission denied")
        return replace(src, dst)

    monkeypatch.setattr(os, "replace", failing)
    code, err = run(capsys, "generate", model_path("planar_2link"), "-o", out, "-q")
    monkeypatch.setattr(os, "replace", replace)
    assert_clean_error(code, err, f"{out}: cannot write the output folder: Permission denied", "nothing was written")
    assert len(calls) > 5 and listing(out) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_a_new_folder_that_cannot_be_made_leaves_no_parent_behind(tmp_path, capsys, monkeypatch):
    out = tmp_path / "a" / "b" / "out"
    monkeypatch.setattr(os, "replace", lambda src, dst: (_ for _ in ()).throw(OSError(28, "No space left on device")))
    code, err = run(capsys, "generate", model_path("planar_2link"), "-o", out, "-q")
    assert_clean_error(code, err, f"{out}: cannot write the output folder: No space left on device")
    assert list(tmp_path.iterdir()) == []


def test_generating_again_replaces_the_files_and_removes_the_stale_ones(tmp_path, capsys):
    """The all-or-nothing swap still does the ordinary job."""
    out = tmp_path / "out"
    assert run(capsys, "generate", model_path("planar_2link"), "-o", out, "-q", "--split")[0] == 0
    (out / "notes.txt").write_text("mine")
    assert run(capsys, "generate", model_path("planar_2link"), "-o", out, "-q")[0] == 0
    expected = ["notes.txt"] + [f"planar_2link.{e}" for e in ("c", "h", "json", "py", "tex")]
    assert sorted(listing(out)) == sorted(expected)


LONG = "n" * 300


@pytest.mark.parametrize("how", ["--name", "yaml", "urdf", "urdf, default folder"])
def test_a_name_too_long_for_the_file_system_names_where_it_came_from(how, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    if how == "--name":
        path, extra, says = model_path("planar_2link"), ["--name", LONG], "comes from the option --name"
    elif how == "yaml":
        path, extra = tmp_path / "long.yaml", []
        path.write_text(model_path("planar_2link").read_text().replace("name: planar_2link", f"name: {LONG}", 1))
        says = f"comes from {path} (its 'name:')"
    else:  # a URDF robot's code is named after its file (not its <robot name>): a long file name, and --split's
        # longer file names (NAME.json fits, NAME_transvective_factors.c does not)
        path, extra = tmp_path / ("n" * 248 + ".urdf"), ["--split"]
        path.write_text(URDF.replace('<robot name="r">', f'<robot name="{LONG}">'))
        says = f"comes from {path} (the file's name; --name NAME gives another)"
    out = tmp_path / "x" / "out"
    folder = [] if how.endswith("default folder") else ["-o", out]
    before = sorted(p.name for p in tmp_path.iterdir())
    code, err = run(capsys, "generate", path, *folder, "-q", *extra)
    assert_clean_error(code, err, "too long for the file system", says, "give a shorter one with --name SHORTER",
                       "(248 characters)" if how.startswith("urdf") else "(300 characters)")
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_a_name_too_long_found_only_when_writing_still_names_its_origin(tmp_path, capsys, monkeypatch):
    """The early check looks at NAME.json; write() checks every file (here: a --split routine's longer name)."""
    import aggsym.codegen.generate as generate_module

    name = "n" * 248  # NAME.json fits, NAME_transvective_factors.c does not
    out = tmp_path / "out"
    code, err = run(capsys, "generate", model_path("planar_2link"), "-o", out, "-q", "--split", "--name", name)
    assert_clean_error(code, err, f"{out}: cannot write the file", "_transvective_factors", "the option --name",
                       "--name SHORTER")
    assert list(tmp_path.iterdir()) == []
    assert generate_module.check_file_names  # (the check is the module's, for library callers of write too)

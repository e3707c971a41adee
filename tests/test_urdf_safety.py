"""Hostile and broken URDF files through the command line (issue 15, items 3, 6, 9).

Each case runs ``aggsym generate FILE -o OUT`` in-process and asserts: exit code 2, a message that names the file
and the place (element, line, or the DOCTYPE), no traceback, nothing written in the output folder and no file
written beside the input.  Names that are only unusual (quotes, ``*/``, newlines, backslashes, ``\\input``) are
read: they become identifiers deterministically, their originals are kept, and two of them never become one
identifier.  The ordering of a 2000-link chain is measured and printed (never asserted: timing is for
``make bench``).
"""
import os
import re
import time
from functools import partial

import pytest

import aggsym
from aggsym import cli
from aggsym.errors import ModelError
from aggsym.model.readers import urdf_reader, xml_source
from aggsym.model.readers.validate import order_tree
import robot_builder
from robot_builder import AXIS, INERTIA, INERTIAL, link, robot

LIMIT = '<limit lower="-3" upper="3" velocity="1" effort="1"/>'
IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
# the error-location tests' pieces (robot_builder.py), every movable joint here with a <limit>; arm(*extra): base ->
# upper (shoulder) -> lower (elbow), plus extra elements
joint = partial(robot_builder.joint, inner=AXIS + LIMIT)
arm = partial(robot_builder.arm, inner=AXIS + LIMIT)


def with_shoulder(inner):
    """The arm with the shoulder's inner elements replaced."""
    return arm().replace(f'<axis xyz="0 0 1"/>{LIMIT}', inner, 1)


def with_link(name, inertial):
    return arm().replace(f'<link name="{name}">{INERTIAL}</link>', f'<link name="{name}">{inertial}</link>')


def laughs(levels=9, attribute=True):
    entities = ['<!ENTITY l0 "lol">'] + [f'<!ENTITY l{i} "{f"&l{i - 1};" * 10}">' for i in range(1, levels + 1)]
    head = '<?xml version="1.0"?>\n<!DOCTYPE robot [\n ' + "\n ".join(entities) + "\n]>\n"
    if attribute:
        return arm(head=head, name=f"&l{levels};")
    return arm(head=head).replace("</robot>", f"<gazebo>&l{levels};</gazebo></robot>")


def chain_links(n, jtype="revolute"):
    parts = [link("l0")]
    for i in range(1, n):
        parts.append(link(f"l{i}"))
        parts.append(joint(f"j{i}", f"l{i - 1}", f"l{i}", jtype=jtype))
    return robot(*parts)


def many(tag, n):
    """A robot whose only content is n elements <tag> (links without joints, joints without links, ...)."""
    item = {"link": '<link name="l{i}"/>', "joint": '<joint name="j{i}" type="fixed"/>', "g": "<g/>"}[tag]
    return '<robot name="r">\n' + "\n".join(item.format(i=i) for i in range(n)) + "\n</robot>\n"


CASES = {
    # XML: entities, external references, size -----------------------------------------------------------
    "billion-laughs-attribute": (laughs(), ["<!DOCTYPE>", "entity declaration", ":3:"]),
    "billion-laughs-text": (laughs(attribute=False), ["<!DOCTYPE>", "entity declaration"]),
    "quadratic-blowup": ('<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY a "' + "x" * 100_000 + '">]>\n'
                         + arm(head="", name="&a;" * 1000), ["<!DOCTYPE>", "<!ENTITY a ...>"]),
    "small-internal-entity": ('<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY b "base">]>\n'
                              + arm(head=""), ["<!DOCTYPE>", "<!ENTITY b ...>", "refused"]),
    "external-entity-text": ('<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY x SYSTEM "file:///etc/passwd">]>\n'
                             + arm(head="").replace("</robot>", "<gazebo>&x;</gazebo></robot>"),
                             ["<!DOCTYPE>", "external entity declaration", "<!ENTITY x ...>"]),
    "external-entity-attribute": ('<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY x SYSTEM "file:///etc/passwd">]>'
                                  "\n" + arm(head="", name="&x;"), ["<!DOCTYPE>", "external entity"]),
    "external-entity-http": ('<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY x SYSTEM "http://127.0.0.1:9/x">]>\n'
                             + arm(head="", name="&x;"), ["<!DOCTYPE>", "external entity"]),
    "parameter-entity": ('<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY % p SYSTEM "file:///etc/passwd"> %p;]>\n'
                         + arm(head=""), ["<!DOCTYPE>", "<!ENTITY % p ...>"]),
    "unparsed-entity": ('<?xml version="1.0"?>\n<!DOCTYPE robot [<!NOTATION n SYSTEM "x">'
                        '<!ENTITY e SYSTEM "file:///etc/passwd" NDATA n>]>\n' + arm(head=""),
                        ["<!DOCTYPE>", "<!ENTITY e ...>"]),
    "external-dtd": ('<?xml version="1.0"?>\n<!DOCTYPE robot SYSTEM "file:///etc/passwd">\n' + arm(head=""),
                     ["<!DOCTYPE>", "external DTD", "'file:///etc/passwd'"]),
    "undefined-entity": (arm(name="&nbsp;"), ["not XML: undefined entity"]),
    "too-many-links": (many("link", xml_source.MAX_LINKS + 1),
                       [f'<link name="l{xml_source.MAX_LINKS}">', f":{xml_source.MAX_LINKS + 2}:", "10,000 <link>"]),
    "too-many-joints": (many("joint", xml_source.MAX_JOINTS + 1),
                        [f'<joint name="j{xml_source.MAX_JOINTS}">', "10,000 <joint>"]),
    "too-many-elements": (many("g", xml_source.MAX_ELEMENTS), ["<g>", "1,000,000 XML elements"]),
    # XML: malformed ---------------------------------------------------------------------------------------
    "mismatched-tag": (arm().replace('<child link="lower"/>', '<child link="lower">'), ["not XML", "mismatched tag"]),
    "unclosed-root": (arm().replace("</robot>\n", ""), ["not XML", "no element found"]),
    "empty-file": ("", ["not XML", ":1:"]),
    "binary-garbage": (bytes(range(256)) * 4, ["not XML"]),
    "invalid-utf8": (arm().encode().replace(b'name="base"', b'name="\xff\xfe"', 1), ["not XML", "invalid token"]),
    "nul-byte": (arm().replace('name="upper"', 'name="up\x00per"', 1), ["not XML"]),
    "unknown-encoding": (arm(head='<?xml version="1.0" encoding="x-made-up"?>\n'), ["<?xml?>", "unknown encoding"]),
    "junk-after-root": (arm() + "<robot/>\n", ["not XML", "junk after document element"]),
    "text-only": ("just some text\n", ["not XML", "syntax error"]),
    "not-a-robot": ('<?xml version="1.0"?>\n<sdf version="1.6"><model name="m"/></sdf>\n',
                    ["<sdf>", "not a URDF file"]),
    "robot-without-name": (arm().replace('<robot name="r">', "<robot>"), ["<robot>", "missing attribute 'name'"]),
    "robot-without-links": (robot(), ['<robot name="r">', "no <link>"]),
    "bad-version": (arm().replace('<robot name="r">', '<robot name="r" version="one">'), ['version="one"']),
    # numbers ------------------------------------------------------------------------------------------------
    "origin-nan": (with_shoulder('<origin xyz="0 nan 0"/><axis xyz="0 0 1"/>'),
                   ['<joint name="shoulder"> <origin>', "'nan' is not a number"]),
    "origin-inf": (with_shoulder('<origin xyz="0 inf 0"/><axis xyz="0 0 1"/>'), ["<origin>", "'inf' is not a number"]),
    "origin-1e400": (with_shoulder('<origin xyz="0 1e400 0"/><axis xyz="0 0 1"/>'), ["<origin>", "is not finite"]),
    "origin-minus-1e400": (with_shoulder('<origin xyz="-1e400 0 0"/><axis xyz="0 0 1"/>'), ["<origin>", "not finite"]),
    "origin-hex": (with_shoulder('<origin xyz="0x10 0 0"/><axis xyz="0 0 1"/>'),
                   ["<origin>", "'0x10' is not a number"]),
    "origin-comma": (with_shoulder('<origin xyz="1,5 0 0"/><axis xyz="0 0 1"/>'),
                     ["<origin>", "'1,5' is not a number"]),
    "origin-two-numbers": (with_shoulder('<origin xyz="1 0"/><axis xyz="0 0 1"/>'),
                           ["<origin>", "must be 3 numbers"]),
    "origin-xacro": (with_shoulder('<origin xyz="${l} 0 0"/><axis xyz="0 0 1"/>'), ["<origin>", "xacro"]),
    "rpy-nan": (with_shoulder('<origin rpy="nan 0 0"/><axis xyz="0 0 1"/>'), ["<origin>", "'nan'"]),
    "rpy-1e400": (with_shoulder('<origin rpy="1e400 0 0"/><axis xyz="0 0 1"/>'), ["<origin>", "not finite"]),
    "quaternion-not-unit": (with_shoulder('<origin quat_xyzw="0 0 0 2"/><axis xyz="0 0 1"/>').replace(
        '<robot name="r">', '<robot name="r" version="1.1">'), ["<origin>", "not a unit quaternion"]),
    "axis-nan": (with_shoulder('<axis xyz="0 0 nan"/>'), ['<joint name="shoulder"> <axis>', "'nan'"]),
    "axis-zero": (with_shoulder('<axis xyz="0 0 0"/>'), ["<axis>", "zero length"]),
    "mass-nan": (with_link("upper", f'<inertial><mass value="nan"/>{INERTIA}</inertial>'),
                 ['<link name="upper"> <inertial> <mass>', "'nan'"]),
    "mass-inf": (with_link("upper", f'<inertial><mass value="inf"/>{INERTIA}</inertial>'), ["<mass>", "'inf'"]),
    "mass-1e400": (with_link("upper", f'<inertial><mass value="1e400"/>{INERTIA}</inertial>'), ["<mass>", "finite"]),
    "mass-negative": (with_link("upper", f'<inertial><mass value="-2"/>{INERTIA}</inertial>'),
                      ["<mass>", "negative mass -2"]),
    "mass-missing": (with_link("upper", f"<inertial>{INERTIA}</inertial>"), ["<inertial>", "missing <mass>"]),
    "inertia-nan": (with_link("upper", '<inertial><mass value="1"/>' + INERTIA.replace('ixx="0.1"', 'ixx="nan"')
                              + "</inertial>"), ["<inertia>", "'nan'"]),
    "inertia-1e400": (with_link("upper", '<inertial><mass value="1"/>' + INERTIA.replace('izz="0.1"', 'izz="1e400"')
                                + "</inertial>"), ["<inertia>", "not finite"]),
    "inertia-1e200": (with_link("upper", '<inertial><mass value="1"/>' + INERTIA.replace('izz="0.1"', 'izz="1e200"')
                                + "</inertial>"), ["<inertia>", "too large"]),
    "inertial-origin-1e400": (with_link("upper", f'<inertial><origin xyz="1e400 0 0"/><mass value="1"/>{INERTIA}'
                                                 "</inertial>"), ["<inertial> <origin>", "not finite"]),
    "merged-overflow": (arm(link("plate", f'<inertial><origin xyz="1e300 0 0"/><mass value="1e300"/>{INERTIA}'
                                          "</inertial>"),
                            joint("weld", "lower", "plate", jtype="fixed", inner='<origin xyz="1e300 0 0"/>')),
                        ['<link name="lower">', "overflows a double", "'plate'"]),
    "inertia-negative-about-axis": (with_link("upper", '<inertial><mass value="1"/>'
                                              + INERTIA.replace('izz="0.1"', 'izz="-0.1"') + "</inertial>"),
                                    ['<link name="upper">', "non-physical inertia of body 'upper'", "kinetic energy"]),
    "damping-negative": (with_shoulder(f'<axis xyz="0 0 1"/><dynamics damping="-1"/>{LIMIT}'),
                         ['<joint name="shoulder"> <dynamics>', "negative"]),
    "friction-nan": (with_shoulder(f'<axis xyz="0 0 1"/><dynamics friction="nan"/>{LIMIT}'), ["<dynamics>", "'nan'"]),
    "limit-1e400": (with_shoulder('<axis xyz="0 0 1"/><limit lower="-1e400" upper="1" velocity="1" effort="1"/>'),
                    ['<joint name="shoulder"> <limit>', "not finite"]),
    "mimic-multiplier-nan": (arm(link("hand"), joint("wrist", "lower", "hand",
                                                     inner=f'<axis xyz="1 0 0"/>{LIMIT}<mimic joint="elbow" '
                                                           'multiplier="nan"/>')), ["<mimic>", "'nan'"]),
    # the tree -----------------------------------------------------------------------------------------------
    "missing-parent-link": (arm().replace('<parent link="upper"/>', '<parent link="ghost"/>'),
                            ['<joint name="elbow"> <parent>', "parent link 'ghost' is not defined"]),
    "missing-child-link": (arm().replace('<child link="lower"/>', '<child link="ghost"/>'),
                           ['<joint name="elbow"> <child>', "'ghost' is not defined"]),
    "missing-parent-element": (arm().replace('    <parent link="upper"/>\n', ""), ["missing <parent> element"]),
    "cycle": (robot(link("base"), link("a"), link("b"), link("c"), joint("j0", "base", "a"), joint("j1", "b", "c"),
                    joint("j2", "c", "b")), ["loop in the kinematic tree", "'j1'", "'j2'"]),
    "no-root": (robot(link("a"), link("b"), joint("j1", "a", "b"), joint("j2", "b", "a")),
                ['<robot name="r">', "no root link"]),
    "two-roots": (arm(link("tool")), ['<link name="tool">', "two root links 'base'"]),
    "two-parents": (arm(joint("wrist", "base", "lower")), ['<joint name="wrist">', "has two parents"]),
    "self-joint": (arm(joint("spin", "lower", "lower")), ['<joint name="spin">', "both the parent and the child"]),
    "duplicate-link": (arm(link("upper")), ['<link name="upper">', "duplicate link name 'upper'"]),
    "duplicate-joint": (arm(link("hand"), joint("elbow", "lower", "hand")), ["duplicate joint name 'elbow'"]),
    "unknown-joint-type": (arm(link("hand"), joint("wrist", "lower", "hand", jtype="ball")),
                           ['<joint name="wrist">', "unknown joint type 'ball'"]),
    "joint-without-type": (arm().replace('name="elbow" type="revolute"', 'name="elbow"'),
                           ['<joint name="elbow">', "missing attribute 'type'"]),
    "no-movable-joint": (robot(link("base"), link("tool"), joint("weld", "base", "tool", jtype="fixed")),
                         ["no movable joint"]),
    # names ----------------------------------------------------------------------------------------------------
    "joint-names-collide": (arm(link("hand"), link("tip"), joint("wrist-1", "lower", "hand"),
                                joint("wrist_1", "hand", "tip")),
                            ['<joint name="wrist_1">', "'wrist-1'", "both become the identifier 'wrist_1'"]),
    "link-names-collide": (arm(link("hand.1"), link("hand_1"), joint("wrist", "lower", "hand.1"),
                               joint("finger", "hand.1", "hand_1")),
                           ['<link name="hand_1">', "'hand.1'", "both become the identifier 'hand_1'"]),
    "reserved-names-collide": (arm(link("hand"), link("tip"), joint("if", "lower", "hand"),
                                   joint("if_", "hand", "tip")),
                               ['<joint name="if_">', "'if' (line", "identifier 'if_'"]),
    "comment-names-collide": (arm(link("hand"), link("tip"), joint("a*/b", "lower", "hand"),
                                  joint("a_/b", "hand", "tip")), ["'a*/b'", "'a_/b'", "identifier 'a__b'"]),
    # <mimic> when coupling needs it -----------------------------------------------------------------------------
    "mimic-dangling-couple": (arm(link("hand"), joint("wrist", "lower", "hand",
                                                      inner=f'<axis xyz="1 0 0"/>{LIMIT}<mimic joint="ghost"/>')),
                              ['<joint name="wrist"> <mimic>', "'ghost', which is not defined", "couple"]),
    "mimic-self-couple": (arm(link("hand"), joint("wrist", "lower", "hand",
                                                  inner=f'<axis xyz="1 0 0"/>{LIMIT}<mimic joint="wrist"/>')),
                          ["<mimic>", "cannot mimic itself"]),
}
OPTIONS = {"mimic-dangling-couple": ["--mimic", "couple"], "mimic-self-couple": ["--mimic", "couple"]}


def run(tmp_path, capsys, content, options=(), name="robot.urdf"):
    """(exit code, stdout, stderr, output folder, path) of ``aggsym generate PATH -o OUT``."""
    path = tmp_path / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    elif content is not None:
        path.write_text(content)
    out = tmp_path / "out"
    code = cli.main(["generate", str(path), "-o", str(out), "-q", *options])
    captured = capsys.readouterr()
    return code, captured.out, captured.err, out, path


def assert_refused(code, out_text, err, out, path, fragments):
    assert code == 2, err
    assert "Traceback" not in err + out_text and "internal error" not in err
    assert err.startswith(f"aggsym: error: {path}"), err
    for fragment in fragments:
        assert fragment in err, f"{fragment!r} not in {err!r}"
    assert not out.exists() or not any(out.iterdir())
    assert sorted(p.name for p in path.parent.iterdir()) == [path.name]  # nothing beside the input either


@pytest.mark.parametrize("case", sorted(CASES))
def test_hostile_urdf(tmp_path, capsys, case):
    content, fragments = CASES[case]
    assert_refused(*run(tmp_path, capsys, content, OPTIONS.get(case, ())), fragments)


def test_error_names_the_line(tmp_path, capsys):
    text = arm().replace('<parent link="upper"/>', '<parent link="ghost"/>')
    line = next(i + 1 for i, row in enumerate(text.splitlines()) if "ghost" in row)
    code, _, err, out, path = run(tmp_path, capsys, text)
    assert_refused(code, "", err, out, path, [f"{path}:{line}: at <joint name=\"elbow\"> <parent>"])


def test_oversized_file(tmp_path, capsys):
    text = arm().encode()
    with open(tmp_path / "robot.urdf", "wb") as f:
        f.write(text.replace(b"</robot>", b"<!--"))
        f.seek(urdf_reader.MAX_BYTES)
        f.write(b"-->\n</robot>\n")  # a sparse file just over the limit
    assert_refused(*run(tmp_path, capsys, None), ["larger than 64 MiB"])


def test_endless_device(tmp_path, capsys):
    os.symlink("/dev/zero", tmp_path / "robot.urdf")
    code, out_text, err, out, path = run(tmp_path, capsys, None)
    assert code == 2 and "larger than 64 MiB" in err and "Traceback" not in err and not out.exists()


@pytest.mark.parametrize("kind", ["missing", "directory"])
def test_unreadable(tmp_path, capsys, kind):
    if kind == "directory":
        (tmp_path / "robot.urdf").mkdir()
    code, _, err, out, path = run(tmp_path, capsys, None)
    assert code == 2 and err.startswith(f"aggsym: error: {path}: cannot read the file") and not out.exists()


def test_floating_base_name_collision(tmp_path, capsys):
    text = arm().replace('joint name="shoulder"', 'joint name="base_x"')
    assert_refused(*run(tmp_path, capsys, text, ["--floating-base"]),
                   ['<joint name="base_x">', "the floating base's coordinate 'base_x'"])


def test_floating_base_non_physical_root(tmp_path, capsys):
    text = with_link("base", '<inertial><mass value="1"/>' + INERTIA.replace('ixy="0"', 'ixy="0.5"') + "</inertial>")
    assert_refused(*run(tmp_path, capsys, text, ["--floating-base"]),
                   ['<link name="base">', "non-physical inertia of body 'base'"])


def test_deep_nesting_is_skipped(tmp_path):
    """100,000 nested elements the reader does not use cost a counter, not a recursion."""
    path = tmp_path / "robot.urdf"
    path.write_text(arm().replace("</robot>", "<gazebo>" + "<a>" * 100_000 + "</a>" * 100_000 + "</gazebo></robot>"))
    assert aggsym.load(path).nq == 2


def test_entities_are_not_expanded_even_when_small(tmp_path):
    path = tmp_path / "robot.urdf"
    path.write_text('<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY b "base">]>\n' + arm(head=""))
    with pytest.raises(ModelError) as info:
        aggsym.load(path)
    assert info.value.where == "<!DOCTYPE>" and info.value.line == 2


def test_plain_doctype_is_accepted(tmp_path):
    path = tmp_path / "robot.urdf"
    path.write_text('<?xml version="1.0"?>\n<!DOCTYPE robot>\n' + arm(head=""))
    assert aggsym.load(path).nq == 2


# unusual names: read, mangled deterministically, originals kept --------------------------------------------

NAMES = {
    "comment-close": "elbow*/ #define double float /*",
    "quote": 'say "hi"',
    "apostrophe": "it's",
    "newline": "two\nlines",
    "backslash": "back\\slash",
    "dollar": "cost$x",
    "latex-input": "\\input{/etc/passwd}",
    "latex-write": "\\immediate\\write18{rm -rf /}",
    "python-code": "__import__('os').system('id')",
    "unicode": "Ellbogen-Gelenk-ä-θ",
    "empty": "",
    "long": "x" * 5000,
    "leading-digit": "1st",
    "keyword": "while",
}


def xml_attribute(value: str) -> str:
    return (value.replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;").replace("\n", "&#10;"))


@pytest.mark.parametrize("case", sorted(NAMES))
def test_unusual_names_are_kept_and_mangled(tmp_path, case):
    name = NAMES[case]
    text = arm().replace('joint name="elbow"', f'joint name="{xml_attribute(name)}"').replace(
        'link name="lower"', f'link name="{xml_attribute(name)}"').replace(
        '<child link="lower"/>', f'<child link="{xml_attribute(name)}"/>')
    path = tmp_path / "robot.urdf"
    path.write_text(text)
    model = aggsym.load(path)
    again = aggsym.load(path)
    coordinate, body = model.coordinates[1], model.bodies[2]
    assert coordinate.joint == name and body.pair.name == name and name in model.meta["links"]
    assert IDENTIFIER.match(coordinate.name) and IDENTIFIER.match(body.name)
    assert (coordinate.name, body.name) == (again.coordinates[1].name, again.bodies[2].name)  # deterministic
    assert coordinate.name != model.coordinates[0].name and body.name not in ("base", "upper")


@pytest.mark.parametrize("case", ["comment-close", "latex-input", "newline"])
def test_unusual_names_generate(tmp_path, capsys, case):
    """Through the command line: generated, exit 0, no traceback, every file inside the output folder (what the
    printers make of the names is their escaping's business)."""
    name = xml_attribute(NAMES[case])
    text = arm().replace('joint name="elbow"', f'joint name="{name}"')
    code, out_text, err, out, path = run(tmp_path, capsys, text)
    assert code == 0, err
    assert "Traceback" not in err + out_text
    written = [p for p in tmp_path.rglob("*") if p.is_file() and p != path]
    assert written and all(out in p.parents for p in written)
    assert {p.suffix for p in written} >= {".c", ".h", ".py", ".json", ".tex"}


def test_distinct_names_never_share_an_identifier(tmp_path):
    """Every pair of NAMES on two joints: either two distinct identifiers, or an error naming both."""
    names = sorted(set(NAMES.values()))
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            text = arm(link("hand"), joint(xml_attribute(b), "lower", "hand")).replace(
                'joint name="elbow"', f'joint name="{xml_attribute(a)}"')
            path = tmp_path / "robot.urdf"
            path.write_text(text)
            try:
                model = aggsym.load(path)
            except ModelError as exc:
                assert repr(a) in exc.message and repr(b) in exc.message and "both become" in exc.message
                continue
            identifiers = [c.name for c in model.coordinates]
            assert len(set(identifiers)) == len(identifiers)


# ordering: linear in the number of links ------------------------------------------------------------------


def test_ordering_a_2000_link_chain(tmp_path):
    """A 2000-link chain listed children first (the worst order for the old quadratic passes): read, ordered and
    merged; the times are printed, not asserted."""
    n = 2000
    parts = [link(f"l{i}") for i in reversed(range(n))]
    parts += [joint(f"j{i}", f"l{i - 1}", f"l{i}") for i in reversed(range(1, n))]
    path = tmp_path / "chain.urdf"
    path.write_text(robot(*parts))
    reader = urdf_reader._Reader(path, xml_source._parse(path, path.read_bytes()), False, "independent")
    links, link_el = reader.links(reader.root)
    joints = reader.joints(reader.root, links, link_el)
    t0 = time.perf_counter()
    root, children = reader.tree(reader.root, link_el, joints)
    t_tree = time.perf_counter() - t0
    names = [f"b{i}" for i in reversed(range(n))]
    parents = ["world" if i == 0 else f"b{i - 1}" for i in reversed(range(n))]
    t0 = time.perf_counter()
    order, problem, _ = order_tree(names, parents, "world")
    t_order = time.perf_counter() - t0
    t0 = time.perf_counter()
    model = aggsym.load(path)
    t_load = time.perf_counter() - t0
    assert problem is None and [names[i] for i in order] == [f"b{i}" for i in range(n)]
    assert root == "l0" and model.nq == n - 1 and [b.name for b in model.bodies] == [f"l{i}" for i in range(n)]
    print(f"\n2000-link chain: URDF tree ordering {t_tree * 1e3:.1f} ms, order_tree (YAML) {t_order * 1e3:.1f} ms, "
          f"whole URDF load {t_load:.2f} s")

"""Hostile YAML at the loader (issue 15, point 3): billion laughs, recursive aliases, tags, deep nesting, huge files
are exit 2 naming the file and the place, fast, with nothing written and nothing run."""
import os
import time
from pathlib import Path

import pytest

from aggsym import cli
from conftest import model_path

LAUGHS = "".join(f"l{k}: &l{k} [{', '.join([f'*l{k - 1}'] * 9)}]\n" for k in range(1, 9))
CASES = {
    "billion_laughs": ("l0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n" + LAUGHS + "name: x\n",
                       "too large"),
    "recursive_alias": ("name: x\nbodies: &b\n  - *b\n", "recursive alias"),
    "python_tag": ("name: !!python/object/apply:os.system ['touch /tmp/aggsym_yaml_pwned']\n", "not allowed"),
    "custom_tag": ("name: x\nbodies:\n  - !body {name: a, mass: 1}\n", "not allowed"),
    "binary_tag": ("name: !!binary aGVsbG8=\n", "not allowed"),
    "timestamp": ("name: x\ndescription: 2001-12-14\nbodies: []\n", "not allowed"),
    "deep_flow": ("a: " + "[" * 5000 + "]" * 5000 + "\n", "nested too deeply"),
    "deep_block": ("".join("  " * k + f"k{k}:\n" for k in range(200)) + "  " * 200 + "v: 1\n", "nested too deeply"),
    "key_is_a_list": ("name: x\n? [a, b]\n: 1\n", "key must be a name"),
    "not_yaml": ("name: [unclosed\n", "not valid YAML"),
    "empty": ("", "empty"),
    "too_many_bodies": ("name: x\nbodies:\n" + "".join(f"  - {{name: b{k}, parent: world}}\n" for k in range(10001)),
                        "at most 10,000 are read"),
    "too_many_parameters": ("name: x\nparameters:\n" + "".join(f"  p{k}: 1\n" for k in range(10001))
                            + "bodies: []\n", "at most 10,000 are read"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_hostile_yaml_is_exit_2_with_the_place(case, tmp_path, capsys):
    text, words = CASES[case]
    path = tmp_path / f"{case}.yaml"
    path.write_text(text)
    out = tmp_path / "out"
    t0 = time.perf_counter()
    code = cli.main(["generate", str(path), "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and str(path) in err and words in err and "Traceback" not in err, err
    assert time.perf_counter() - t0 < 30  # a guard against a hang, not a timing target
    assert not out.exists() and not os.path.exists("/tmp/aggsym_yaml_pwned")


def test_a_file_over_the_size_cap_is_refused_unread(tmp_path, capsys):
    path = tmp_path / "huge.yaml"
    with open(path, "wb") as f:
        f.truncate(17 * 2 ** 20)
    assert cli.main(["generate", str(path), "-o", str(tmp_path / "o")]) == 2
    assert "larger than 16 MiB" in capsys.readouterr().err


def test_anchors_and_aliases_that_are_fine_still_load(tmp_path):
    """Aliases are a YAML feature people use for repeated inertias: within the caps they work."""
    text = model_path("planar_2link").read_text()
    import aggsym

    model = aggsym.load(model_path("planar_2link"))
    assert model.nq == 2 and text
    path = tmp_path / "alias.yaml"
    path.write_text("name: alias\ngravity: &g [0, 0, -9.81]\nbodies:\n"
                    "  - name: a\n    pair: {functional: {theta6: q1}}\n    mass: 1.0\n    com: &c [0.1, 0, 0]\n"
                    "    inertia: &i {xx: 0.01, yy: 0.01, zz: 0.01}\n"
                    "  - name: b\n    parent: a\n    pair: {translation: [0.2, 0, 0], functional: {theta6: q2}}\n"
                    "    mass: 1.0\n    com: *c\n    inertia: *i\n")
    assert aggsym.load(path).nq == 2


RESOLVER_CASES = ("yes Yes YES no No NO true True TRUE false False FALSE on On ON off Off OFF null Null NULL y n Y N ~ "
                  "yes1 nope tRUE oN 1 1.5 .inf .nan 0x1F 0o17 0b101 1_000 190:20:30 2001-12-14 "
                  "2001-12-14t21:59:43.10-05:00 << = -1 +1 .5 +.inf abc theta4 _x 1e3 -2e3 6.8523015e+5 0. "
                  "1_000.5 190:20:30.15 -.Inf .NaN").split()


def test_the_shortcut_resolver_gives_the_safe_loaders_tags_and_values():
    """The composer's shortcut (text known by its first character or word) and the float shortcut change nothing:
    every edge case of YAML 1.1's implicit resolvers gets SafeLoader's tag and value."""
    import math

    import yaml

    from aggsym.model.readers.yaml_source import _PLAIN_TAGS, _Composer, _Doc

    for word in RESOLVER_CASES:
        ours = yaml.compose(f"a: {word}", Loader=_Composer).value[0][1].tag
        theirs = yaml.compose(f"a: {word}", Loader=yaml.SafeLoader).value[0][1].tag
        assert ours == theirs, word
    plain = [w for w in RESOLVER_CASES if yaml.compose(f"a: {w}", Loader=yaml.SafeLoader).value[0][1].tag
             in _PLAIN_TAGS]  # (a timestamp, a merge key or '=' are refused by the model reader)
    text = "a: [" + ", ".join(plain) + "]"
    ours, theirs = _Doc(Path("x.yaml"), text).root["a"], yaml.safe_load(text)["a"]
    for x, y in zip(ours, theirs):
        assert type(x) is type(y) and (x == y or (isinstance(x, float) and math.isnan(x) and math.isnan(y))), (x, y)

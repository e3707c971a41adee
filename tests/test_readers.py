"""The reader registry (aggsym/model/readers/registry.py) and the typed links of a model (Model.links)."""
from __future__ import annotations

import dataclasses
import subprocess
import sys

import pytest

import aggsym
from aggsym.errors import AggsymError, ModelError
from aggsym.model.readers import registry as readers
from aggsym.model.readers.registry import Reader, reader_for, register
from aggsym.model.types import LinkFrame, Links

from conftest import model_path
from helpers import robot_path


def test_suffixes_choose_the_reader(tmp_path):
    assert reader_for(model_path("double_pendulum")).name == "YAML"
    assert reader_for(tmp_path / "a.YML").name == "YAML"
    assert reader_for(robot_path("ur5")).name == "URDF"
    assert reader_for(tmp_path / "robot.urdf.xacro").name == "xacro"
    with pytest.raises(ModelError, match=r"unknown model type '\.foo': expected \.yaml, \.yml, \.urdf, \.xacro or "
                                         r"\.mjcf"):
        reader_for(tmp_path / "a.foo")


def test_a_shared_suffix_is_decided_by_the_content(tmp_path):
    urdf = tmp_path / "ur5.xml"
    urdf.write_bytes(robot_path("ur5").read_bytes())
    assert reader_for(urdf).name == "URDF"
    assert aggsym.load(urdf) == dataclasses.replace(aggsym.load(robot_path("ur5")), source=str(urdf), name="ur5")
    scene = tmp_path / "scene.xml"
    scene.write_text("<mujoco/>\n")
    assert reader_for(scene).name == "MJCF"
    other = tmp_path / "world.xml"
    other.write_text("<sdf/>\n")
    with pytest.raises(ModelError, match="no reader recognizes"):
        aggsym.load(other)


def test_a_new_format_is_one_reader(tmp_path, monkeypatch):
    monkeypatch.setattr(readers, "READERS", list(readers.READERS))
    base = aggsym.load(model_path("double_pendulum"))
    seen = []

    def load(path, **options):
        seen.append(options)
        return base

    register(Reader("Toy", (".toy",), load, options=("scale", "floating_base"), sniffed=(".xml",),
                    sniff=lambda head: b"<toy" in head))
    (tmp_path / "m.toy").write_text("")
    (tmp_path / "m.xml").write_text("<toy/>")
    assert aggsym.model.load(tmp_path / "m.toy", scale=2) is base and seen == [{"scale": 2}]
    assert reader_for(tmp_path / "m.xml").name == "Toy"
    # the pipeline passes a reader its own options (those of the table it names, and any of its own), and refuses
    # the table's others
    model = aggsym.load(tmp_path / "m.toy", scale=3, floating_base="euler", armature=0.5)
    assert seen[-1] == {"scale": 3, "floating_base": "euler"} and model.armature == 0.5 and model.name == "m"
    with pytest.raises(AggsymError, match="the Toy reader does not accept --payload"):
        aggsym.load(tmp_path / "m.toy", floating_base="euler", payload="x")
    with pytest.raises(ValueError, match="taken"):
        register(Reader("Other", (".yaml",), load))


def test_options_a_reader_does_not_accept_name_the_reader_and_the_option(tmp_path):
    with pytest.raises(TypeError, match="YAML models take no options"):
        aggsym.model.load(model_path("double_pendulum"), floating_base=True)
    with pytest.raises(AggsymError, match="the YAML reader does not accept --floating-base"):
        aggsym.load(model_path("double_pendulum"), floating_base=True)
    with pytest.raises(TypeError, match="unknown model option flaoting_base"):
        aggsym.load(model_path("double_pendulum"), flaoting_base=True)
    run = subprocess.run([sys.executable, "-m", "aggsym", "ops", str(model_path("double_pendulum")), "--mimic",
                          "couple", "--payload", "x"], capture_output=True, text=True)
    assert run.returncode == 2 and "the YAML reader does not accept --mimic and --payload" in run.stderr
    assert "Traceback" not in run.stderr


def test_links_are_typed_fields():
    ur5 = aggsym.load(robot_path("ur5"))
    assert ur5.links.kind == "link" and ur5.links.from_file and "tool0" in ur5.links.leaves
    tool = ur5.links.by_name["tool0"]
    assert isinstance(tool, LinkFrame) and tool.body == "wrist_3_link"
    assert [f.name for f in ur5.frames] == list(ur5.links.leaves)
    pendulum = aggsym.load(model_path("double_pendulum"))
    assert pendulum.links == Links.of_bodies(pendulum.bodies) and not pendulum.links.from_file
    assert all(f.name == f.body and f.rotation is None and f.part is None for f in pendulum.links.frames)
    assert dataclasses.replace(pendulum, links=None).link_table == pendulum.links
    hash(ur5)

"""Property-based fuzzing of the model readers through the command line (issue 15, point 8).

Hypothesis mutates the bundled models and small URDFs (lines deleted, duplicated, swapped or truncated; values
replaced by hostile ones: huge or non-finite numbers, code, YAML tags and aliases, XML entities, unbalanced
brackets) and runs ``aggsym generate`` on each.  Whatever the file, the run ends with exit 0 (the files written)
or 2 (a message naming the file, nothing written), never a traceback or an internal error, and nothing appears
outside the output folder.  Derandomized, so a CI run is reproducible; about a minute in all.
"""
import shutil

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import model_path
from helpers import data_text, run_cli

HOSTILE = ["1e400", "-1", "nan", ".inf", "0", "1e-320", "9^9^9^9", "1/0", "__import__('os').system('true')",
           "sin('x')", "x.__class__", "''", "", "*a", "&a [1, 2]", "!!python/object/apply:os.system ['true']",
           "[[[[[[[[[[", "{", "}", "- ", "\t", "???", "\u202e", "1" * 400, "(" * 200, "&lt;", "&xxe;",
           "<!ENTITY a 'b'>", "\"", "'", "world", "*/ #define x /*", "\\input{/etc/passwd}", "-0", "2**0.5",
           "pi/0", "deg", "1 deg deg", "t", "e", "a b c"]


def mutate(text: str, data) -> str:
    """One to three edits of a file's text, drawn by Hypothesis."""
    lines = text.split("\n")
    for _ in range(data.draw(st.integers(1, 3))):
        kind = data.draw(st.sampled_from(["replace_token", "delete", "duplicate", "swap", "truncate", "insert"]))
        i = data.draw(st.integers(0, len(lines) - 1))
        if kind == "replace_token":
            tokens = lines[i].replace('"', " \" ").replace(":", " : ").split(" ")
            if tokens:
                k = data.draw(st.integers(0, len(tokens) - 1))
                tokens[k] = data.draw(st.sampled_from(HOSTILE))
                lines[i] = " ".join(tokens).replace(" \" ", '"').replace(" : ", ":")
        elif kind == "delete" and len(lines) > 1:
            del lines[i]
        elif kind == "duplicate":
            lines.insert(i, lines[i])
        elif kind == "swap":
            j = data.draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
        elif kind == "truncate":
            lines[i] = lines[i][:data.draw(st.integers(0, len(lines[i])))]
        else:
            lines.insert(i, data.draw(st.sampled_from(HOSTILE)))
    return "\n".join(lines)


SOURCES = {"double_pendulum.yaml": model_path("double_pendulum").read_text(),
           "gyroscope.yaml": model_path("gyroscope").read_text(),
           "fuzzed.urdf": data_text("fuzzed.urdf")}  # a two-joint arm


@pytest.mark.parametrize("source", sorted(SOURCES))
@settings(max_examples=30, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data())
def test_mutated_models_end_in_exit_0_or_2(source, data, tmp_path_factory):
    folder = tmp_path_factory.mktemp("fuzz")
    path = folder / source
    text = mutate(SOURCES[source], data)
    path.write_text(text)
    out = folder / "out"
    code, err = run_cli(["generate", str(path), "-o", str(out), "-q"])
    assert code in (0, 2), (code, err, text)
    assert "Traceback" not in err and "internal error" not in err, (err, text)
    if code == 2:
        assert str(path) in err, (err, text)
        assert not out.exists(), text
    else:
        assert sorted(p.suffix for p in out.iterdir()) == [".c", ".h", ".json", ".py", ".tex"]
    assert sorted(p.name for p in folder.iterdir()) in ([source], [source, "out"])
    shutil.rmtree(folder)

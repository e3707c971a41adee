"""A YAML model file as plain Python values with the line of every path (:class:`_Doc`), read safely.

PyYAML's safe composer (libyaml's where installed) builds the node graph, then every node is checked while it is
turned into plain values: only text, numbers, booleans, null, mappings and sequences; at most :data:`MAX_DEPTH`
levels and :data:`MAX_NODES` nodes with aliases expanded; no recursive alias; no integer beyond every double.
The YAML model reader (:mod:`.yaml_reader`) reads the model from it; its errors name the file, the YAML path
(:func:`_path`) and the line.
"""
from __future__ import annotations

import sys
from pathlib import Path

import yaml

from ...errors import ModelError


def _path(parts) -> str:
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


MAX_NODES = 200_000  # YAML nodes after aliases are expanded (a billion-laughs file stops here)
MAX_DEPTH = 64  # nesting of mappings and sequences
# libyaml's composer (C, ten times faster; it refuses nesting beyond 1000 levels itself) where PyYAML has it
_BASE_COMPOSER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
# What a plain scalar must start with, or be, to be anything but text under the safe loader's implicit resolvers
# (YAML 1.1: int, float, .inf/.nan, timestamp, null ~, merge <<, value =; the words of bool and null)
_NOT_TEXT_START = frozenset("-+.0123456789<~=")
_WORDS = frozenset("yes Yes YES no No NO true True TRUE false False FALSE on On ON off Off OFF null Null NULL".split())
_STR = "tag:yaml.org,2002:str"
_FLOAT = "tag:yaml.org,2002:float"
_INT = "tag:yaml.org,2002:int"
_LARGEST = sys.float_info.max  # an integer beyond it is no finite double: no mass, length or parameter


class _Composer(_BASE_COMPOSER):
    """The safe composer with a shortcut in tag resolution: a plain scalar that starts with a character no implicit
    resolver of the safe loader matches is text, without trying the resolvers' patterns one by one (the names and
    keys of a model: most of its scalars)."""

    def resolve(self, kind, value, implicit):
        if kind is yaml.ScalarNode and implicit[0] and value and value[0] not in _NOT_TEXT_START \
                and value not in _WORDS:
            return _STR
        return super().resolve(kind, value, implicit)


_COMPOSER = _Composer
_PLAIN_TAGS = {f"tag:yaml.org,2002:{t}" for t in ("str", "int", "float", "bool", "null", "map", "seq")}


class _Doc:
    """The YAML document as plain Python values, with the line of every path.

    Safe by construction: PyYAML's safe composer (libyaml's where installed) builds the node graph (aliases are references there, nothing is
    expanded or constructed yet); then every node is checked while it is turned into Python values: only the plain
    types (text, numbers, booleans, null, mappings, sequences; explicit tags such as ``!!python/object`` or
    ``!custom`` are refused), at most :data:`MAX_DEPTH` levels, at most :data:`MAX_NODES` nodes with aliases
    expanded, and no alias inside itself."""

    def __init__(self, file: Path, text: str):
        self.file = file
        self.lines: dict[tuple, int] = {}
        try:
            node = yaml.compose(text, Loader=_COMPOSER)
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
            problem = getattr(exc, "problem", None) or str(exc)
            if "nesting depth" in problem:  # libyaml's own cap (1000 levels)
                problem = f"the YAML is nested too deeply (at most {MAX_DEPTH} levels)"
            raise ModelError(file, "", f"not valid YAML: {problem}", mark.line + 1 if mark else None) from None
        except RecursionError:
            raise ModelError(file, "", f"the YAML is nested too deeply (at most {MAX_DEPTH} levels)") from None
        if node is None:
            raise ModelError(file, "", "the file is empty")
        self._constructor = yaml.SafeLoader("")
        self._nodes = 0
        self._open: set = set()
        self.root = self._build(node, ())

    def _build(self, node, path):
        line = node.start_mark.line + 1
        self.lines[path] = line
        self._nodes += 1
        if self._nodes > MAX_NODES:
            raise ModelError(self.file, _path(path), f"the YAML document is too large: more than {MAX_NODES} values "
                                                     f"with its aliases expanded", line)
        if len(path) > MAX_DEPTH:
            raise ModelError(self.file, _path(path), f"the YAML is nested too deeply (at most {MAX_DEPTH} levels)",
                             line)
        if node.tag not in _PLAIN_TAGS:
            raise ModelError(self.file, _path(path), f"YAML tag {node.tag!r} is not allowed: a model holds only "
                                                     f"text, numbers, booleans, mappings and lists", line)
        if id(node) in self._open:
            raise ModelError(self.file, _path(path), "a YAML alias refers to a node that contains it (a recursive "
                                                     "alias)", line)
        if isinstance(node, (yaml.MappingNode, yaml.SequenceNode)):
            self._open.add(id(node))
            try:
                return self._collection(node, path)
            finally:
                self._open.discard(id(node))
        try:
            return self._scalar(node, path)
        except yaml.YAMLError as exc:
            raise ModelError(self.file, _path(path), f"not valid YAML: {getattr(exc, 'problem', None) or exc}",
                             line) from None

    def _scalar(self, node, path):
        """A scalar by its tag's constructor directly (what construct_object does for a scalar, without its
        bookkeeping: a model has tens of thousands of scalars)."""
        tag = node.tag
        if tag == _STR:
            return node.value
        if tag == _INT:
            return self._integer(node, path)
        if tag == _FLOAT and ":" not in node.value and node.value[:1] != ".":
            try:  # the resolver matched YAML's float pattern: digits, a point, an exponent, underscores
                return float(node.value)
            except ValueError:
                pass
        if isinstance(node, yaml.ScalarNode) and tag in self._constructor.yaml_constructors:
            return self._constructor.yaml_constructors[tag](self._constructor, node)
        return self._constructor.construct_object(node, deep=True)

    def _integer(self, node, path) -> int:
        """A YAML integer; one beyond every finite double (e.g. 5,000 digits, which Python will not even convert
        from text) is an error naming its path and line."""
        try:
            value = self._constructor.yaml_constructors[_INT](self._constructor, node)
        except ValueError:  # more digits than Python converts (sys.get_int_max_str_digits)
            value = None
        if value is None or abs(value) > _LARGEST:
            text = node.value.strip()
            digits = sum(ch.isdigit() for ch in text)
            raise ModelError(self.file, _path(path), f"the integer {text[:20]}... ({digits:,} digits) is larger "
                                                     f"than any finite double (about 1.8e308): write the intended "
                                                     f"value, e.g. as a float with an exponent such as 1.5e40",
                             node.start_mark.line + 1)
        return value

    def _collection(self, node, path):
        if isinstance(node, yaml.MappingNode):
            out = {}
            for key_node, value_node in node.value:
                if not isinstance(key_node, yaml.ScalarNode) or key_node.tag not in _PLAIN_TAGS or \
                        key_node.tag == "tag:yaml.org,2002:map":
                    raise ModelError(self.file, _path(path), "a key must be a name",
                                     key_node.start_mark.line + 1)
                key = self._scalar(key_node, path)
                if not isinstance(key, (str, int)):
                    raise ModelError(self.file, _path(path), f"a key must be a name, got {key!r}",
                                     key_node.start_mark.line + 1)
                if key in out:
                    raise ModelError(self.file, _path(path + (key,)), f"duplicate key {key!r}",
                                     key_node.start_mark.line + 1)
                out[key] = self._build(value_node, path + (key,))
            return out
        if isinstance(node, yaml.SequenceNode):
            return [self._build(v, path + (i,)) for i, v in enumerate(node.value)]
        return self._constructor.construct_object(node, deep=True)

    def line(self, path) -> int | None:
        path = tuple(path)
        while path not in self.lines and path:
            path = path[:-1]
        return self.lines.get(path)

    def error(self, path, message):
        return ModelError(self.file, _path(path), message, self.line(path))


__all__ = ["MAX_DEPTH", "MAX_NODES", "_Doc", "_path"]

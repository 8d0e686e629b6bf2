"""YAML input for every file the program reads: a mapping that repeats a key is an error naming
both lines (PyYAML would keep the last one silently: ``steps: [1.0]`` appended to a config
replaced its levels), and a file that is not UTF-8 text says so."""
from __future__ import annotations

import reprlib
from typing import Any

import yaml
from yaml.constructor import ConstructorError


class StrictLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses a mapping with a repeated key."""

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            seen: dict = {}
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                key = self.construct_object(key_node, deep=True)
                here = (key_node.start_mark.line + 1, key_node.start_mark.column + 1)
                try:
                    first = seen.setdefault(key, here)
                except TypeError:              # an unhashable key: PyYAML's own error follows
                    continue
                if first != here:              # by line and column: {a: 1, a: 2} on one line too
                    where = f"line {first[0]}" + (f", column {first[1]}" if first[0] == here[0] else "")
                    raise ConstructorError(
                        None, None, f"duplicate key {key!r} (first at {where}); a mapping "
                        "holds each key once: remove one of them", key_node.start_mark)
        return super().construct_mapping(node, deep=deep)


def load(stream: Any, loader: type = StrictLoader) -> Any:
    """One YAML document from a string or a file object (``loader``: StrictLoader or a subclass)."""
    return yaml.load(stream, Loader=loader)  # noqa: S506 (SafeLoader subclasses only)


def read_text(path: str) -> str:
    """A file's text, or UnicodeDecodeError for a binary file (a NUL byte counts as binary)."""
    with open(path, "rb") as fh:
        data = fh.read()
    if b"\0" in data:
        raise UnicodeDecodeError("utf-8", data, data.index(b"\0"), data.index(b"\0") + 1,
                                 "NUL byte: a binary file")
    return data.decode("utf-8")


def syntax_error(exc: yaml.YAMLError) -> str:
    """One line for a YAML syntax error: where (line, column) and PyYAML's problem."""
    mark = getattr(exc, "problem_mark", None)
    at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
    problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    return f"YAML syntax error{at}: {problem}"


def not_a_mapping(doc: Any, keys: tuple[str, ...]) -> str:
    """What a file whose document is not a mapping (empty, a list, a word) should hold."""
    got = "an empty file" if doc is None else f"{type(doc).__name__} {reprlib.repr(doc)}"
    return f"expected a mapping with keys {', '.join(keys)}; got {got}"

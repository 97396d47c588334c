"""YAML files users give (Kalibr's ``camchain.yaml``, a rig file in YAML),
read with PyYAML's safe loader and bounded.

Kalibr writes its results with PyYAML's ``yaml.dump``; OpenCV's
``cv::FileStorage`` refuses them (a list at its key's own indentation), so
the rig reader reads them with PyYAML. Imported only when a YAML file is
read (:func:`linemap.rig_files.load_rig`): ``import linemap`` and
``import matcher`` do not load PyYAML.

What a calibration file never holds is refused, since a few lines of it
can ask for unbounded work:

- anchors and aliases (``&a``, ``*a``): an alias bomb (a billion laughs)
  is a few lines whose aliases expand into billions of nodes;
- more than :data:`MAX_CHARS` characters, or nesting deeper than
  :data:`MAX_DEPTH` (PyYAML's composer recurses per level);
- a key given twice in a mapping (PyYAML would keep the last silently).

Tags outside YAML's own (``!!python/object``) are refused by the safe
loader itself. A float written without a dot (``1e-05``, YAML 1.2's form)
is a float, as in the files other YAML writers make. Every refusal is one
:class:`YamlError` line naming the file and the line.
"""

from __future__ import annotations

import re

import yaml

from linemap.errors import InputError

#: Input size limits: a calibration file is a few kilobytes, a few levels deep.
MAX_CHARS = 1 << 20
MAX_DEPTH = 32


class YamlError(InputError):
    """A YAML file that is not YAML, or holds what a calibration file never does."""


class _Loader(yaml.SafeLoader):
    """PyYAML's safe loader without anchors, aliases, repeated keys or deep nesting."""

    def __init__(self, text: str, what: str):
        super().__init__(text)
        self.what, self.depth = what, 0

    def fail(self, mark, why: str):
        raise YamlError(f"{self.what} line {mark.line + 1} {why}")

    def compose_node(self, parent, index):
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None) is not None:
            self.fail(event.start_mark, "uses an anchor or alias (&, *), which a calibration file never needs")
        if self.depth >= MAX_DEPTH:
            self.fail(event.start_mark, f"is nested deeper than {MAX_DEPTH} levels: not a calibration file")
        self.depth += 1
        try:
            return super().compose_node(parent, index)
        finally:
            self.depth -= 1

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            if isinstance(key, (str, int, float, bool)) and key in seen:
                self.fail(key_node.start_mark, f"repeats the key {key!r}")
            seen.add(key if isinstance(key, (str, int, float, bool)) else id(key_node))
        return super().construct_mapping(node, deep)


# YAML 1.2's floats with no dot (1e-05, as C's printf writes them); PyYAML's
# YAML 1.1 resolver reads them as strings.
_Loader.add_implicit_resolver("tag:yaml.org,2002:float", re.compile(r"^[-+]?[0-9]+[eE][-+]?[0-9]+$"),
                              list("-+0123456789"))


def load(text: str, what: str = "YAML file"):
    """The document of ``text``: dicts, lists, floats, ints, strings, bools,
    None (and the other types of YAML's safe schema). ``what`` names the file
    in errors; :class:`YamlError` in one line for anything refused."""
    if len(text) > MAX_CHARS:
        raise YamlError(f"{what} is larger than {MAX_CHARS} characters: not a calibration file")
    if not text.strip():
        raise YamlError(f"{what} is empty")
    loader = None
    try:
        loader = _Loader(text, what)  # PyYAML's reader checks the characters here
        return loader.get_single_data()
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f" line {mark.line + 1}" if mark is not None else ""
        why = " ".join(p for p in (exc.context, exc.problem) if p)
        raise YamlError(f"{what}{where}: not valid YAML ({why})") from None
    except yaml.YAMLError as exc:  # the reader's: a character YAML does not allow
        raise YamlError(f"{what}: not valid YAML ({' '.join(str(exc).split())})") from None
    finally:
        if loader is not None:
            loader.dispose()

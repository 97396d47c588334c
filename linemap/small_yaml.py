"""A reader of the small YAML files calibration tools write (Kalibr's
``camchain.yaml``), standard library only.

Kalibr writes its results with PyYAML's ``yaml.dump``, whose style changed
with PyYAML 5.1 (lists of numbers in flow style ``[a, b]`` before, one
``- a`` a line after), and at the top level without indenting a list under
its key; OpenCV's ``cv::FileStorage`` refuses the latter, and PyYAML is no
dependency of the runtime. This reader takes the subset those files use:

- block mappings (``key: value``, ``key:`` and the value below, indented or,
  for a list, at the key's own indentation), keys unique;
- block sequences (``- item``, nested ``- - item``, ``- key: value``);
- flow sequences ``[a, [b, c]]``, also broken over several lines;
- scalars: integers, floats (``1e-05``, ``.nan``, ``.inf``), ``true`` /
  ``false``, ``null`` / ``~``, plain and quoted strings;
- comments (``#`` at a line's start or after a space), ``---``, ``...``
  and ``%`` directives.

Anchors, aliases, tags, flow mappings and multi-line scalars are refused:
:class:`SmallYamlError` (an :class:`~linemap.errors.InputError`) in one line
naming the line. Sizes are bounded (:data:`MAX_CHARS`, :data:`MAX_DEPTH`): a
calibration file is a few kilobytes and a few levels deep.
"""

from __future__ import annotations

import re

from linemap.errors import InputError

#: Input size limits: a calibration file is a few kilobytes, a few levels deep.
MAX_CHARS = 1 << 20
MAX_DEPTH = 32

_INT = re.compile(r"[-+]?(0|[1-9][0-9]*)$")
_FLOAT = re.compile(r"[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?$")
_SPECIAL_FLOATS = {".nan": float("nan"), ".inf": float("inf"), "+.inf": float("inf"), "-.inf": float("-inf")}
_WORDS = {"true": True, "false": False, "null": None, "~": None}
#: A key: plain (no ': ' or ' #' in it) or quoted, then ':' at the end or before a space.
_KEY = re.compile(r"""("[^"]*"|'[^']*'|[^'"\s\-\[\]{}#,&*!|>%@`][^:#]*?|-[^\s][^:#]*?)\s*:(\s+|$)""")


class SmallYamlError(InputError):
    """A YAML file outside the subset this reader takes, or not YAML."""


class _Line:
    __slots__ = ("number", "indent", "text")

    def __init__(self, number: int, indent: int, text: str) -> None:
        self.number, self.indent, self.text = number, indent, text


def load(text: str, what: str = "YAML file"):
    """The document of ``text``: dicts, lists, floats, ints, strings, bools,
    None. ``what`` names the file in errors."""
    if len(text) > MAX_CHARS:
        raise SmallYamlError(f"{what} is larger than {MAX_CHARS} characters: not a calibration file")
    lines = _lines(text, what)
    if not lines:
        raise SmallYamlError(f"{what} is empty")
    reader = _Reader(lines, what)
    value = reader.block(0, lines[0].indent, 0)
    if reader.i < len(lines):
        reader.fail(lines[reader.i], "is indented less than the lines before it but not as any key above")
    return value


def _lines(text: str, what: str) -> list[_Line]:
    """The content lines of ``text``: comments, blank lines, document markers
    and directives dropped; flow sequences broken over lines joined."""
    out: list[_Line] = []
    pending: _Line | None = None
    for number, raw in enumerate(text.lstrip("\ufeff").splitlines(), start=1):
        if "\t" in raw[: len(raw) - len(raw.lstrip())]:
            raise SmallYamlError(f"{what} line {number}: indentation by tabs is not YAML; indent with spaces")
        body = _strip_comment(raw).rstrip()
        stripped = body.lstrip()
        if pending is not None:
            pending.text += " " + stripped
            if _open_brackets(pending.text) <= 0:
                out.append(pending)
                pending = None
            continue
        if not stripped or stripped in ("---", "...") or stripped.startswith("%"):
            continue
        line = _Line(number, len(body) - len(stripped), stripped)
        if _open_brackets(stripped) > 0:
            pending = line
        else:
            out.append(line)
    if pending is not None:
        raise SmallYamlError(f"{what} line {pending.number}: a '[' is never closed")
    return out


def _strip_comment(line: str) -> str:
    """``line`` without its comment (a '#' at the start or after whitespace,
    outside quotes)."""
    quote = None
    for k, c in enumerate(line):
        if quote:
            if c == quote:
                quote = None
        elif c in "'\"" and (k == 0 or line[k - 1] in " [,:-"):
            quote = c
        elif c == "#" and (k == 0 or line[k - 1] in " \t"):
            return line[:k]
    return line


def _open_brackets(text: str) -> int:
    """'[' minus ']' outside quotes."""
    depth, quote = 0, None
    for c in text:
        if quote:
            quote = None if c == quote else quote
        elif c in "'\"":
            quote = c
        elif c == "[":
            depth += 1
        elif c == "]":
            depth -= 1
    return depth


class _Reader:
    """Recursive descent over the content lines; ``i`` is the next line."""

    def __init__(self, lines: list[_Line], what: str) -> None:
        self.lines, self.what, self.i = lines, what, 0

    def fail(self, line: _Line, why: str):
        raise SmallYamlError(f"{self.what} line {line.number} {why}")

    def block(self, i: int, indent: int, depth: int):
        """The node whose first line is ``lines[i]`` at column ``indent``."""
        if depth > MAX_DEPTH:
            self.fail(self.lines[i], f"is nested deeper than {MAX_DEPTH} levels: not a calibration file")
        line = self.lines[i]
        if line.text == "-" or line.text.startswith("- "):
            return self.sequence(i, indent, depth)
        if _KEY.match(line.text):
            return self.mapping(i, indent, depth)
        self.i = i + 1
        return self.scalar_or_flow(line.text, line, depth)

    def sequence(self, i: int, indent: int, depth: int) -> list:
        out = []
        self.i = i
        while self.i < len(self.lines):
            line = self.lines[self.i]
            if line.indent != indent or not (line.text == "-" or line.text.startswith("- ")):
                if line.indent > indent:
                    self.fail(line, "is indented more than the list item above it")
                break
            rest = line.text[1:].lstrip()
            if not rest:  # the item's value on the lines below, indented more
                out.append(self.nested(line, indent, depth))
                continue
            # The item's text starts a node at its own column ("- - a", "- key: v").
            self.lines[self.i] = _Line(line.number, indent + len(line.text) - len(rest), rest)
            out.append(self.block(self.i, self.lines[self.i].indent, depth + 1))
        return out

    def mapping(self, i: int, indent: int, depth: int) -> dict:
        out: dict = {}
        self.i = i
        while self.i < len(self.lines):
            line = self.lines[self.i]
            if line.indent < indent:
                break
            if line.indent > indent:
                self.fail(line, "is indented more than the key above it (a value cannot follow on a new line "
                                "after 'key: value')")
            m = _KEY.match(line.text)
            if not m:
                if line.text == "-" or line.text.startswith("- "):
                    self.fail(line, "is a list item among the keys of a mapping (a list goes under a 'key:')")
                self.fail(line, f"is neither 'key: value' nor '- item': {line.text[:40]!r}")
            key = _unquote(m.group(1))
            if key in out:
                self.fail(line, f"repeats the key {key!r}")
            rest = line.text[m.end():]
            if rest:
                self.i += 1
                out[key] = self.scalar_or_flow(rest, line, depth)
            else:
                out[key] = self.nested(line, indent, depth, list_at_same_indent=True)
        return out

    def nested(self, line: _Line, indent: int, depth: int, list_at_same_indent: bool = False):
        """The value below ``line`` (a key or a '-' with nothing after it):
        indented more, or a list at the key's own indentation; None if none."""
        self.i += 1
        if self.i < len(self.lines):
            nxt = self.lines[self.i]
            if nxt.indent > indent or (list_at_same_indent and nxt.indent == indent
                                       and (nxt.text == "-" or nxt.text.startswith("- "))):
                return self.block(self.i, nxt.indent, depth + 1)
        return None

    def scalar_or_flow(self, text: str, line: _Line, depth: int):
        if text.startswith("["):
            value, end = self.flow(text, 0, line, depth + 1)
            if text[end:].strip():
                self.fail(line, f"has text after a closed ']': {text[end:].strip()[:40]!r}")
            return value
        if text[0] in "{&*!|>@`":
            self.fail(line, f"uses YAML this reader does not take (flow mappings, anchors, aliases, tags, "
                            f"block scalars): {text[:40]!r}")
        return _scalar(text, lambda why: self.fail(line, why))

    def flow(self, text: str, k: int, line: _Line, depth: int):
        """The flow sequence starting at ``text[k] == '['``; (list, index after ']')."""
        if depth > MAX_DEPTH:
            self.fail(line, f"is nested deeper than {MAX_DEPTH} levels: not a calibration file")
        out, k = [], k + 1
        while True:
            while k < len(text) and text[k] == " ":
                k += 1
            if k >= len(text):
                self.fail(line, "has a '[' that is never closed")
            if text[k] == "]" and not out:
                return out, k + 1
            if text[k] == "[":
                item, k = self.flow(text, k, line, depth + 1)
            else:
                end = _item_end(text, k)
                item = _scalar(text[k:end].strip(), lambda why: self.fail(line, why))
                k = end
            out.append(item)
            while k < len(text) and text[k] == " ":
                k += 1
            if k < len(text) and text[k] == ",":
                k += 1
            elif k < len(text) and text[k] == "]":
                return out, k + 1
            else:
                self.fail(line, "has a list item not followed by ',' or ']'")


def _item_end(text: str, k: int) -> int:
    """Index of the ',' or ']' ending the flow item at ``text[k]`` (quotes skipped)."""
    if text[k] in "'\"":
        close = text.find(text[k], k + 1)
        return len(text) if close < 0 else close + 1
    ends = [p for p in (text.find(",", k), text.find("]", k)) if p >= 0]
    return min(ends) if ends else len(text)


def _unquote(text: str) -> str:
    if len(text) >= 2 and text[0] == text[-1] and text[0] in "'\"":
        return text[1:-1]
    return text


def _scalar(text: str, fail):
    """A plain or quoted scalar: int, float, bool, None or str."""
    if not text:
        fail("has an empty list item")
    if text[0] in "'\"":
        if len(text) < 2 or text[-1] != text[0]:
            fail(f"has an unclosed quote: {text[:40]!r}")
        return text[1:-1]
    low = text.lower()
    if low in _WORDS:
        return _WORDS[low]
    if low in _SPECIAL_FLOATS:
        return _SPECIAL_FLOATS[low]
    if _INT.match(text):
        return int(text)
    if _FLOAT.match(text):
        return float(text)
    if text[0] in "{&*!|>@`[":
        fail(f"uses YAML this reader does not take (flow mappings, anchors, aliases, tags): {text[:40]!r}")
    return text


__all__ = ["MAX_CHARS", "MAX_DEPTH", "SmallYamlError", "load"]

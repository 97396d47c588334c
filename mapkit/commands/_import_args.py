"""The flags of :class:`~mapkit.options.BuildOptions`, shared by ``build``,
``preview``, ``extrude`` and ``layers``.

The flags are generated from the options' fields (their default, help text,
flag and group are written once, in :mod:`mapkit.options`), so every
command that reads a plan accepts the same flags with the same defaults;
and one check of the output file every command that writes one makes.
"""

from __future__ import annotations

import argparse
from dataclasses import fields
from pathlib import Path

from mapkit.errors import MapkitError
from mapkit.options import IMPORT_GROUPS, RETIRED_FLAGS, BuildOptions, OptionError, flags_of

#: argparse ``type`` of each field type that takes a value.
_PARSERS = {"float": float, "float | None": float, "int": int, "int | None": int, "str": str, "str | None": str}


def output_file(path, suffixes, inputs=()) -> Path:
    """``path`` as a Path once it ends in one of ``suffixes`` (lower case,
    with the dot), a file can be written there and it is none of the
    ``inputs``; else a one-line error."""
    from linemap.atomic import check_output_path

    out = Path(path)
    if out.suffix.lower() not in suffixes:
        wanted = suffixes[0] if len(suffixes) == 1 else "one of " + ", ".join(suffixes)
        raise MapkitError(f"output must end in {wanted}, got '{out.name}'")
    return check_output_path(out, inputs)


def _help_text(f, default) -> str:
    """Field ``f``'s help text with its default: in place of ``{default}``,
    else appended (options whose default is none or empty say what it
    means in their text)."""
    text = f.metadata["help"]
    shown = f"{default:g}" if isinstance(default, float) else str(default)
    if "{default}" in text:
        return text.replace("{default}", shown)
    return text if default is None or isinstance(default, list) else f"{text} (default {shown})"


def add_option_flags(p, groups) -> None:
    """Add to argparse parser ``p`` the flag of every BuildOptions field
    listed under one of ``groups`` (``mapkit.options.IMPORT_GROUPS``,
    ``BUILD_GROUPS``), group by group, each under its heading."""
    defaults = BuildOptions()
    for group in groups:
        g = p if group == "" else p.add_argument_group(group)
        for f in fields(BuildOptions):
            if f.metadata["group"] != group:
                continue
            default = getattr(defaults, f.name)
            kw = {"dest": f.name, "help": _help_text(f, default)}
            if f.metadata["metavar"]:
                kw["metavar"] = f.metadata["metavar"]
            if f.type == "bool":
                kw.update(action="store_true", default=default)
            elif f.type == "list[str]":
                kw.update(action="append", default=None)  # None: argparse would append to a shared default list
            elif isinstance(f.metadata["allowed"], tuple):
                kw.update(choices=f.metadata["allowed"], default=default)
            else:
                kw.update(type=_PARSERS[f.type], default=default)
            g.add_argument(*flags_of(f), **kw)
    group_of = {f.name: f.metadata["group"] for f in fields(BuildOptions)}
    for flag, (replaced_by, _) in RETIRED_FLAGS.items():  # taken, unlisted: options_from_args names the new flag
        if group_of[replaced_by] in groups:
            p.add_argument(flag, dest=_retired_dest(flag), help=argparse.SUPPRESS, default=None)


def _retired_dest(flag: str) -> str:
    return "retired_" + flag.lstrip("-").replace("-", "_")


def options_from_args(args, groups=IMPORT_GROUPS, **others) -> BuildOptions:
    """BuildOptions holding the flags of ``groups`` in ``args`` and the
    fields ``others`` (the rest default); validated on construction."""
    for flag, (_, message) in RETIRED_FLAGS.items():
        if getattr(args, _retired_dest(flag), None) is not None:
            raise MapkitError(message)
    values = {}
    for f in fields(BuildOptions):
        if f.metadata["group"] in groups:
            v = getattr(args, f.name)
            values[f.name] = list(v or []) if f.type == "list[str]" else v
    try:
        return BuildOptions(**values, **others)
    except OptionError as exc:
        raise exc.as_typed() from None  # the flag the user typed, not the field behind it


def add_import_arguments(p) -> None:
    """Add the plan/mesh import flags to an argparse parser."""
    add_option_flags(p, IMPORT_GROUPS)


def import_options_from_args(args) -> BuildOptions:
    """BuildOptions holding the import flags of ``args`` (other fields default)."""
    return options_from_args(args, IMPORT_GROUPS)

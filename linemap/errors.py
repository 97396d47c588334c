"""The one exception type for bad input, shared by both halves.

An :class:`InputError` says the *input* is wrong (a damaged map, a camera
file without a focal length, a prior of NaN, an option out of range) and
its message, one line, says what to do. Every check of what a user gives
raises it or a subclass (:class:`linemap.lmap.LmapError`,
:class:`linemap.camera.CameraError`, ``mapkit.errors.MapkitError``,
``matcher.tracking.rosbag.BagError``); the command lines print it as
``error: ...`` and exit 2. Any other exception escaping a command is a bug
of ours, reported as one and exit 3, never as the user's fault.

It is a ``ValueError`` so that code written against the API before it
existed (``except ValueError``) keeps catching bad input.
"""

from __future__ import annotations


class InputError(ValueError):
    """Bad input: the message (one line) names the parameter or file and what to do."""


#: Exit code of a command that met a bug of ours (2 is bad input, 1 a valid "not found").
EXIT_BUG = 3
#: The one line of a MemoryError (exit 2): work too large for the memory the
#: process may use is not a bug, and not quite a mistake in the input either.
OUT_OF_MEMORY = "out of memory: the work this input asks for does not fit in the memory this process may use"


def add_debug_option(parser, subparsers=()) -> None:
    """``--debug`` on a command line, before or after the subcommand."""
    import argparse

    text = "on an internal error, print its traceback (for a bug report)"
    parser.add_argument("--debug", action="store_true", help=text)
    for sub in subparsers:  # SUPPRESS: absent there, the top level's value stays
        sub.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=text)


def report_bug(prog: str, exc: BaseException, debug: bool) -> int:
    """Report an exception that is not an :class:`InputError` as what it is,
    a bug: one line on stderr (the traceback before it with ``debug``);
    returns :data:`EXIT_BUG`."""
    import sys
    import traceback

    what = str(exc).strip().splitlines()
    what = f"{type(exc).__name__}: {what[0][:300]}" if what else type(exc).__name__
    if debug:
        traceback.print_exception(type(exc), exc, exc.__traceback__, file=sys.stderr)
        hint = "the traceback is above"
    else:
        hint = "rerun with --debug for the traceback"
    print(f"{prog}: internal error: {what} -- this is a bug, please report it ({hint})", file=sys.stderr)
    return EXIT_BUG

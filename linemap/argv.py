"""Command-line values that start with a minus sign.

argparse reads ``--at -5,-5`` as the option ``--at`` followed by another
option ``-5,-5``, and fails with "expected one argument": only plain
negative numbers are recognised as values. Floor coordinates are negative
as often as not, so both command lines join such a value to its option
(``--at=-5,-5``) before parsing. numpy-free: the matcher's CLI uses it too.
"""

from __future__ import annotations


def join_negative_values(argv: list[str], options: tuple[str, ...]) -> list[str]:
    """``argv`` with ``OPTION -N...`` written ``OPTION=-N...`` for each of
    ``options`` whose next argument is a minus sign then a digit or a dot."""
    out, i = [], 0
    while i < len(argv):
        nxt = argv[i + 1] if i + 1 < len(argv) else ""
        if argv[i] in options and len(nxt) > 1 and nxt[0] == "-" and (nxt[1].isdigit() or nxt[1] == "."):
            out.append(f"{argv[i]}={nxt}")
            i += 2
        else:
            out.append(argv[i])
            i += 1
    return out

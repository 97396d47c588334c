"""The ``mapkit`` command line. Subcommands live in :mod:`mapkit.commands`.

User errors (missing file, bad format, no walls, bad option: an
:class:`~linemap.errors.InputError` or an ``OSError``) print one line
``mapkit: error: ...`` to stderr and exit 2, never a traceback. Any other
exception is a bug: one line ``mapkit: internal error: ...`` asking for a
report, exit 3, and its traceback with ``--debug``.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import pkgutil
import sys

import mapkit.commands
from linemap.argv import join_negative_values
from linemap.atomic import OutputPathError
from linemap.errors import OUT_OF_MEMORY, InputError, add_debug_option, report_bug

#: Order in ``mapkit --help``; any other command module is listed after these.
ORDER = ["build", "info", "query", "export", "layers", "preview", "view", "extrude"]


def _command_modules() -> list[str]:
    found = {m.name for m in pkgutil.iter_modules(mapkit.commands.__path__) if not m.name.startswith("_")}
    return [n for n in ORDER if n in found] + sorted(found - set(ORDER))


class _Parser(argparse.ArgumentParser):
    """argparse that reports bad options in our one-line error style."""

    def error(self, message: str):  # noqa: D401 - argparse API
        self.exit(2, f"mapkit: error: {message} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    from mapkit import __version__

    parser = _Parser(prog="mapkit", description="Build and inspect line maps (.lmap) for robot self-location.")
    parser.add_argument("--version", action="version", version=f"mapkit {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for name in _command_modules():
        mod = importlib.import_module(f"mapkit.commands.{name}")
        p = sub.add_parser(name, help=mod.HELP, description=mod.HELP)
        mod.add_arguments(p)
        p.set_defaults(_run=mod.run)
    add_debug_option(parser, sub.choices.values())
    return parser


class _OneLineWarnings(logging.Handler):
    """Print the importers' and stages' warnings as 'mapkit: warning: ...'."""

    def emit(self, record: logging.LogRecord) -> None:
        print(f"mapkit: {record.levelname.lower()}: {record.getMessage()}", file=sys.stderr)


def _setup_logging() -> None:
    log = logging.getLogger("mapkit")
    if not any(isinstance(h, _OneLineWarnings) for h in log.handlers):
        log.addHandler(_OneLineWarnings(logging.WARNING))
    log.propagate = False
    # ezdxf logs each repair of a damaged file ("recovered invalid integer
    # value ..."); the reader's own one-line warning says what matters, and
    # Python's last-resort handler would print them all to stderr.
    # trimesh likewise logs the formats it tried on a damaged mesh, with tracebacks.
    for name in ("ezdxf", "trimesh"):
        quiet = logging.getLogger(name)
        if not any(isinstance(h, logging.NullHandler) for h in quiet.handlers):
            quiet.addHandler(logging.NullHandler())


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    # '--at -5,-5': a negative X would read as an option.
    args = parser.parse_args(join_negative_values(sys.argv[1:] if argv is None else list(argv), ("--at",)))
    _setup_logging()
    try:
        return int(args._run(args) or 0)
    except InputError as exc:  # MapkitError, LmapError, CameraError, ...
        return _fail(str(exc))
    except OutputPathError as exc:
        return _fail(f"{exc.filename}: {exc.strerror}")
    except FileNotFoundError as exc:
        what = (exc.strerror or "no such file").lower().replace("no such file or directory", "no such file")
        return _fail(f"{exc.filename or exc}: {what}; check the path")
    except BrokenPipeError:  # before OSError, whose subclass it is
        # The reader went away (`mapkit info --json | head`): not an error of ours.
        # Point stdout at devnull so the interpreter's final flush stays quiet.
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except IsADirectoryError as exc:
        return _fail(f"{exc.filename}: is a directory, expected a file")
    except PermissionError as exc:
        return _fail(f"{exc.filename}: permission denied")
    except OSError as exc:  # a full disk, a read-only file system, ...
        return _fail(f"{exc.filename}: {exc.strerror or exc}" if exc.filename else f"{exc.strerror or exc}")
    except MemoryError:
        return _fail(OUT_OF_MEMORY)
    except KeyboardInterrupt:
        print("mapkit: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # noqa: BLE001 - anything else is a bug of ours, said to be one
        return report_bug("mapkit", exc, args.debug)


def _fail(message: str) -> int:
    print(f"mapkit: error: {message}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    raise SystemExit(main())

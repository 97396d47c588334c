"""The benchmarks' tables: markdown printed the same way by every
``tools/bench_*.py``, and ``--report PATH``, which writes what a benchmark
printed into a markdown file under the command line, the git commit and the
machine it was measured on (``docs/benchmarks/*.md``).

    table = Table("PEQ", "ms (median)")      # prints the header
    table.row(3, f"{12.345:.1f}")            # prints "| 3 | 12.3 |" at once

    ap = argparse.ArgumentParser(...)
    add_report_option(ap)
    args = ap.parse_args(argv)
    return reported(args.report, lambda: run(args), __file__, argv)   # report None: no file
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import platform
import shlex
import subprocess
import sys
import time
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path

from linemap.atomic import OutputPathError, check_output_path, write_atomic

def markdown_row(cells: Iterable[object]) -> str:
    """``| a | b |``: the cells as given (format numbers before)."""
    return "| " + " | ".join(str(c) for c in cells) + " |"


def markdown_table(columns: Sequence[str], rows: Iterable[Sequence[object]]) -> str:
    """A whole markdown table (GitHub's), its columns aligned: the cells as
    given, ``str()`` of each (format numbers before; tabulate would reformat
    a number-like text, so it is told not to parse numbers)."""
    from tabulate import tabulate

    return tabulate([[str(c) for c in r] for r in rows], headers=[str(c) for c in columns], tablefmt="github",
                    disable_numparse=True)


def markdown_cells(line: str) -> list[str]:
    """The cells of one table line, stripped: ``"| 1   | 2.5 |"`` -> ``["1", "2.5"]``."""
    return [c.strip() for c in line.strip().strip("|").split("|")]


class Table:
    """A markdown table printed row by row (a benchmark's rows show up as
    they are measured, and a run stopped half-way keeps the rows it had).

    Its own row printer, not tabulate's: tabulate lays a table out whole
    (each column as wide as its widest cell), so it cannot print a row
    before the rows below it are known."""

    def __init__(self, *columns: str, file=None):
        self.columns = columns
        self.file = file
        self._print(markdown_row(columns))
        self._print("|" + "---|" * len(columns))

    def row(self, *cells: object) -> None:
        if len(cells) != len(self.columns):
            raise ValueError(f"{len(cells)} cells for {len(self.columns)} columns")
        self._print(markdown_row(cells))

    def _print(self, line: str) -> None:
        print(line, file=self.file or sys.stdout, flush=True)


# --------------------------------------------------------------------------
# --report: the table in a file, with what it was measured with


def add_report_option(parser) -> None:
    parser.add_argument("--report", metavar="PATH",
                        help="also write what this prints into the markdown file PATH, under the command line, "
                             "the git commit and the machine (default: no file)")


def git_commit(folder: Path) -> str:
    """The commit checked out in ``folder``, and whether tracked files differ from it."""
    def git(*args: str) -> str:
        out = subprocess.run(["git", "-C", str(folder), *args], capture_output=True, text=True)
        return out.stdout.strip() if out.returncode == 0 else ""

    head = git("rev-parse", "--short=12", "HEAD")
    if not head:
        return "unknown (not a git checkout)"
    dirty = git("status", "--porcelain", "--untracked-files=no")
    return head + (" with uncommitted changes" if dirty else "")


def cpu_model() -> str:
    """The CPU's model name (Linux: /proc/cpuinfo), else what platform says."""
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                return line.split(":", 1)[1].strip()
    return platform.processor() or platform.machine()


def cpu_count() -> int:
    """The CPUs this process may run on (``nproc``)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def load_average() -> str:
    return " ".join(f"{v:.2f}" for v in os.getloadavg()) if hasattr(os, "getloadavg") else "unknown"


def report_header(command: Sequence[str], started_load: str, ended_load: str) -> str:
    """The lines above a report's table: how to rerun it (``command``: the
    script, ``tools/NAME.py``, and its arguments) and on what it ran."""
    root = Path(command[0]).resolve().parents[1]
    script = os.path.relpath(Path(command[0]).resolve(), root)
    line = "python " + shlex.join([script, *command[1:]])
    return "\n".join([
        f"Command: `{line}`",
        "",
        f"Commit: {git_commit(root)}",
        "",
        f"Machine: {cpu_count()} CPUs ({cpu_model()}), load average {started_load} at the start and "
        f"{ended_load} at the end (1, 5, 15 minutes); Python {platform.python_version()} on "
        f"{platform.system()} {platform.machine()}",
        "",
        f"Measured: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}",
    ])


class _Tee(io.TextIOBase):
    """Writes to the terminal and keeps a copy."""

    def __init__(self, out):
        self.out, self.kept = out, io.StringIO()

    def write(self, text: str) -> int:
        self.kept.write(text)
        return self.out.write(text)

    def flush(self) -> None:
        self.out.flush()


def reported(path: str | os.PathLike | None, run: Callable[[], int], script: str,
             argv: Sequence[str] | None) -> int:
    """``run()``, its stdout going to the terminal as usual; with a ``path``,
    a run that returns 0 also writes all it printed there, under
    :func:`report_header` for ``python SCRIPT ARGV`` (``argv`` None: this
    process's). The file is replaced whole, never left half written; a
    failed run leaves it as it was; a path that cannot be written is a
    one-line error before the run (exit 2). Returns ``run()``'s code."""
    if path is None:
        return run()
    try:
        check_output_path(path)
    except OutputPathError as exc:
        print(f"error: --report {exc.filename}: {exc.strerror}", file=sys.stderr)
        return 2
    started = load_average()
    tee = _Tee(sys.stdout)
    with contextlib.redirect_stdout(tee):
        code = run()
    if code == 0:
        command = [script, *(sys.argv[1:] if argv is None else argv)]
        write_atomic(path, report_header(command, started, load_average()) + "\n\n"
                     + tee.kept.getvalue().rstrip("\n") + "\n")
        print(f"report: {path}", file=sys.stderr)
    return code


def row_from_child(cmd: Sequence[str]) -> dict:
    """A benchmark's row measured in a fresh interpreter (``cmd``, whose
    last line of output is the row as JSON), so that its peak memory is its
    own; a failed child raises RuntimeError with its last line."""
    done = subprocess.run(list(cmd), capture_output=True, text=True)
    if done.returncode != 0:
        lines = (done.stderr or done.stdout).strip().splitlines()
        raise RuntimeError(lines[-1] if lines else f"exit status {done.returncode}")
    return json.loads(done.stdout.strip().splitlines()[-1])

"""Running a fuzz case: in this process (``run_case_here``: its files
written into the current directory, its call, then its follow-ups), or
bounded in a forked child (``run_bounded``; ``start_case`` and
``finish_case`` for a campaign that runs several at once) under a time
bound and an address-space limit. What each call ended in is
``classify``'s verdict.
"""

from __future__ import annotations

import contextlib
import io
import os
import resource
import signal
import sys
import time
import traceback
from pathlib import Path

from .cases import ROOT, Case, Outcome
from .classify import BUG, ERROR, FALSY, OVER, VALID, classify_cli, classify_input_error


def _api(function: str, args: dict):
    """Run an API case; returns the outcome kind and its detail."""
    import numpy as np

    import matcher

    cam = matcher.Camera.from_dict(args["camera"]) if args.get("camera") else None
    if function == "localize":
        m = matcher.load_map(ROOT / "maps" / "flat.lmap")
        lines = np.load(args["lines"], allow_pickle=True)
        res = matcher.localize(m, cam, lines, args["prior"], args["dt"], args["dyaw"])
        if not res:
            return (FALSY, res.reason) if res.reason else (BUG, "falsy result without a reason")
        return VALID, ""
    kwargs = {} if args.get("min_length") is None else {"min_length": args["min_length"]}
    lines = matcher.detect_lines(np.load(args["image"], allow_pickle=True), cam, **kwargs)
    if not (isinstance(lines, np.ndarray) and lines.ndim == 3 and lines.shape[1:] == (2, 2)
            and np.isfinite(lines).all()):
        return BUG, f"detect_lines returned {type(lines).__name__} {getattr(lines, 'shape', '')}"
    return VALID, ""


def run_case_here(case: Case) -> tuple[str, str]:
    """Run ``case`` in this process, in the current directory (its files
    written there): its call, then each of ``case.then`` while the one
    before ended valid; returns (kind, detail) of the first that did not
    (the detail naming a follow-up's command), or (VALID, ""). May not
    return (a hang)."""
    for fname, blob in case.files.items():
        Path(fname).write_bytes(blob)
    for k, call in enumerate([case.call, *case.then]):
        kind, detail = run_call(call)
        if kind != VALID:
            if k and case.then_valid and kind in (ERROR, FALSY):
                kind, detail = BUG, f"a map the case wrote is refused: {detail}"
            return kind, (f"then {' '.join(map(str, call))}: {detail}" if k else detail)
    return VALID, ""


def run_call(call: list) -> tuple[str, str]:
    """Run one command or API call of a case in the current directory; (kind, detail)."""
    from linemap.errors import InputError

    what = call[0]
    if what == "api":
        try:
            return _api(call[1], call[2])
        except InputError as exc:
            return classify_input_error(str(exc))
        except MemoryError:
            return OVER, "MemoryError"
        except Exception:  # noqa: BLE001 - the point of the exercise: any other exception is a bug, ValueError too
            return BUG, traceback.format_exc()[-2000:]
    argv = [a.replace("{ROOT}", str(ROOT)) if isinstance(a, str) else a for a in call[1:]]
    if what == "mapkit":
        from mapkit.cli import main
    else:
        from matcher.cli import main
    out, err = io.StringIO(), io.StringIO()
    code = None
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except SystemExit as exc:  # argparse's errors
                code = exc.code
    except MemoryError:
        return OVER, "MemoryError"
    except Exception:  # noqa: BLE001
        said = err.getvalue()[-500:]
        return BUG, (f"stderr: {said}\n" if said else "") + traceback.format_exc()[-2000:]
    return classify_cli(what, code, out.getvalue(), err.getvalue())


def _child(case: Case, folder: Path, conn, mem_bytes: int) -> None:
    """The forked child: limit its address space, run ``case`` in ``folder``
    with fd 2 silenced, send (kind, detail) and exit without cleanup."""
    try:
        resource.setrlimit(resource.RLIMIT_AS, (mem_bytes, mem_bytes))
        folder.mkdir(parents=True, exist_ok=True)
        os.chdir(folder)
        with open(os.devnull, "w") as null:  # C libraries' own complaints on fd 2
            os.dup2(null.fileno(), 2)
        result = run_case_here(case)
    except BaseException as exc:  # noqa: BLE001
        result = (OVER, "MemoryError") if isinstance(exc, MemoryError) else (BUG, repr(exc))
    try:
        conn.send(result)
    finally:
        os._exit(0)


def start_case(case: Case, folder: Path, mem_gb: float):
    """Fork a child running ``case`` in ``folder``; returns (pid, connection, start time)."""
    import multiprocessing

    recv, send = multiprocessing.Pipe(duplex=False)
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:
        recv.close()
        _child(case, folder, send, int(mem_gb * 2 ** 30))
    send.close()
    return pid, recv, time.monotonic()


def finish_case(pid: int, conn, t0: float, bound_s: float, block: bool = True) -> Outcome | None:
    """The outcome of a started case (None if still running and not ``block``)."""
    left = bound_s - (time.monotonic() - t0)
    if conn.poll(max(left, 0) if block else 0):
        try:
            kind, detail = conn.recv()
        except EOFError:  # the child died without a word: a crash
            kind, detail = BUG, "child died"
        _, status = os.waitpid(pid, 0)
        if os.WIFSIGNALED(status):
            kind, detail = BUG, f"killed by signal {os.WTERMSIG(status)}"
        conn.close()
        return Outcome(kind, detail, time.monotonic() - t0)
    if time.monotonic() - t0 < bound_s:
        return None
    os.kill(pid, signal.SIGKILL)
    os.waitpid(pid, 0)
    conn.close()
    return Outcome(OVER, f"still running after {bound_s:g} s", time.monotonic() - t0)


def run_bounded(case: Case, folder: Path, bound_s: float = 60.0, mem_gb: float = 3.0) -> Outcome:
    """Run ``case`` in a forked child in ``folder`` under a time bound and an
    address-space limit."""
    out = finish_case(*start_case(case, folder, mem_gb), bound_s)
    out.case = case
    return out

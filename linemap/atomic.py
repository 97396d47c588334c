"""Atomic file output: a reader sees the old file or the whole new one, never half.

An output that is a symbolic link is written through it (the link stays,
its target gets the new contents, atomically); an output that is one of the
command's inputs is refused before any work (writing it would destroy what
is being read); the temporary files a killed run left beside an output are
removed by the next write to it. Standard library only (the numpy-only
format module uses it too).
"""

from __future__ import annotations

import contextlib
import errno
import os
import tempfile
import time
from pathlib import Path
from typing import IO, Iterator


class OutputPathError(OSError):
    """A file cannot be written at the path given; ``filename`` is that
    path (or its folder), ``strerror`` says why and what to do."""


#: Temporary files of ours older than this many seconds beside an output are
#: a killed run's leftovers (a live write renames its own within seconds).
STALE_TEMP_S = 60.0


def check_output_path(path: str | os.PathLike, inputs=()) -> Path:
    """The path to write for ``path`` (a symbolic link's target, so that
    the link stays) if a file can be written there and it is none of the
    files ``inputs``; else :class:`OutputPathError`. Commands call it before
    their work, so that a wrong ``-o`` fails at once, and the error names
    the path asked for, not the temporary file written beside it."""
    asked = Path(path)
    for inp in inputs:
        if inp is not None and _same_file(asked, Path(inp)):
            raise OutputPathError(errno.EEXIST, f"is also the input {inp}: writing it would destroy what is read; "
                                  "choose another output path", str(asked))
    path = asked.resolve() if asked.is_symlink() else asked
    parent = path.parent if str(path.parent) else Path(".")
    if path.is_dir():
        raise OutputPathError(errno.EISDIR, "is a directory; give a file name", str(path))
    if not parent.exists():
        raise OutputPathError(errno.ENOENT, "output folder does not exist; create it first", str(parent))
    if not parent.is_dir():
        raise OutputPathError(errno.ENOTDIR, "is a file, not a folder; choose another output path", str(parent))
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputPathError(errno.EACCES, "output folder is not writable (permission denied)", str(parent))
    # The rename below would put a regular file in place of a device or a
    # pipe (-o /dev/null, run as root, would replace /dev/null).
    if path.exists() and not path.is_file():
        raise OutputPathError(errno.EINVAL, "is not a regular file (a device or a pipe); give a file name", str(path))
    # The rename below needs only the folder's permission, so it would replace
    # a file its owner made read-only; refuse, as rm asks before removing one
    # (the mode bits, not os.access: that says yes to root whatever the mode).
    if path.exists() and (not os.access(path, os.W_OK) or not path.stat().st_mode & 0o222):
        raise OutputPathError(errno.EACCES, "is read-only; make it writable (chmod u+w) or choose another "
                              "output path", str(path))
    return path


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, mode: str = "wb") -> Iterator[IO]:
    """Open a temporary file beside ``path``; on success rename it over ``path``.

    If the body raises, the temporary file is removed and ``path`` is left as
    it was (absent, or the previous version)."""
    path = check_output_path(path)
    parent = path.parent if str(path.parent) else Path(".")
    _remove_stale_temporaries(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=parent)
    except OSError as exc:  # a read-only file system, a special folder, ...
        raise OutputPathError(exc.errno, f"cannot create a file there ({exc.strerror})", str(path)) from None
    try:
        with os.fdopen(fd, mode) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        # mkstemp makes the file private (0600); give it the mode a plain open() would.
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def _same_file(a: Path, b: Path) -> bool:
    """Do ``a`` and ``b`` name one file (links and relative paths followed)?"""
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
        return a.resolve() == b.resolve()
    except OSError:
        return False


def _remove_stale_temporaries(path: Path) -> None:
    """Remove the temporary files beside ``path`` that a killed write left:
    only names this module makes for it (``.NAME.XXXXXXXX.tmp``, mkstemp's
    eight characters) and older than :data:`STALE_TEMP_S`."""
    parent = path.parent if str(path.parent) else Path(".")
    now = time.time()
    for tmp in parent.glob(f".{_glob_escape(path.name)}.????????.tmp"):
        with contextlib.suppress(OSError):
            if tmp.is_file() and not tmp.is_symlink() and now - tmp.stat().st_mtime > STALE_TEMP_S:
                tmp.unlink()


def _glob_escape(name: str) -> str:
    """``name`` with glob's special characters taken literally."""
    return "".join(f"[{c}]" if c in "*?[" else c for c in name)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_atomic(path: str | os.PathLike, data: bytes | str) -> None:
    """Write all of ``data`` to ``path`` atomically."""
    with atomic_output(path, "wb" if isinstance(data, bytes) else "w") as fh:
        fh.write(data)

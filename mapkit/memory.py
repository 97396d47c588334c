"""Memory between the steps of a build."""

from __future__ import annotations


def release_memory() -> None:
    """Hand the memory freed so far back to the system (glibc's malloc_trim).

    GEOS allocates each geometry in many small blocks; freed, they stay in
    the process's heap, so without this each step's high-water mark would
    add to the next one's instead of being reused. A no-op elsewhere."""
    import ctypes
    import ctypes.util

    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.malloc_trim(0)
    except (OSError, AttributeError):
        pass


__all__ = ["release_memory"]

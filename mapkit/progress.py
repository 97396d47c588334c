"""Progress on a terminal: a tqdm bar for each build step that may take a
while. The quadtree, which loops over its levels, shows a bar of its own;
the other steps show their name and, once done, are cleared. Disabled (no output at all) unless the caller
asks, which ``mapkit build`` does only when stderr is a terminal."""

from __future__ import annotations

from contextlib import contextmanager


@contextmanager
def step(desc: str, enabled: bool):
    """Show ``desc`` while the block runs (when ``enabled``)."""
    if not enabled:
        yield
        return
    from tqdm import tqdm

    bar = tqdm(total=1, desc=desc, leave=False, bar_format="{desc} ... {elapsed}")
    try:
        yield
    finally:
        bar.update(1)
        bar.close()


__all__ = ["step"]

"""A picture of what the importer understood of a plan: walls, openings, free space.

Draws from the :class:`~mapkit.scene.Scene` only, so plans and meshes
preview alike. The PNG is written atomically (temporary file, then rename).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import LineString, Polygon

from mapkit.scene import Scene

#: Colours per element (walls dark, free space light, doors and windows distinct).
COLOURS = {
    "walls": "#2b2b2b",
    "free": "#cfe8cf",
    "door": "#e07b00",
    "window": "#1f77d0",
    "obstacle": "#9ecae1",
    "ignored": "#a8a8a8",
}


def render_preview(scene: Scene, out: str | Path, title: str | None = None, dpi: int = 150) -> Path:
    """Write a PNG of ``scene`` to ``out`` (atomically) and return its path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    out = Path(out)
    bounds = _bounds(scene)
    width, height = bounds[2] - bounds[0], bounds[3] - bounds[1]
    aspect = height / width if width > 0 else 1.0
    fig_w = 12.0
    fig, ax = plt.subplots(figsize=(fig_w, max(3.0, min(fig_w * aspect, 14.0)) + 1.0))
    try:
        for geom in scene.ignored.values():
            _draw_lines(ax, geom, color=COLOURS["ignored"], lw=0.5, alpha=0.7, zorder=3)
        _fill(ax, scene.free_space, COLOURS["free"], zorder=2)
        _fill(ax, scene.obstacles, COLOURS["obstacle"], zorder=3, edge=COLOURS["window"])
        _fill(ax, scene.walls, COLOURS["walls"], zorder=4)
        for o in scene.openings:
            colour = COLOURS["door"] if o.kind == "door" else COLOURS["window"]
            _fill(ax, o.footprint, colour, zorder=5, edge=colour)
        handles = [
            Patch(color=COLOURS["walls"], label=f"walls ({scene.walls.area:.1f} m²)"),
            Patch(color=COLOURS["free"], label=f"free space ({scene.free_space.area:.1f} m²)"),
            Patch(color=COLOURS["door"], label=f"doors ({sum(o.kind == 'door' for o in scene.openings)})"),
            Patch(color=COLOURS["window"], label=f"windows ({sum(o.kind == 'window' for o in scene.openings)})"),
        ]
        if not scene.obstacles.is_empty:
            handles.append(Patch(color=COLOURS["obstacle"], label="glass / obstacles"))
        if scene.ignored:
            handles.append(Line2D([], [], color=COLOURS["ignored"], label="ignored layers"))
        ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9, frameon=False)
        _scale_bar(ax, bounds)
        ax.set_aspect("equal")
        margin = 0.03 * max(width, height, 1.0)
        ax.set_xlim(bounds[0] - margin, bounds[2] + margin)
        ax.set_ylim(bounds[1] - 2.5 * margin, bounds[3] + margin)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.tick_params(labelsize=8)
        if title:
            ax.set_title(title, fontsize=10)
        fig.tight_layout()
        _save_atomic(fig, out, dpi)
    finally:
        plt.close(fig)
    return out


def _bounds(scene: Scene) -> tuple[float, float, float, float]:
    geoms = [scene.walls, scene.free_space, scene.obstacles]
    geoms = [g for g in geoms if g is not None and not g.is_empty]
    if not geoms:
        return (0.0, 0.0, 1.0, 1.0)
    b = np.array([g.bounds for g in geoms])
    return (b[:, 0].min(), b[:, 1].min(), b[:, 2].max(), b[:, 3].max())


def _fill(ax, geom, colour: str, zorder: int, edge: str | None = None) -> None:
    from matplotlib.patches import PathPatch
    from matplotlib.path import Path as MplPath

    for poly in shapely.get_parts(geom):
        if not isinstance(poly, Polygon) or poly.is_empty:
            continue
        rings = [np.asarray(poly.exterior.coords)[:, :2]] + [np.asarray(r.coords)[:, :2] for r in poly.interiors]
        verts = np.concatenate(rings)
        codes = np.concatenate(
            [[MplPath.MOVETO] + [MplPath.LINETO] * (len(r) - 2) + [MplPath.CLOSEPOLY] for r in rings]
        )
        patch = PathPatch(MplPath(verts, codes), facecolor=colour, edgecolor=edge or "none", lw=0.5, zorder=zorder)
        ax.add_patch(patch)


def _draw_lines(ax, geom, **style) -> None:
    from matplotlib.collections import LineCollection

    segs = [np.asarray(g.coords)[:, :2] for g in shapely.get_parts(geom) if isinstance(g, LineString)]
    if segs:
        ax.add_collection(LineCollection(segs, **style))


def _scale_bar(ax, bounds) -> None:
    """A bar of a round length (1, 2, 5 x 10^k m) about a fifth of the width, below the plan."""
    width = bounds[2] - bounds[0]
    raw = max(width / 5.0, 1e-3)
    exp = math.floor(math.log10(raw))
    length = min((m * 10**exp for m in (1, 2, 5, 10)), key=lambda v: abs(v - raw))
    margin = 0.03 * max(width, bounds[3] - bounds[1], 1.0)
    x0, y0 = bounds[0], bounds[1] - 1.5 * margin
    ax.plot([x0, x0 + length], [y0, y0], color="black", lw=3, solid_capstyle="butt", zorder=6)
    ax.text(x0 + length / 2, y0 + 0.3 * margin, f"{length:g} m", ha="center", va="bottom", fontsize=8, zorder=6)


def _save_atomic(fig, out: Path, dpi: int) -> None:
    """Render to a temporary file beside ``out``, then rename: no half-written PNG is ever seen."""
    from linemap.atomic import atomic_output

    with atomic_output(out) as fh:
        fig.savefig(fh, dpi=dpi, format="png")

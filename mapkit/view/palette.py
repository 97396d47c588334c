"""Colours of the inspector: segment kinds, regions and highlights (RGB 0-255).

Kinds get saturated colours, regions lighter ones, so that segments lying on the
floor stay readable over the region fills. Highlights use hues no kind or
region uses, so the browser test can find them in a screenshot.
"""

from __future__ import annotations

import numpy as np

from linemap.lmap import SegmentKind

#: One colour per segment kind; the legend lists them in this order.
KIND_COLOURS: dict[SegmentKind, tuple[int, int, int]] = {
    SegmentKind.FLOOR: (31, 119, 180),  # blue
    SegmentKind.CEILING: (44, 160, 44),  # green
    SegmentKind.VERTICAL: (214, 39, 40),  # red
    SegmentKind.JAMB: (148, 103, 189),  # purple
    SegmentKind.LINTEL: (140, 86, 75),  # brown
    SegmentKind.WINDOW: (23, 190, 207),  # cyan
    SegmentKind.HORIZONTAL: (127, 127, 127),  # grey
    SegmentKind.OBLIQUE: (188, 189, 34),  # olive
}

#: Light qualitative colours for region fills; neighbours never share one
#: while the palette has enough colours for the neighbourhood (greedy colouring).
REGION_PALETTE = np.array(
    [
        (120, 180, 230), (150, 215, 110), (245, 130, 125), (250, 175, 80),
        (185, 150, 215), (245, 235, 110), (100, 200, 180), (230, 150, 200),
        (170, 170, 170), (190, 225, 160), (120, 150, 200), (215, 190, 140),
    ],
    dtype=np.uint8,
)

OUTLINE = (90, 90, 90)
WALL = (150, 160, 175)
#: The clicked region and its visible segments.
SELECTED_REGION = (255, 0, 255)
SELECTED_SEGMENTS = (255, 0, 160)
#: The pose tool: uncertainty disk, retained regions, candidates.
POSE_DISK = (255, 120, 0)
RETAINED_REGION = (255, 170, 60)
CANDIDATE = (255, 140, 0)
CANDIDATE_OUT_OF_VIEW = (200, 200, 200)
FRUSTUM = (255, 120, 0)
#: A matcher result: estimated pose, matched segments, image-line rays.
RESULT_POSE = (0, 170, 90)
MATCHED = (0, 200, 120)
RAYS = (0, 140, 255)
#: The plan overlay (--plan).
PLAN_WALLS = (60, 60, 60)
PLAN_FREE = (0, 120, 200)


def colour_regions(n: int, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """(n,) palette index per region such that touching regions differ.

    ``(i, j)`` are the adjacent pairs (both orders or either). Greedy in
    region order: deterministic, and a few thousand regions take milliseconds.
    """
    order = np.argsort(i, kind="stable")
    i, j = np.asarray(i)[order], np.asarray(j)[order]
    starts = np.searchsorted(i, np.arange(n + 1))
    k = len(REGION_PALETTE)
    colour = np.full(n, -1, dtype=np.int64)
    for r in range(n):
        used = colour[j[starts[r] : starts[r + 1]]]
        free = np.ones(k, dtype=bool)
        free[used[used >= 0] % k] = False
        # Start the search at r % k so that colours spread evenly over the map.
        cand = np.roll(np.arange(k), -(r % k))
        ok = cand[free[cand]]
        colour[r] = ok[0] if len(ok) else r % k
    return colour


def legend_html(interactive: bool = True) -> str:
    """HTML rows: a coloured swatch and the name of every segment kind and
    overlay (``interactive=False``: only what a static snapshot shows)."""
    rows = [(KIND_COLOURS[k], f"{k.label} segments") for k in SegmentKind]
    rows += [(WALL, "walls (extruded)"), (REGION_PALETTE[0], "regions")]
    if not interactive:
        rows += [(MATCHED, "matched segments (result)"), (RAYS, "image lines as rays (result)")]
    else:
        rows += [
            (SELECTED_REGION, "clicked region"),
            (SELECTED_SEGMENTS, "its visible segments"),
            (POSE_DISK, "pose: disk, retained regions"),
            (CANDIDATE, "candidates in view"),
            (CANDIDATE_OUT_OF_VIEW, "candidates out of view"),
            (MATCHED, "matched segments (result)"),
            (RAYS, "image lines as rays (result)"),
        ]
    cells = "".join(
        f'<div style="display:flex;align-items:center;gap:6px;font-size:12px">'
        f'<span style="display:inline-block;width:14px;height:14px;border-radius:2px;'
        f'background:rgb({int(c[0])},{int(c[1])},{int(c[2])})"></span>{name}</div>'
        for c, name in rows
    )
    # Two columns: the legend stays short enough to leave the pose tool in view.
    return f'<div style="display:grid;grid-template-columns:1fr 1fr;gap:2px 8px;padding:4px 0">{cells}</div>'

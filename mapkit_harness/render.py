"""Grey images of a map seen from a pose, for testing the image path end to end.

What a camera sees (:class:`VisibleSurfaces`): the map's wall outlines
extruded from the floor (z = 0) to ``meta["wall_height"]`` (the simulator's
occluders, :mod:`mapkit_harness.simulate`), a flat
floor and a flat ceiling, and across the door and window openings the walls
above their heads and below their sills, with the slabs between the wall's
two faces (from the map's LINTEL and WINDOW segments). Each pixel's ray is
cast against them (in blocks of columns, each block against the surfaces
within its bearings); the nearest surface gives its grey level. Wall
faces are shaded by their orientation (a light from one side), so two walls
meeting at a corner differ and the corner shows as an edge, as do the
wall/floor and wall/ceiling junctions; a ray that leaves the building
through an opening meets a plain grey background. Rendered ``supersample``
times larger and averaged down (anti-aliased edges), lightly blurred, with
seeded Gaussian noise: the edges LSD meets in a real frame, at known
geometry.

    python tools/render.py --pose 2.0,1.5,30 -o view.png
"""

from __future__ import annotations

import copy
import math

import cv2
import numpy as np

from linemap.camera import Camera
from linemap.geometry import in_field_of_view
from linemap.lmap import SegmentKind
from matcher.map_geometry.freespace import free_space
from matcher.map_geometry.occlusion import inside_walls, wall_edges

LINTEL, WINDOW = SegmentKind.LINTEL, SegmentKind.WINDOW

#: Grey levels: floor, ceiling, and the range of wall shades.
FLOOR_GREY = 45.0
CEILING_GREY = 225.0
WALL_GREY = (95.0, 175.0)
#: Grey levels of a window sill's top and of the underside of a door or
#: window head.
SILL_GREY = 205.0
HEAD_GREY = 70.0
#: The two faces of a wall across an opening are at most this far apart, metres.
_OPENING_DEPTH_M = 0.6
#: What a ray that leaves the building through an opening sees.
OUTSIDE_GREY = 135.0
#: Floor and ceiling end this far, metres, from the map's regions (the floor
#: the robot's centre reaches) where no wall bounds them: an open doorway.
_FLOOR_REACH_M = 0.3
#: Direction of the light that shades the walls, degrees from the x axis: off
#: the axes, so that walls at right angles get different shades.
LIGHT_DEG = 20.0
#: Sigma of the Gaussian blur of a rendered panorama, pixels.
BLUR_PX = 0.6
#: Column blocks a panorama and a view are cast in (each against the walls in
#: its bearings; more blocks, fewer walls per ray, more passes). The image
#: is the same for any count; these were the fastest of the counts tried
#: on the example flat (views and a panorama of maps/flat.lmap timed with
#: time.process_time at 64 to 200 and 48 to 192 blocks).
_PANO_BLOCKS = 96
_VIEW_BLOCKS = 160
#: Pixels cast per batch (bounds the (pixels, walls) arrays).
_CHUNK = 65536


def render_view(linemap, camera: Camera, pose, supersample: int = 3, blur_px: float = 0.6, noise: float = 2.0,
                rng=None) -> np.ndarray:
    """(height, width) uint8 image of ``linemap`` from ``pose`` ``(x, y,
    yaw_deg)`` through the ideal pinhole ``camera`` (no distortion).

    ``supersample``: rays per pixel along each axis; ``blur_px``: sigma of
    the Gaussian blur, pixels (0: none); ``noise``: sigma of the Gaussian
    noise, grey levels, drawn from ``rng`` (a numpy Generator; seeded 0 if
    None)."""
    if supersample < 1:
        raise ValueError(f"supersample must be >= 1, got {supersample}")
    s = int(supersample)
    W, H = camera.width * s, camera.height * s
    # Pixel (i, j) of the large image has its centre at ((j + 0.5) / s - 0.5,
    # (i + 0.5) / s - 0.5) in the camera's pixels: averaging s x s blocks
    # brings each back to the centre of its camera pixel.
    u = (np.arange(W) + 0.5) / s - 0.5
    v = (np.arange(H) + 0.5) / s - 0.5
    R = camera.world2cam(math.radians(pose[2]))

    def rays_of(cols):
        return camera.pixel_rays(np.stack(np.meshgrid(u[cols], v), axis=-1).reshape(-1, 2)) @ R  # R^T ray

    surfaces = VisibleSurfaces(linemap, camera, pose)
    grey = shade_column_blocks(linemap, pose[:2], camera.height_m, rays_of, (H, W), surfaces, _VIEW_BLOCKS)
    if s > 1:
        grey = cv2.resize(grey, (camera.width, camera.height), interpolation=cv2.INTER_AREA)
    if blur_px > 0:
        grey = cv2.GaussianBlur(grey, (0, 0), blur_px)
    rng = np.random.default_rng(0) if rng is None else rng
    grey = grey + rng.normal(0.0, noise, grey.shape)
    return np.clip(np.rint(grey), 0, 255).astype(np.uint8)


def render_panorama(linemap, pose, height_m: float, width: int, yaw_offset_deg: float = 0.0, supersample: int = 2,
                    noise: float = 2.0, rng=None) -> np.ndarray:
    """(width / 2, width) uint8 equirectangular panorama of ``linemap`` taken
    from ``pose`` ``(x, y, yaw_deg)`` (the robot's) at ``height_m`` metres,
    in :mod:`matcher.panorama`'s convention (centre column along the robot's
    heading plus ``yaw_offset_deg``, columns clockwise, up at the top).

    Every (supersampled) pixel's exact direction is cast as in
    :func:`render_view`, so a wall's edges are where the panorama shows them
    (curves, for the horizontal ones) and a pinhole view cut from it sees
    them straight. ``supersample``, ``noise``, ``rng`` as there; blurred by
    ``BLUR_PX``."""
    from matcher.panorama import pixel_directions

    if supersample < 1:
        raise ValueError(f"supersample must be >= 1, got {supersample}")
    if width < 8 or width % 2:
        raise ValueError(f"panorama width must be an even number of pixels >= 8, got {width}")
    s, x, y, yaw = int(supersample), float(pose[0]), float(pose[1]), math.radians(pose[2])
    W, H = width * s, width // 2 * s
    u = (np.arange(W) + 0.5) / s - 0.5  # the centres of the large image's pixels, in the panorama's
    v = (np.arange(H) + 0.5) / s - 0.5
    c, sn = math.cos(yaw), math.sin(yaw)
    to_world = np.array([[c, sn, 0.0], [-sn, c, 0.0], [0.0, 0.0, 1.0]])  # row vectors: robot frame -> world
    surfaces = VisibleSurfaces(linemap, None, pose)

    def rays_of(cols):
        uv = np.stack(np.meshgrid(u[cols], v), axis=-1).reshape(-1, 2)
        return pixel_directions(uv, width, yaw_offset_deg) @ to_world

    grey = shade_column_blocks(linemap, (x, y), height_m, rays_of, (H, W), surfaces, _PANO_BLOCKS)
    if s > 1:
        grey = cv2.resize(grey, (width, width // 2), interpolation=cv2.INTER_AREA)
    # Blurred along rows with the seam wrapped (the two ends are neighbours).
    pad = 4 * max(1, math.ceil(BLUR_PX))
    grey = cv2.GaussianBlur(np.hstack([grey[:, -pad:], grey, grey[:, :pad]]), (0, 0), BLUR_PX)[:, pad:-pad]
    rng = np.random.default_rng(0) if rng is None else rng
    grey = grey + rng.normal(0.0, noise, grey.shape)
    return np.clip(np.rint(grey), 0, 255).astype(np.uint8)


def shade_column_blocks(linemap, xy, h: float, rays_of, shape: tuple[int, int], surfaces: "VisibleSurfaces",
                        blocks: int) -> np.ndarray:
    """(H, W) float32 grey levels of an image of ``shape`` (H, W) whose
    column indices ``cols`` look along the world directions ``rays_of(cols)``
    ((H * len(cols), 3), row-major), seen from ``xy`` at height ``h``.

    Cast in ``blocks`` blocks of columns, each against only the surfaces
    within its rays' bearings: a ray meets only the walls ahead of it, and
    the (rays, walls) arrays of a whole image against every wall are what
    makes rendering slow. The cut is conservative (the bearings' spread plus
    half a degree), so the image is the one cast against every surface."""
    H, W = shape
    sliver = Camera.from_fov(1.0, 8, 8, h, 0.0)  # the bearing test's camera: half a degree each side
    out = []
    for cols in np.array_split(np.arange(W), max(1, min(blocks, W))):
        rays = rays_of(cols)
        near = surfaces
        # The block's bearings reach their extremes on its outline: a
        # bearing is an angle about the image of the vertical through the
        # camera, a point outside the block (else the outline's bearings go
        # all the way round and nothing is cut).
        grid = rays.reshape(H, len(cols), 3)
        outline = np.concatenate([grid[0], grid[-1], grid[:, 0], grid[:, -1]])
        level = np.hypot(outline[:, 0], outline[:, 1])
        if level.min() > 1e-6:  # (a ray straight up or down has no bearing: that block meets everything)
            azimuth = np.arctan2(outline[:, 1], outline[:, 0])
            mid = math.atan2(np.sin(azimuth).sum(), np.cos(azimuth).sum())
            half = float(np.abs(np.angle(np.exp(1j * (azimuth - mid)))).max())
            if half < math.pi / 2:
                near = surfaces.subset(*surfaces.bearing_masks(sliver, (xy[0], xy[1], mid), half))
        out.append(shade_directions(linemap, xy, h, rays, near, len(cols)).reshape(H, len(cols)))
    return np.hstack(out)


def shade_directions(linemap, xy, h: float, rays: np.ndarray, surfaces: "VisibleSurfaces", columns: int = 0
                     ) -> np.ndarray:
    """(P,) float32 grey level seen along world directions ``rays`` (P, 3)
    from the point ``xy`` (2,) at height ``h`` metres, among ``surfaces``;
    ``columns``: the rays are rows of that many columns (see
    :meth:`VisibleSurfaces.first_panel`)."""
    top = float(linemap.meta.get("wall_height", 2.5))
    free = free_space(linemap)
    origin = np.array([float(xy[0]), float(xy[1])])
    out = np.empty(len(rays), dtype=np.float32)
    chunk = _CHUNK // columns * columns if 0 < columns <= _CHUNK else _CHUNK  # whole rows
    for i0 in range(0, len(rays), chunk):
        d = rays[i0:i0 + chunk]
        # Floor or ceiling, whichever the ray meets (rays along the horizon
        # meet neither).
        with np.errstate(divide="ignore"):
            s_plane = np.where(d[:, 2] < 0, -h / d[:, 2], np.where(d[:, 2] > 0, (top - h) / d[:, 2], np.inf))
        grey = np.where(d[:, 2] < 0, FLOOR_GREY, CEILING_GREY).astype(np.float32)
        s_panel, panel = surfaces.first_panel(origin, h, d, columns)
        s_slab, slab = surfaces.first_slab(origin, h, d)
        hit = (s_panel < s_plane) & (s_panel <= s_slab)
        grey[hit] = surfaces.panel_grey[panel[hit]]
        on_slab = (s_slab < s_plane) & (s_slab < s_panel)
        grey[on_slab] = surfaces.slab_grey[slab[on_slab]]
        # Nothing ahead but the floor or ceiling planes: the point seen is
        # past an opening unless it lies by the map's regions.
        out_of = np.isinf(s_panel) & np.isinf(s_slab)
        if out_of.any():
            reach = np.full(int(out_of.sum()), np.inf)
            finite = np.isfinite(s_plane[out_of])
            at = origin + s_plane[out_of][finite, None] * d[out_of][finite, :2]
            reach[finite] = free.distance(at)
            grey[out_of] = np.where(reach <= _FLOOR_REACH_M, grey[out_of], OUTSIDE_GREY)
        out[i0:i0 + chunk] = grey
    return out


def _nearest(s: np.ndarray, which: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each row's least value of ``s`` (P, n) and the entry of ``which`` (n,) it is in (the first of equals)."""
    i = s.argmin(axis=1)
    return s[np.arange(len(s)), i], which[i]


class VisibleSurfaces:
    """The surfaces a camera at ``pose`` can see, in the floor plane.

    ``panels``: vertical faces along 2D edges ``a, b`` (E, 2) between
    heights ``zlo, zhi`` (E,): the walls (all heights) and, across each door
    or window opening, the wall above its head and below its sill (the
    map's LINTEL and WINDOW segments on the wall faces). ``slabs``:
    horizontal faces, convex quads (Q, 4, 2) at heights ``slab_z`` (Q,):
    the sills' tops and the heads' undersides, between the two faces of the
    wall. Only surfaces some pixel's ray can meet are kept."""

    def __init__(self, linemap, camera: Camera | None, pose) -> None:
        """``camera`` None: every surface (a panorama sees all round)."""
        yaw = math.radians(pose[2])
        top = float(linemap.meta.get("wall_height", 2.5))
        walls = wall_edges(linemap)
        a, b = (np.zeros((0, 2)), np.zeros((0, 2))) if walls is None else walls
        grey = _panel_shades(a, b, _room_normals(a, b, walls))
        zlo, zhi = np.full(len(a), -np.inf), np.full(len(a), np.inf)
        pa, pb, plo, phi, pgrey, quads, qz, qgrey = _openings(linemap, top)
        self.a, self.b = np.concatenate([a, pa]), np.concatenate([b, pb])
        self.zlo, self.zhi = np.concatenate([zlo, plo]), np.concatenate([zhi, phi])
        self.panel_grey = np.concatenate([grey, pgrey]).astype(np.float32)
        z0 = np.zeros((len(self.a), 1))
        as_segments = np.stack([np.hstack([self.a, z0]), np.hstack([self.b, z0])], axis=1)
        keep = np.ones(len(self.a), dtype=bool) if camera is None else \
            in_field_of_view(as_segments, camera, (pose[0], pose[1], yaw), 0.0, 0.0)
        self.a, self.b, self.zlo, self.zhi = self.a[keep], self.b[keep], self.zlo[keep], self.zhi[keep]
        self.panel_grey = self.panel_grey[keep]
        self.quads, self.slab_z, self.slab_grey = quads, qz, qgrey.astype(np.float32)

    def bearing_masks(self, camera: Camera, pose, half_width: float) -> tuple[np.ndarray, np.ndarray]:
        """(E,) and (Q,) bool: the panels and slabs some heading within
        ``half_width`` radians of ``pose``'s yaw (radians) has within
        ``camera``'s field of view (a convex slab spans the bearings of its
        two diagonals)."""
        def within(a, b):
            z0 = np.zeros((len(a), 1))
            segments = np.stack([np.hstack([a, z0]), np.hstack([b, z0])], axis=1)
            return in_field_of_view(segments, camera, pose, 0.0, half_width)

        q = self.quads
        return within(self.a, self.b), within(q[:, 0], q[:, 2]) | within(q[:, 1], q[:, 3])

    def subset(self, panels: np.ndarray, slabs: np.ndarray) -> "VisibleSurfaces":
        """These surfaces with only the ``panels`` (E,) and ``slabs`` (Q,) kept (bool)."""
        out = copy.copy(self)
        out.a, out.b, out.zlo, out.zhi = self.a[panels], self.b[panels], self.zlo[panels], self.zhi[panels]
        out.panel_grey = self.panel_grey[panels]
        out.quads, out.slab_z, out.slab_grey = self.quads[slabs], self.slab_z[slabs], self.slab_grey[slabs]
        return out

    def first_panel(self, origin: np.ndarray, h: float, d: np.ndarray, columns: int = 0
                    ) -> tuple[np.ndarray, np.ndarray]:
        """For rays ``(origin, h) + s d`` (d (P, 3)): the smallest s > 0 at
        which each meets a panel within its heights (inf if none), and that
        panel's index (0 if none).

        ``columns``: the rays are rows of that many columns (row-major). When
        every column's rays share their level direction exactly (a level
        pinhole camera's columns), a wall of the full height is met at the
        same s by a whole column, so walls are cast once a column and only
        the openings' panels once a ray: the same values, a fraction of the
        work."""
        if not len(self.a):
            return np.full(len(d), np.inf), np.zeros(len(d), dtype=np.int64)
        full = np.isinf(self.zlo) & np.isinf(self.zhi)
        if columns and len(d) % columns == 0 and full.any():
            level = d[:, :2].reshape(-1, columns, 2)
            if (level == level[:1]).all():
                return self._first_panel_by_column(origin, h, d, columns, full)
        return _nearest(self._panel_hits(origin, h, d, np.arange(len(self.a))), np.arange(len(self.a)))

    def _first_panel_by_column(self, origin, h, d, columns: int, full: np.ndarray):
        walls, openings = np.flatnonzero(full), np.flatnonzero(~full)
        s_wall, i_wall = _nearest(self._panel_hits(origin, h, d[:columns], walls), walls)
        s, i = np.tile(s_wall, len(d) // columns), np.tile(i_wall, len(d) // columns)
        if len(openings):
            s_open, i_open = _nearest(self._panel_hits(origin, h, d, openings), openings)
            # The first of equal values in the panels' order, as one argmin over all of them picks.
            nearer = (s_open < s) | ((s_open == s) & (i_open < i))
            s, i = np.where(nearer, s_open, s), np.where(nearer, i_open, i)
        return s, np.where(np.isinf(s), 0, i)

    def _panel_hits(self, origin: np.ndarray, h: float, d: np.ndarray, which: np.ndarray) -> np.ndarray:
        """(P, len(which)): the s > 0 at which each ray meets each of the
        panels ``which`` within its heights, inf where it does not."""
        a, b, zlo, zhi = self.a[which], self.b[which], self.zlo[which], self.zhi[which]
        e = b - a  # (E, 2)
        w = a - origin
        den = d[:, None, 0] * e[None, :, 1] - d[:, None, 1] * e[None, :, 0]  # (P, E)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (w[None, :, 0] * e[None, :, 1] - w[None, :, 1] * e[None, :, 0]) / den
            t = (w[None, :, 0] * d[:, None, 1] - w[None, :, 1] * d[:, None, 0]) / den
        z = h + s * d[:, None, 2]
        return np.where((den != 0) & (s > 1e-9) & (t >= 0) & (t <= 1) & (z >= zlo) & (z <= zhi), s, np.inf)

    def first_slab(self, origin: np.ndarray, h: float, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`first_panel` for the slabs."""
        if not len(self.quads):
            return np.full(len(d), np.inf), np.zeros(len(d), dtype=np.int64)
        # (A ray level with a slab never meets it: inf and nan, dropped below.)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (self.slab_z[None, :] - h) / d[:, None, 2]  # (P, Q)
            p = origin + s[..., None] * d[:, None, :2]  # (P, Q, 2)
            q = self.quads  # (Q, 4, 2), convex, either turning sense
            edge = np.roll(q, -1, axis=1) - q
            cross = edge[None, :, :, 0] * (p[:, :, None, 1] - q[None, :, :, 1]) \
                - edge[None, :, :, 1] * (p[:, :, None, 0] - q[None, :, :, 0])  # (P, Q, 4)
            inside = (cross >= 0).all(axis=2) | (cross <= 0).all(axis=2)
        s = np.where(np.isfinite(s) & (s > 1e-9) & inside, s, np.inf)
        i = s.argmin(axis=1)
        return s[np.arange(len(s)), i], i


def _room_normals(a: np.ndarray, b: np.ndarray, walls) -> np.ndarray:
    """(E, 2) unit normal of each wall edge pointing out of the wall, into
    the room (probed a centimetre to one side)."""
    e = b - a
    n = np.stack([e[:, 1], -e[:, 0]], axis=1) / np.maximum(np.linalg.norm(e, axis=1, keepdims=True), 1e-12)
    if walls is None or not len(a):
        return n
    into_wall = inside_walls(0.5 * (a + b) + 0.01 * n, walls)
    return np.where(into_wall[:, None], -n, n)


def _panel_shades(a: np.ndarray, b: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(E,) grey level of faces with room-side ``normals`` (E, 2): lit from
    ``LIGHT_DEG``, so that walls at a corner and the two faces of one wall
    differ."""
    lo, hi = WALL_GREY
    light = np.array([math.cos(math.radians(LIGHT_DEG)), math.sin(math.radians(LIGHT_DEG))])
    return lo + (hi - lo) * (0.5 + 0.5 * normals @ light)


def _openings(linemap, top: float):
    """Panels and slabs of the door and window openings, from the map's
    LINTEL and WINDOW segments. Two such segments at one height, parallel
    and at most _OPENING_DEPTH_M apart, are the two faces of the wall over
    (or under) one opening: each gets a panel (above a head, below a sill:
    a WINDOW segment lower than half the wall height is a sill) facing away
    from the other, and the quad between them is a slab.

    Returns ``(a, b, zlo, zhi, grey)`` of the panels and ``(quads, z,
    grey)`` of the slabs."""
    segs = linemap.segments[np.isin(linemap.kinds, (LINTEL, WINDOW))]
    kinds = linemap.kinds[np.isin(linemap.kinds, (LINTEL, WINDOW))]
    horizontal = np.abs(segs[:, 0, 2] - segs[:, 1, 2]) < 1e-6
    segs, kinds = segs[horizontal], kinds[horizontal]
    pa, pb, plo, phi, pn, quads, qz, qgrey = [], [], [], [], [], [], [], []
    for i in range(len(segs)):
        a, b, z = segs[i, 0, :2], segs[i, 1, :2], segs[i, 0, 2]
        e = b - a
        length = float(np.hypot(*e))
        if length < 1e-6:
            continue
        u = e / length
        n = np.array([-u[1], u[0]])
        sill = kinds[i] == WINDOW and z < 0.5 * top
        for j in range(len(segs)):
            c, f = segs[j, 0, :2], segs[j, 1, :2]
            if j == i or abs(segs[j, 0, 2] - z) > 1e-6:
                continue
            off = float(np.dot(0.5 * (c + f) - a, n))
            along = np.sort([np.dot(c - a, u), np.dot(f - a, u)])
            if (abs(abs(np.dot((f - c) / max(np.hypot(*(f - c)), 1e-12), u)) - 1.0) > 1e-4
                    or not 0.01 < abs(off) <= _OPENING_DEPTH_M or along[1] < 1e-3 or along[0] > length - 1e-3):
                continue
            # j is the other face: i's panel faces away from it.
            pa.append(a)
            pb.append(b)
            plo.append(-np.inf if sill else z)
            phi.append(z if sill else np.inf)
            pn.append(-n if off > 0 else n)
            if i < j:
                quads.append(np.array([a, b, b + off * n, a + off * n]))
                qz.append(z)
                qgrey.append(SILL_GREY if sill else HEAD_GREY)
            break
    panels = (np.array(pa).reshape(-1, 2), np.array(pb).reshape(-1, 2), np.array(plo), np.array(phi))
    grey = _panel_shades(panels[0], panels[1], np.array(pn).reshape(-1, 2))
    return (*panels, grey, np.array(quads).reshape(-1, 4, 2), np.array(qz), np.array(qgrey))

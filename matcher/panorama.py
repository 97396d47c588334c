"""An equirectangular panorama as a rig of virtual pinhole cameras.

**The panorama's convention.** An image ``H x W`` with ``W = 2H`` (grey or
colour). Pixel ``(u, v)``: ``u`` the column, ``v`` the row, pixel centres
at whole numbers (OpenCV's). Column ``u`` looks at azimuth

    a = ((u + 0.5) / W - 0.5) * 360 degrees,

*clockwise* seen from above from the camera's centre direction: the
vertical line between columns ``W/2 - 1`` and ``W/2`` (``u = (W - 1) / 2``)
looks along the robot's heading, and columns run left to right as a person
turns right. Row ``v`` looks at elevation ``90 - (v + 0.5) / H * 180``
degrees: the top row straight up, the bottom row straight down, the middle
at the horizon. ``yaw_offset_deg`` is for cameras mounted otherwise: the
heading of the panorama's centre column relative to the robot's heading,
degrees, *counter-clockwise positive* (+90: the centre column looks to the
robot's left). A direction at robot-frame heading ``psi`` (counter-clockwise
from the robot's heading) is at ``a = yaw_offset_deg - psi``. So rolling
the image right by ``W/4`` columns (``np.roll(pano, W // 4, axis=1)``) is
the same panorama taken with ``yaw_offset_deg`` 90 degrees larger.

ZInD's panoramas follow the same directions (centre column forward,
clockwise, up at the top) but spread the full turn over ``W - 1`` columns
(:meth:`mapkit.importers.zind.annotations.ZindPano.pixel_of`: columns 0
and ``W - 1`` both at the seam); the two differ by at most half a
panorama pixel, at the seam (tests/test_panorama.py holds the bound).

**The cut** (:func:`panorama_rig`, defaults in
:class:`matcher.tolerances.PanoramaCut`): one ring of ``views`` level
pinhole cameras at the robot's centre and the camera's height, view ``k``
heading ``k * 360 / views`` degrees clockwise from the panorama's centre
column (view 0 along it). Each has square pixels with the panorama's
pixels per degree at its centre (``f = W / 2 pi``), a horizontal field of
view ``hfov_deg`` wider than its sector of ``360 / views`` degrees, and a
tall vertical one (``vfov_deg``, 100 by default: the floor and ceiling
junctions of a room from a metre or two away, both in one view, so no
second ring and no vertical overlap to resolve).

**Overlaps: one line, one view.** A line is kept only in the view whose
*sector* (its heading +- 180 / views degrees, half-open) holds the middle
of the line's azimuth range (the azimuths of its two end points' rays, the
shorter way round: the same in every view that sees the line). A line
spanning up to ``hfov_deg - 360 / views`` degrees of azimuth (45 degrees
with the default 8 views of 90 degrees) lies whole in the view that keeps
it and is kept once: a neighbour sees it whole or cut at its border, and
either way the middle of what it sees lies in the keeper's sector (for a
level view a ray's column depends on its azimuth only, so "inside
horizontally" is an azimuth test). A longer line (a wall's floor junction
seen from close by) is cut at the views' borders and kept as pieces, at
most one per view, and the pieces may overlap.

**Why this cut.** Measured by ``tools/bench_pano_cut.py`` on the ZInD
sample tour (32 panoramas, docs/benchmarks/pano-cut.md): map segments
supported by the kept lines at the annotated pose (a line within 2 degrees
and 3 px of the projected segment, over half of it). 4 to 12 views of 60 to
120 degrees and 90 to 130 degrees tall all support a median of 22 to 25.5
segments per panorama; 8 views of 90 x 100 degrees have the best tenth
percentile (11, as 8 x 75 x 90) and the most panoramas with at least 6 (32 of 32) and 10
(31) supported, with fewer lines than the taller cuts (268 a panorama
against 312 at 110 degrees and 535 at 130, which support no more
segments) and lines up to 45 degrees long kept whole. On
panoramas of maps/flat.lmap rendered by the project
(``mapkit_harness.render.render_panorama``) the cuts are within a few
segments of each other.

numpy and OpenCV only.
"""

from __future__ import annotations

import functools
import math
import numbers
from dataclasses import dataclass

import cv2
import numpy as np

from linemap.camera import Camera
from linemap.errors import InputError
from linemap.rig import Mount, Rig, RigCamera
from matcher.lines import detect_lines
from matcher.tolerances import DETECTION, PANORAMA_CUT, LineDetection, PanoramaCut

#: Panorama pixel types the cut resamples as they are (cv2.remap's).
_REMAP_DTYPES = (np.uint8, np.uint16, np.int16, np.float32, np.float64)


@dataclass(frozen=True)
class PanoramaRig(Rig):
    """The virtual cameras cut from a panorama (a :class:`linemap.rig.Rig`:
    every camera at the robot's centre, mount yaw its heading relative to the
    robot's), with the panorama's ``yaw_offset_deg`` (module docstring) and
    the ``cut`` that made them."""

    yaw_offset_deg: float = 0.0
    cut: PanoramaCut = PANORAMA_CUT

    @property
    def sector_deg(self) -> float:
        """Width of each view's own sector, degrees."""
        return 360.0 / len(self.cameras)


def panorama_rig(pano_width: int, height_m: float, yaw_offset_deg: float = 0.0, views: int | None = None,
                 hfov_deg: float | None = None, vfov_deg: float | None = None,
                 pitch_deg: float | None = None) -> PanoramaRig:
    """The rig of virtual pinhole cameras cut from a ``pano_width`` x
    ``pano_width / 2`` panorama taken ``height_m`` metres above the floor
    (module docstring); ``views``, ``hfov_deg``, ``vfov_deg`` and
    ``pitch_deg`` default to :data:`matcher.tolerances.PANORAMA_CUT`'s.
    Cameras are named ``pano0``, ``pano1``, ... in heading order (clockwise
    from the panorama's centre column)."""
    if isinstance(pano_width, bool) or not isinstance(pano_width, numbers.Integral) or pano_width < 64 \
            or pano_width % 2:
        raise InputError(f"panorama width must be an even number of pixels >= 64, got {pano_width!r}")
    if isinstance(yaw_offset_deg, bool) or not isinstance(yaw_offset_deg, numbers.Real) \
            or not math.isfinite(yaw_offset_deg):
        raise InputError(f"panorama yaw offset must be a finite number of degrees, got {yaw_offset_deg!r}")
    given = {"views": views, "hfov_deg": hfov_deg, "vfov_deg": vfov_deg, "pitch_deg": pitch_deg}
    cut = PanoramaCut(**{k: (getattr(PANORAMA_CUT, k) if v is None else v) for k, v in given.items()})
    f = pano_width / (2.0 * math.pi)  # the panorama's pixels per radian
    width = 2 * max(8, round(f * math.tan(math.radians(cut.hfov_deg) / 2.0)))
    height = 2 * max(8, round(f * math.tan(math.radians(cut.vfov_deg) / 2.0)))
    camera = Camera(width, height, f, f, width / 2.0, height / 2.0, float(height_m), float(cut.pitch_deg))
    step = 360.0 / cut.views
    cameras = tuple(RigCamera(f"pano{k}", camera, Mount(0.0, 0.0, _wrap_deg(yaw_offset_deg - k * step)))
                    for k in range(cut.views))
    return PanoramaRig(cameras, float(yaw_offset_deg), cut)


def check_panorama(panorama) -> np.ndarray:
    """``panorama`` as an array the cut can resample, or InputError saying
    what is wrong with it (not an array of numbers, empty, not 2:1)."""
    if not isinstance(panorama, np.ndarray):
        raise InputError(f"panorama must be an image array (cv2.imread), got {type(panorama).__name__}")
    if panorama.ndim not in (2, 3) or (panorama.ndim == 3 and panorama.shape[2] not in (1, 3, 4)):
        raise InputError(f"panorama must be (H, W) grey or (H, W, 3|4) colour, got shape {panorama.shape}")
    if panorama.size == 0:
        raise InputError(f"panorama is empty (shape {panorama.shape})")
    if panorama.dtype == np.bool_:
        panorama = panorama.astype(np.uint8) * 255
    elif panorama.dtype not in _REMAP_DTYPES:
        raise InputError(f"panorama pixels must be uint8, uint16, int16 or float, got dtype {panorama.dtype}")
    h, w = panorama.shape[:2]
    if w != 2 * h:
        raise InputError(f"an equirectangular panorama is twice as wide as high, got {w}x{h}: "
                         "give the whole 360 x 180 degree image")
    if panorama.dtype.kind == "f" and not np.isfinite(panorama).all():
        raise InputError("panorama holds non-finite values")
    return np.ascontiguousarray(panorama)


def direction_pixels(directions: np.ndarray, pano_width: int, yaw_offset_deg: float = 0.0) -> np.ndarray:
    """(..., 2) panorama pixels ``(u, v)`` of robot-frame directions
    (..., 3) (x forward, y left, z up; any length), ``u`` in ``[-0.5, W -
    0.5)``."""
    d = np.asarray(directions, dtype=float)
    psi = np.arctan2(d[..., 1], d[..., 0])
    a = np.mod(math.radians(yaw_offset_deg) - psi + math.pi, 2.0 * math.pi) - math.pi  # clockwise from the centre
    elevation = np.arctan2(d[..., 2], np.hypot(d[..., 0], d[..., 1]))
    h = pano_width / 2.0
    u = (a / (2.0 * math.pi) + 0.5) * pano_width - 0.5
    v = (0.5 - elevation / math.pi) * h - 0.5
    return np.stack([u, v], axis=-1)


def pixel_directions(uv: np.ndarray, pano_width: int, yaw_offset_deg: float = 0.0) -> np.ndarray:
    """(..., 3) unit robot-frame directions of panorama pixels (..., 2):
    the inverse of :func:`direction_pixels`."""
    uv = np.asarray(uv, dtype=float)
    a = ((uv[..., 0] + 0.5) / pano_width - 0.5) * 2.0 * math.pi
    elevation = (0.5 - (uv[..., 1] + 0.5) / (pano_width / 2.0)) * math.pi
    psi = math.radians(yaw_offset_deg) - a
    c = np.cos(elevation)
    return np.stack([c * np.cos(psi), c * np.sin(psi), np.sin(elevation)], axis=-1)


def view_directions(rig_camera: RigCamera, uv: np.ndarray | None = None) -> np.ndarray:
    """(..., 3) robot-frame directions (not normalised) of pixels ``uv``
    (..., 2) of one virtual camera; every pixel centre (H, W, 3) if None."""
    cam = rig_camera.camera
    if uv is None:
        uv = np.stack(np.meshgrid(np.arange(cam.width, dtype=float), np.arange(cam.height, dtype=float)), axis=-1)
    return cam.pixel_rays(uv) @ cam.world2cam(rig_camera.mount.yaw)  # R^T ray


def view_maps(rig_camera: RigCamera, pano_width: int, yaw_offset_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``(map_u, map_v)`` (H, W) float32: the panorama pixel each pixel of
    ``rig_camera``'s view samples (cv2.remap's maps; rows clamped to the
    panorama, columns wrapped by the remap)."""
    uv = direction_pixels(view_directions(rig_camera), pano_width, yaw_offset_deg)
    v = np.clip(uv[..., 1], 0.0, pano_width / 2.0 - 1.0)
    return uv[..., 0].astype(np.float32), v.astype(np.float32)


#: The remap maps of this many views are kept (:func:`_kept_view_maps`):
#: one robot's panoramas share one rig, whose 8 default views' maps take 4 MB
#: each at ZInD's 2048-pixel width; room for two rigs.
_KEPT_VIEW_MAPS = 16


@functools.lru_cache(maxsize=_KEPT_VIEW_MAPS)
def _kept_view_maps(rig_camera: RigCamera, pano_width: int, yaw_offset_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`view_maps`, computed once per view (read-only arrays): every
    panorama of a stream is cut by the same rig, and computing a view's maps
    (a ray per pixel, its azimuth and elevation) costs more than the remap
    itself (a ZInD panorama's 8 default views: 0.47 s of CPU the first
    time, 14 ms after)."""
    maps = view_maps(rig_camera, pano_width, yaw_offset_deg)
    for m in maps:
        m.flags.writeable = False
    return maps


def cut_views(panorama, rig: PanoramaRig) -> list[np.ndarray]:
    """The views of ``rig`` (:func:`panorama_rig`) resampled from
    ``panorama`` (H, 2H[, C]), bilinear, wrapping round the seam: one image
    per camera, in the rig's order, of the panorama's type and channels."""
    if not isinstance(rig, PanoramaRig):
        raise InputError(f"cut_views needs the rig of a panorama (matcher.panorama_rig), got {type(rig).__name__}")
    pano = check_panorama(panorama)
    width = pano.shape[1]
    out = []
    for rc in rig:
        map_u, map_v = _kept_view_maps(rc, width, float(rig.yaw_offset_deg))
        out.append(cv2.remap(pano, map_u, map_v, interpolation=cv2.INTER_LINEAR, borderMode=cv2.BORDER_WRAP))
    return out


def line_azimuths(lines: np.ndarray, rig_camera: RigCamera) -> np.ndarray:
    """(M, 2) robot-frame headings, radians counter-clockwise, of the rays of
    the end points of ``lines`` (M, 2, 2) pixels of ``rig_camera``."""
    d = view_directions(rig_camera, np.asarray(lines, dtype=float).reshape(-1, 2, 2))
    return np.arctan2(d[..., 1], d[..., 0])


def in_own_sector(lines: np.ndarray, rig_camera: RigCamera, sector_deg: float) -> np.ndarray:
    """(M,) bool: does the middle of each line's azimuth range lie in the
    camera's own sector, its heading +- sector_deg / 2, half-open (module
    docstring)? The middle is the same in every view that sees the whole
    line, so such a line is kept by exactly one view."""
    az = line_azimuths(lines, rig_camera)
    middle = az[:, 0] + 0.5 * _wrap(az[:, 1] - az[:, 0])
    off = _wrap(middle - rig_camera.mount.yaw)
    half = math.radians(sector_deg) / 2.0
    return (off >= -half) & (off < half)


def panorama_lines(panorama, rig: PanoramaRig, min_length: float | None = None,
                   settings: LineDetection = DETECTION) -> list[np.ndarray]:
    """Lines of ``panorama`` per camera of ``rig``: a list of (M_c, 2, 2)
    pixel arrays of each view's ideal pinhole, in the rig's order (what
    ``matcher.localize_rig`` takes). :func:`matcher.lines.detect_lines` on
    each view (``min_length``, ``settings`` as there), then each line kept
    only in the view whose own sector holds it (module docstring)."""
    out = []
    for rc, view in zip(rig, cut_views(panorama, rig)):
        lines = detect_lines(view, rc.camera, min_length=min_length, settings=settings)
        out.append(lines[in_own_sector(lines, rc, rig.sector_deg)] if len(lines) else lines)
    return out


def _wrap(a):
    """Angles (radians) wrapped to [-pi, pi)."""
    return np.mod(np.asarray(a, dtype=float) + math.pi, 2.0 * math.pi) - math.pi


def _wrap_deg(a: float) -> float:
    """An angle in degrees wrapped to [-180, 180)."""
    return float((a + 180.0) % 360.0 - 180.0)

"""matcher: runtime model-to-image straight-line matching for robot self-location.

Light by design: numpy, scipy and OpenCV only. Maps and cameras come from
the numpy-only core :mod:`linemap`; nothing of ``mapkit`` or the authoring
stack (ezdxf, trimesh, shapely, viser) is imported here.

The method's two stages have a folder each (:mod:`matcher.stage1`,
hypothesis generation; :mod:`matcher.stage2`, verification);
:mod:`matcher.strategy` says which hypothesis sources run and when;
:mod:`matcher.from_prior` and :mod:`matcher.lost` are the entry points.

    >>> import matcher
    >>> m = matcher.load_map("maps/flat.lmap")
    >>> cam = matcher.Camera.load("camera.json")
    >>> res = matcher.localize(m, cam, lines, prior=(x, y, yaw_deg), dt=0.5, dyaw=20)
    >>> if res: print(res.pose)
    ... else: print(res.reason)

A 360-degree panorama is a rig of virtual pinhole cameras
(:mod:`matcher.panorama`): ``rig = matcher.panorama_rig(width, height_m)``,
``lines = matcher.panorama_lines(image, rig)``.
"""

from linemap.camera import Camera, CameraError
from linemap.errors import InputError
from linemap.lmap import LineMap, LmapError, SegmentKind, load_map
from matcher.from_prior import localize
from matcher.lost import localize_global
from matcher.result import LocalizeResult
from matcher.tolerances import Tolerances, Tracking
from matcher.tracking import TrackedFrame, Tracker

__all__ = [
    "Camera",
    "CameraError",
    "InputError",
    "LineMap",
    "LmapError",
    "LocalizeResult",
    "SegmentKind",
    "Tolerances",
    "TrackedFrame",
    "Tracker",
    "Tracking",
    "detect_lines",
    "load_map",
    "localize",
    "localize_global",
    "panorama_lines",
    "panorama_rig",
]

#: Loaded on first use (OpenCV): ``import matcher`` stays numpy and scipy only.
_LAZY = {"panorama_rig": "matcher.panorama", "panorama_lines": "matcher.panorama"}


def __getattr__(name):
    """The lazily imported names of ``__all__`` (:data:`_LAZY`)."""
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'matcher' has no attribute {name!r}")


def detect_lines(image, camera=None, **kwargs):
    """Straight lines (M, 2, 2) pixels of an image with OpenCV's LSD (see matcher.lines)."""
    from matcher.lines import detect_lines as _detect

    return _detect(image, camera, **kwargs)

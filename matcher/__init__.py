"""matcher: runtime model-to-image straight-line matching for robot self-location.

Light by design: numpy, scipy and OpenCV only. Maps and cameras come from
the numpy-only core :mod:`linemap`; nothing of ``mapkit`` or the authoring
stack (ezdxf, trimesh, shapely, viser) is imported here.

The method's two stages have a folder each (:mod:`matcher.search.tree`,
hypothesis generation; :mod:`matcher.stage2`, verification);
:mod:`matcher.search.tree.strategy` says which hypothesis sources run and when;
:mod:`matcher.from_prior` and :mod:`matcher.lost` are the entry points.

    >>> import matcher
    >>> m = matcher.load_map("maps/flat.lmap")
    >>> cam = matcher.Camera.load("camera.json")
    >>> rig = matcher.load_rig("rig.json")  # several cameras on one robot (linemap.rig_files)
    >>> res = matcher.localize(m, cam, lines, prior=(x, y, yaw_deg), dt=0.5, dyaw=20)
    >>> if res: print(res.pose)
    ... else: print(res.reason)

A robot with several cameras (:mod:`matcher.rig`) gives one list of lines
per camera: ``matcher.localize_rig(m, rig, [lines0, lines1, ...], prior,
dt, dyaw)``, and :func:`localize_rig_global` without a prior.

A building (``mapkit build model.ifc -o DIR``) loads from its manifest:
``matcher.load_map("DIR/building.json")`` gives a :class:`Building`, its
storeys each with a map; ``localize(..., storey=NAME)`` works on one,
``localize_global`` searches them all and names the storey
(:mod:`matcher.building`).

A 360-degree panorama is a rig of virtual pinhole cameras
(:mod:`matcher.panorama`): ``rig = matcher.panorama_rig(width, height_m)``,
``lines = matcher.panorama_lines(image, rig)``, then ``localize_rig``.
"""

from linemap import __version__
from linemap.building import Building, Storey
from linemap.building import load_any as load_map
from linemap.camera import Camera, CameraError
from linemap.errors import InputError
from linemap.lmap import LineMap, LmapError, SegmentKind
from linemap.rig import Mount, Rig, RigCamera
from linemap.rig_files import load_rig
from matcher.from_prior import localize
from matcher.lost import localize_global
from matcher.result import LocalizeResult
from matcher.rig import localize_rig, localize_rig_global
from matcher.tolerances import Tolerances, Tracking
from matcher.tracking import TrackedFrame, Tracker

__all__ = [
    "__version__",
    "Building",
    "Camera",
    "CameraError",
    "InputError",
    "LineMap",
    "LmapError",
    "LocalizeResult",
    "Mount",
    "Rig",
    "RigCamera",
    "SegmentKind",
    "Storey",
    "Tolerances",
    "TrackedFrame",
    "Tracker",
    "Tracking",
    "detect_lines",
    "load_map",
    "load_rig",
    "localize",
    "localize_global",
    "localize_rig",
    "localize_rig_global",
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

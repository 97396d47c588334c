"""The camera model now lives in :mod:`linemap.camera` (shared by ``mapkit``
and ``matcher``); this module keeps the old import path."""

from linemap.camera import REQUIRED_FIELDS, Camera, CameraError, check_camera, world2cam_rotation  # noqa: F401

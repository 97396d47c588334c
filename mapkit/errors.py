"""Errors a user can cause. The CLI turns them into one line, exit code 2.

All are :class:`linemap.errors.InputError` subclasses: anything else a command
raises is a bug (exit 3).
"""

from linemap.errors import InputError


class MapkitError(InputError):
    """A problem with the user's input or options: the message says what to do."""


class ImplausibleUnitsError(MapkitError):
    """The units a drawing's header states make it no building's size."""


class NoWallsError(MapkitError):
    """The plan has no geometry we recognise as walls."""


class NoFreeSpaceError(MapkitError):
    """The plan was understood but leaves no place for the camera; ``scene``
    holds what was understood (empty free space), for ``mapkit preview``."""

    def __init__(self, message: str, scene=None):
        super().__init__(message)
        self.scene = scene


class InconsistentDrawingError(MapkitError):
    """The map built contradicts its own drawing (:mod:`mapkit.importers.dxf.self_check`):
    refused unless ``--accept-inconsistent``; ``scene`` holds what was built, for ``mapkit preview``."""

    def __init__(self, message: str, scene=None):
        super().__init__(message)
        self.scene = scene

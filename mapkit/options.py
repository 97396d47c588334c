"""Options of ``mapkit build``, shared by every importer and stage.

One dataclass, so the CLI, the pipeline and the tests agree on names and
defaults, and the whole set is recorded in the map's META as build parameters.
Lengths in metres, angles in degrees.

Each field carries, in one place, its default, its help text, its
command-line flag, the group its flag is listed under and the values it
allows (:func:`option`); the commands' flags are generated from the fields
(:mod:`mapkit.commands._import_args`), and :meth:`BuildOptions.validate`,
run on construction, is the one check of the values, whoever sets them.
"""

from __future__ import annotations

import math
from dataclasses import MISSING, asdict, dataclass, field, fields

from mapkit.errors import MapkitError
from mapkit.parallel import MAX_DEFAULT_JOBS, default_jobs
from mapkit.tolerances import (
    DEFAULT_MEMORY_BUDGET_MB,
    DXF_MAX_ENTITIES,
    MAX_FLOOR_AREA_M2,
    MAX_REGION_SECONDS_PER_100M2,
    REGION_BOUND_MIN_AREA_M2,
    VIR_MERGE_GROWTH,
)

#: Groups of flags, in the order ``--help`` lists them: the import groups
#: every command that reads a plan takes, then the build's own. ``""``:
#: listed with the command's own options, not under a heading.
IMPORT_GROUPS = ("import", "reconstruction")
BUILD_GROUPS = ("edges and visibility", "")

#: The default camera: an ideal pinhole of this horizontal field of view,
#: degrees, and image size, pixels (``--hfov``, ``--image-size``), its focal
#: length rounded to a whole pixel (70 degrees over 640 pixels: 457), at
#: this height above the floor, metres, level (``--camera-height``, ``--pitch``).
DEFAULT_HFOV_DEG = 70.0
DEFAULT_IMAGE_SIZE = (640, 480)
DEFAULT_CAMERA_HEIGHT_M = 1.2


def default_camera() -> dict:
    """The camera.json shape of the default camera (see ``DEFAULT_HFOV_DEG``)."""
    width, height = DEFAULT_IMAGE_SIZE
    f = float(round((width / 2.0) / math.tan(math.radians(DEFAULT_HFOV_DEG) / 2.0)))
    return {"width": width, "height": height, "fx": f, "fy": f, "cx": width / 2.0, "cy": height / 2.0,
            "height_m": DEFAULT_CAMERA_HEIGHT_M, "pitch_deg": 0.0}


@dataclass(frozen=True)
class Range:
    """The values a numeric option allows: finite, from ``lo`` to ``hi``
    (None: unbounded), each end included unless ``*_open``; ``unit`` for
    the message."""

    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    unit: str = ""

    def holds(self, v: float) -> bool:
        if not math.isfinite(v):
            return False
        if self.lo is not None and (v <= self.lo if self.lo_open else v < self.lo):
            return False
        return self.hi is None or (v < self.hi if self.hi_open else v <= self.hi)

    def __str__(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        if self.hi is None:
            return f"{'>' if self.lo_open else '>='} {self.lo:g}{unit}"
        return f"in {'(' if self.lo_open else '['}{self.lo:g}, {self.hi:g}{')' if self.hi_open else ']'}{unit}"


POSITIVE_M = Range(0.0, lo_open=True, unit="metres")
NON_NEGATIVE_M = Range(0.0, unit="metres")
POSITIVE = Range(0.0, lo_open=True)


def option(default=MISSING, *, factory=MISSING, help: str, group: str | None, flag: str | tuple[str, ...] | None = None,
           metavar: str | None = None, allowed: Range | tuple | None = None):
    """A :class:`BuildOptions` field and its command line, in one place.

    - ``default`` or ``factory`` (a callable making it);
    - ``help``: the flag's help text; ``{default}`` in it stands for the
      default, else ``(default ...)`` is appended (not for list options);
    - ``group``: the heading the flag is listed under (``IMPORT_GROUPS``,
      ``BUILD_GROUPS``), None: no flag of its own (help says what sets it);
    - ``flag``: the flag, or flags (``("-j", "--jobs")``); default
      ``--name-with-dashes``;
    - ``allowed``: a :class:`Range`, or a tuple of the allowed values.
    """
    meta = {"help": help, "group": group, "flag": flag, "metavar": metavar, "allowed": allowed}
    if factory is not MISSING:
        return field(default_factory=factory, metadata=meta)
    return field(default=default, metadata=meta)


def length_option(default: float, group: str, help: str, allowed: Range = POSITIVE_M):
    """An :func:`option` of a length in metres (``M`` on the command line)."""
    return option(default, group=group, metavar="M", allowed=allowed, help=help)


@dataclass
class BuildOptions:
    # The order of the fields is that of the build parameters in a map's
    # META: changing it changes every map's bytes.

    # ---- import -------------------------------------------------------
    units: str | None = option(
        None, group="import", metavar="UNIT",
        help="drawing units, overriding the file's: m, cm, mm, in, ft, ... ($INSUNITS for DXF)")
    scale: float = option(
        1.0, group="import", metavar="F", allowed=POSITIVE,
        help="extra scale factor after unit conversion, for meshes in odd scales")
    walls: list[str] = option(
        factory=list, group="import", metavar="GLOB",
        help="layer(s) holding walls and columns (repeatable; fnmatch, case-insensitive; default: guessed from names)")
    doors: list[str] = option(factory=list, group="import", metavar="GLOB", help="layer(s) holding doors (repeatable)")
    windows: list[str] = option(
        factory=list, group="import", metavar="GLOB", help="layer(s) holding windows or glass (repeatable)")
    ignore: list[str] = option(factory=list, group="import", metavar="GLOB", help="layer(s) to leave out (repeatable)")
    floor: list[str] = option(
        factory=list, group="import", metavar="GLOB",
        help="layer(s) outlining the floor (the interior) of an open plan (repeatable)")
    up: str = option(
        "auto", group="import", allowed=("auto", "z", "y"),
        help="mesh up axis (default {default}: glTF's y-up, z for the other formats; a glTF stored z-up is told by "
             "its faces)")
    floor_name: str | None = option(
        None, group="import", metavar="NAME", flag=("--floor-name", "--storey"),
        help="floor to build of a source with several: a ZInD tour's floor (floor_01, ...; default the first, with "
             "a warning), an IFC model's storey (its name; default every storey, with -o DIR)")
    plan_number: int | None = option(
        None, group="import", flag="--plan", metavar="N", allowed=Range(1),
        help="plan to build of a sheet with several side by side (DXF: numbered by wall length, largest first, "
             "as 'mapkit layers' lists them; default the largest, with a warning)")

    accept_inconsistent: bool = option(
        False, group="import",
        help="write a DXF plan's map even when it contradicts its drawing (the self-check: free space far smaller "
             "than the drawn building, walls no building has, door drawings or rooms lost), with a warning; "
             "without it such a map is refused")

    # ---- reconstruction -----------------------------------------------
    wall_height: float = length_option(2.5, "reconstruction", "wall (ceiling) height")
    door_height: float = length_option(2.1, "reconstruction", "door head height")
    window_sill: float = length_option(0.9, "reconstruction", "window sill height", NON_NEGATIVE_M)
    window_head: float = length_option(2.1, "reconstruction", "window head height")
    robot_radius: float = length_option(
        0.2, "reconstruction", "keep the camera this far from walls: the free space is shrunk by it", NON_NEGATIVE_M)
    max_wall_thickness: float = length_option(
        0.8, "reconstruction", "thicker double lines are not walls: they are not closed into solids")

    # ---- edges --------------------------------------------------------
    min_edge_length: float = length_option(
        0.2, "edges and visibility", "drop shorter edges: tiny pieces, furniture noise", NON_NEGATIVE_M)
    crease_deg: float = option(
        30.0, group="edges and visibility", metavar="DEG", allowed=Range(0.0, 180.0, True, True, "degrees"),
        help="mesh feature-edge angle: dihedral angle above which an edge is sharp")

    # ---- visibility and regions ----------------------------------------
    camera_from_source: bool = option(
        True, group=None,
        help="a source that records its camera's height (ZInD's panoramas) sets the map camera's height, unless "
             "False: the user chose the camera (--camera, --camera-height)")
    camera: dict = option(
        factory=default_camera, group=None,
        help="camera: intrinsics, height above the floor, pitch (down positive); set by --camera, "
             "--camera-height, --pitch, --hfov, --image-size")
    max_range: float = length_option(
        10.0, "edges and visibility", "farthest visible distance: farther segments are not listed")
    min_visible_length: float = length_option(
        0.3, "edges and visibility",
        "shortest contiguous visible piece that counts: a segment is visible if a piece this long is seen")
    eps: float = length_option(
        0.05, "edges and visibility",
        "region lists cover everything visible within this distance, the lookup tolerance",
        Range(0.0, 0.5, lo_open=True, unit="metres"))
    merge_growth: float = option(
        VIR_MERGE_GROWTH, group="edges and visibility", metavar="F", allowed=Range(0.0, 10.0),
        help="merge neighbouring regions while the mean list grows by at most this fraction (default {default}; "
             "0: tightest lists, more regions)")

    # ---- limits of work (not recorded: they change no result) ----------
    max_entities: int = option(
        DXF_MAX_ENTITIES, group="import", metavar="N", allowed=Range(0, lo_open=True),
        help="most DXF entities taken, blocks and MINSERT arrays expanded")
    max_floor_area: float = option(
        MAX_FLOOR_AREA_M2, group="edges and visibility", metavar="M2", allowed=Range(0.0, lo_open=True, unit="m2"),
        help="largest floor a map is built for, square metres, bounding box of the free space (default {default}; "
             "the region builder's time and memory grow with it)")
    max_region_seconds_per_100m2: float = option(
        MAX_REGION_SECONDS_PER_100M2, group="edges and visibility", metavar="S", allowed=POSITIVE,
        help="most seconds the region stage may take per 100 m2 of free space, predicted before it runs "
             f"(default {{default}}; floors under {REGION_BOUND_MIN_AREA_M2:g} m2 count as that large; real buildings "
             "need up to 8, walls tangled by faces crossing the building more)")
    jobs: int = option(
        factory=default_jobs, group="", flag=("-j", "--jobs"), metavar="N", allowed=Range(1),
        help="threads for the region stage's geometry work (default {default}: the cores available, at most "
             f"{MAX_DEFAULT_JOBS}; 1: one thread); the map is the same byte for byte")

    # ---- tiles (not recorded as options: the map's META records the tiling) ----
    memory_budget: float = option(
        DEFAULT_MEMORY_BUDGET_MB, group="", metavar="MB", allowed=Range(0.0, lo_open=True, unit="MB"),
        help="peak memory the region stage aims to stay under, MB (default {default}): a floor predicted above it "
             "is built in tiles sized to it (docs/tiles.md); smaller floors in one piece, as always")
    tile_side: float | None = option(
        None, group="", metavar="M", allowed=POSITIVE_M,
        help="build the region stage in tiles of at most this side, metres, whatever the floor's size "
             "(default: none, or what --memory-budget needs)")

    def __post_init__(self):
        self.validate()

    def validate(self) -> None:
        """MapkitError, one line naming the option, its flag and what it
        allows, for the first value out of range or of the wrong type; the
        units made canonical. Run on construction, and again by
        :func:`mapkit.pipeline.build_map` (fields may be set afterwards)."""
        for f in fields(self):
            _check_field(f, getattr(self, f.name))
        if self.units is not None:
            from mapkit.units import canonical_units

            self.units = canonical_units(self.units)  # one-line error for unknown units
        _check_camera(self.camera)
        if not self.door_height <= self.wall_height:
            raise MapkitError(f"--door-height {self.door_height:g} must be in (0, --wall-height {self.wall_height:g}]; "
                              "lower --door-height or raise --wall-height")
        if not self.window_sill < self.window_head <= self.wall_height:
            raise MapkitError(f"windows need 0 <= --window-sill < --window-head <= --wall-height, got "
                              f"{self.window_sill:g}, {self.window_head:g}, {self.wall_height:g}")

    def to_meta(self) -> dict:
        """JSON-able record of every option that shapes the map (stored in
        it); the limits of work are left out."""
        d = asdict(self)
        for name in LIMITS + TILING:
            d.pop(name)
        for name in RECORDED_WHEN_SET:
            if d[name] is None or d[name] is False:
                d.pop(name)
        return d


#: Fields of :class:`BuildOptions` that bound the work rather than shape the map.
LIMITS = ("max_entities", "max_floor_area", "max_region_seconds_per_100m2", "jobs")
#: Fields of :class:`BuildOptions` that choose one piece or tiles: left out of
#: the recorded options (a floor built in one piece keeps its bytes); a tiled
#: map records the tiling it was built with in META ``stats.regions``.
TILING = ("memory_budget", "tile_side")
#: Flags no longer taken: each with the field that replaced it (the flag is
#: taken where that field's is) and the one-line error that names it.
RETIRED_FLAGS = {
    "--max-sight-work": (
        "max_region_seconds_per_100m2",
        "--max-sight-work (sight tests per m2) was replaced by --max-region-seconds-per-100m2 (the region stage's "
        f"predicted seconds per 100 m2 of free space, default {MAX_REGION_SECONDS_PER_100M2:g}); give that instead",
    ),
}
#: Fields added after format 1.0, recorded in a map only when set, so maps
#: built without them keep their bytes.
RECORDED_WHEN_SET = ("plan_number", "accept_inconsistent")


def flags_of(f) -> tuple[str, ...]:
    """The command-line flags of field ``f`` (a dataclasses.Field), () if none."""
    if f.metadata["group"] is None:
        return ()
    flag = f.metadata["flag"] or "--" + f.name.replace("_", "-")
    return (flag,) if isinstance(flag, str) else tuple(flag)


class OptionError(MapkitError):
    """A :class:`BuildOptions` field of the wrong type or out of range. Its
    message names the flag and the field (from Python one sets the field);
    :meth:`as_typed` is the command line's, naming the flag alone."""

    def __init__(self, f, problem: str):
        self.flag = "/".join(flags_of(f)) or f.name
        self.problem = problem  # "must be > 0 metres, got 0.0"
        super().__init__(f"{self.flag} {problem} (BuildOptions.{f.name})")

    def as_typed(self) -> MapkitError:
        """The error as the command line reports it: ``--max-range must be ...``."""
        return MapkitError(f"{self.flag} {self.problem}")


def _check_field(f, value) -> None:
    """OptionError unless ``value`` has field ``f``'s type and allowed value."""
    kind, allowed = f.type, f.metadata["allowed"]
    if kind in ("float", "int"):
        wanted = int if kind == "int" else (int, float)
        if isinstance(value, bool) or not isinstance(value, wanted):
            raise OptionError(f, f"must be a{'n integer' if kind == 'int' else ' number'}, got {value!r}")
    elif kind == "bool" and not isinstance(value, bool):
        raise OptionError(f, f"must be True or False, got {value!r}")
    elif kind == "dict" and not isinstance(value, dict):
        raise OptionError(f, f"must be a camera.json object, got {value!r}")
    elif kind == "list[str]" and not (isinstance(value, list) and all(isinstance(v, str) for v in value)):
        raise OptionError(f, f"must be a list of layer names or globs, got {value!r}")
    elif kind == "float | None" and not (value is None or (isinstance(value, (int, float)) and not isinstance(value, bool))):
        raise OptionError(f, f"must be a number, got {value!r}")
    elif kind == "int | None" and not (value is None or (isinstance(value, int) and not isinstance(value, bool))):
        raise OptionError(f, f"must be an integer, got {value!r}")
    elif kind in ("str", "str | None") and not (isinstance(value, str) or (value is None and kind != "str")):
        raise OptionError(f, f"must be text, got {value!r}")
    if isinstance(allowed, Range) and value is not None and not allowed.holds(value):
        raise OptionError(f, f"must be {allowed}, got {value!r}")
    if isinstance(allowed, tuple) and value not in allowed:
        raise OptionError(f, f"must be one of {', '.join(allowed)}, got {value!r}")


def _check_camera(camera: dict) -> None:
    """MapkitError unless ``camera`` is a camera.json object
    :class:`linemap.camera.Camera` accepts."""
    from linemap.camera import Camera, CameraError

    try:
        Camera.from_dict(camera)
    except CameraError as exc:
        raise MapkitError(f"BuildOptions.camera (set by --camera, --camera-height, --pitch, --hfov, --image-size): "
                          f"{exc}") from None


def option_default(name: str):
    """The default of :class:`BuildOptions` field ``name`` (stages that take
    one of the options as a parameter default to it, not to a copy)."""
    f = BuildOptions.__dataclass_fields__[name]
    return f.default_factory() if f.default is MISSING else f.default

"""Options of ``mapkit build``, shared by every importer and stage.

One dataclass, so the CLI, the pipeline and the tests agree on names and
defaults, and the whole set is recorded in the map's META as build parameters.
Lengths in metres, angles in degrees.
"""

from __future__ import annotations

from dataclasses import MISSING, asdict, dataclass, field

from mapkit.parallel import default_jobs
from mapkit.tolerances import DXF_MAX_ENTITIES, MAX_FLOOR_AREA_M2, MAX_SIGHT_WORK_PER_M2, VIR_MERGE_GROWTH


@dataclass
class BuildOptions:
    # ---- import -------------------------------------------------------
    #: Drawing/mesh units ("m", "cm", "mm", "in", "ft", ...); None: from the file.
    units: str | None = None
    #: Extra factor applied after unit conversion (meshes in odd scales).
    scale: float = 1.0
    #: Layer name globs (fnmatch, case-insensitive) per role; empty: guess.
    walls: list[str] = field(default_factory=list)
    doors: list[str] = field(default_factory=list)
    windows: list[str] = field(default_factory=list)
    ignore: list[str] = field(default_factory=list)
    #: Layers whose outlines give the floor (the interior) of an open plan.
    floor: list[str] = field(default_factory=list)
    #: Mesh up axis: "z", "y" or "auto": the file format's convention (glTF
    #: is y-up, the others have none and default to z), a glTF file stored
    #: z-up being told by its faces (:func:`mapkit.importers.mesh.load.guess_up`).
    up: str = "auto"
    #: The floor to build of a source holding several (ZInD's "floor_01");
    #: None: the first, with a warning when there are more.
    floor_name: str | None = None

    # ---- reconstruction -----------------------------------------------
    wall_height: float = 2.5
    door_height: float = 2.1
    window_sill: float = 0.9
    window_head: float = 2.1
    #: The free space is shrunk by this (the camera centre stays this far from walls).
    robot_radius: float = 0.2
    #: Double-line walls thicker than this are not closed into solids.
    max_wall_thickness: float = 0.8

    # ---- edges --------------------------------------------------------
    #: Edges shorter than this are dropped (tiny pieces, furniture noise).
    min_edge_length: float = 0.2
    #: Mesh feature edges: dihedral angle above which an edge is sharp.
    crease_deg: float = 30.0

    # ---- visibility and regions ----------------------------------------
    #: A source that records its camera's height (ZInD's panoramas) sets the
    #: map camera's height, unless this is False (the user chose the camera:
    #: --camera, --camera-height).
    camera_from_source: bool = True
    #: Camera: height above the floor, pitch (down positive) and intrinsics.
    camera: dict = field(
        default_factory=lambda: {
            "width": 640,
            "height": 480,
            "fx": 457.0,
            "fy": 457.0,
            "cx": 320.0,
            "cy": 240.0,
            "height_m": 1.2,
            "pitch_deg": 0.0,
        }
    )
    #: Segments farther than this from the camera are not listed.
    max_range: float = 10.0
    #: A segment counts as visible if a contiguous piece this long is seen.
    min_visible_length: float = 0.3
    #: Region lists hold everything visible from within this distance.
    eps: float = 0.05
    #: Neighbouring regions merge (lists united) while the mean list length
    #: grows by at most this fraction: 0 keeps lists tightest, more regions.
    merge_growth: float = VIR_MERGE_GROWTH

    # ---- limits of work (not recorded: they change no result) ----------
    #: Most DXF entities flattened (blocks and MINSERT arrays expanded).
    max_entities: int = DXF_MAX_ENTITIES
    #: Largest floor, square metres (bounding box of the free space).
    max_floor_area: float = MAX_FLOOR_AREA_M2
    #: Most sight tests of the region builder per square metre of free space.
    max_sight_work: float = MAX_SIGHT_WORK_PER_M2
    #: Threads for the region stage's GEOS work (1: one thread); the map's
    #: bytes do not depend on it.
    jobs: int = field(default_factory=default_jobs)

    def to_meta(self) -> dict:
        """JSON-able record of every option that shapes the map (stored in
        it); the limits of work are left out."""
        d = asdict(self)
        for name in LIMITS:
            d.pop(name)
        return d


#: Fields of :class:`BuildOptions` that bound the work rather than shape the map.
LIMITS = ("max_entities", "max_floor_area", "max_sight_work", "jobs")


def option_default(name: str):
    """The default of :class:`BuildOptions` field ``name`` (stages that take
    one of the options as a parameter default to it, not to a copy)."""
    f = BuildOptions.__dataclass_fields__[name]
    return f.default_factory() if f.default is MISSING else f.default

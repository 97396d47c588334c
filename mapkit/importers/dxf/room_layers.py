"""Plans drawn one layer per room: the rooms' outlines are the walls.

Some drawings have no wall layer. Each room is drawn on a layer of its own
(a JuPedSim geometry: 'Raum_001' ... 'Raum_344'; a house: 'BedRoom1',
'BedRoom1a', 'Closet3', 'Kitchen'), or all rooms on a layer named for
spaces ('room', 'hall'), as lines that trace the room's outline, broken
where a door line closes it. Those lines are where the walls are: read as
room fills (the floor role their names would give) they leave the plan
without walls, and it is refused.

Decided from layer names and entity counts only (before any geometry is
read), for layers whose role was guessed, never for those named with
``--walls/--doors/--windows/--floor/--ignore``:

1. **per-room layers**: at least ``PER_ROOM_MIN_LAYERS`` layers with
   linework whose names are one stem and a running number ('Raum_001',
   'Closet2', 'BathRoom2a'), their linework mostly lines and arcs (a
   room's outline traced, not one closed zone polygon per room), holding
   more of it than the layers named for walls. A stem whose name gives
   another role keeps it ('Door1', 'Door2', 'Door3' are doors), and so
   do a generic one ('Layer1', 'Layer2') and a code of a letter or two
   ('F-0', 'F-4', 'F-8': pens of a framing plan).
2. in such a drawing, the layers named for a room or a space ('Kitchen',
   'DiningRoom', 'Balcony1') drawn the same way are rooms too, and so are
   those named for a void the rooms are drawn around ('OTS', open to sky;
   'Void', 'Shaft'): its outline is walls (a parapet, a shaft's walls)
   and, with no door into it, it is no room.
3. in a drawing with no wall linework at all, the layers named for rooms
   or spaces in general ('room', 'hall'; not one kind of room: a 'Kitchen
   stuff' layer holds furniture) that hold linework are the walls.

The door lines (a 'Tueren' layer) connect the rooms: each straight one is
a door of its own (:func:`door_lines_apart`), and where no wall gap of a
door leaf fits it (a shop front, an escalator lane's end) the line itself
is the opening (:func:`door_line_opening`). The rooms (:func:`room_faces`)
are what the outlines enclose together with the door lines: they say where
the inside of the building is. A room whose own outline stays open (a
living room drawn as three lines, closed by a staircase's walls and a void
beside it) is the space all barriers enclose that a door opens into
(:func:`entered_spaces`).
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Mapping
from dataclasses import replace

import numpy as np
import shapely
from shapely.geometry import LineString, MultiPolygon, Polygon
from shapely.ops import unary_union

from mapkit.importers.dxf.enclosure import passable
from mapkit.importers.dxf.entities import SILENT
from mapkit.importers.dxf.layer_roles import tokens
from mapkit.importers.dxf.strokes import Stroke
from mapkit.tolerances import (JAMB_REACH, MIN_OPENING_WIDTH, PER_ROOM_MIN_LAYERS, ROOM_FACES_COVER_SHARE, SNAP_GAP,
                               THIN_WALL)

#: A layer name that ends in a running number, optionally a letter after it
#: ('Raum_001', 'BathRoom2a', 'Room 12'): the stem, then the number.
_NUMBERED = re.compile(r"^(?P<stem>.*[^\W\d_])[\s_.\-]*(?P<number>\d+)[a-zA-Z]?$")

#: Stems that number layers, not rooms (CAD programs' default layer names).
_GENERIC_STEMS = frozenset({"layer", "layers", "ebene", "calque", "capa", "livello", "laag", "level", "plan",
                            "sheet", "group", "block", "new"})

#: Letters a stem needs to name rooms ('Raum', 'Closet'); fewer are a code.
_STEM_MIN_LETTERS = 3

#: Words that name a room or a space, whole words of the layer name (see
#: :func:`mapkit.importers.dxf.layer_roles.tokens`); a word ending in "room"
#: ('bedroom', 'storeroom') is one too. The last line's words name voids and
#: courts the rooms are drawn around ('OTS', 'Open to sky' of Indian plans).
_SPACE_WORDS = re.compile(r"""^(?:
    rooms?|raum|raume|raeume|zimmer|spaces?|zones?|pieces?|stanze?|habitaciones?|locaux|local
    |halls?|hallway|corridors?|flur|gang|lobby|foyer|landing|passage|walkway|vestibule
    |kitchen|kueche|kuche|bath|baths|bad|toilets?|wc|closets?|pantry|laundry|utility|wash
    |bed|bedrooms?|living|dining|lounge|study|office|offices|buero|buro|balcony|balkon|loggia
    |store|storage|lager|shops?|laden|geschaeft|stores
    |ots|sky|voids?|shafts?|lightwell|courtyard|atrium
)$""", re.X)

#: Words that name rooms or spaces in general, not one kind of room: a
#: drawing with no wall layer takes layers named so as its rooms' outlines
#: ('room', 'hall'), not a 'Kitchen stuff' layer of furniture.
_GENERAL_SPACE_WORDS = re.compile(r"""^(?:
    rooms?|raum|raume|raeume|zimmer|spaces?|zones?|pieces?|stanze?|habitaciones?|locaux|local
    |halls?|hallway|corridors?|flur
)$""", re.X)

#: Entity types that trace an outline stroke by stroke.
_OPEN_STROKES = ("LINE", "ARC")

#: Roles of guessed layers that an outline of a room may replace.
_REPLACEABLE = (None, "floor")


def is_space_name(layer: str) -> bool:
    """Whether a layer's name says it holds a room or a space ('Kitchen', 'BedRoom1', 'hall')."""
    return any(_SPACE_WORDS.match(w) or w.endswith("room") for w in tokens(layer))


def is_general_space_name(layer: str) -> bool:
    """Whether a layer's name says it holds rooms or spaces in general ('room', 'hall', 'Raum')."""
    return any(_GENERAL_SPACE_WORDS.match(w) for w in tokens(layer))


def room_stem(layer: str) -> str | None:
    """The stem of a numbered layer name, case-folded ('Raum_001' -> 'raum'), or None."""
    m = _NUMBERED.match(layer.strip())
    if m is None:
        return None
    stem = m.group("stem").casefold()
    # A letter or two is a pen or sheet code ('F-0', 'F-4', 'F-8' of a framing plan), not a room's name.
    if stem.strip(" _.-") in _GENERIC_STEMS or sum(c.isalpha() for c in stem) < _STEM_MIN_LETTERS:
        return None
    return stem


def _linework(counter: Counter) -> int:
    return sum(n for kind, n in counter.items() if kind not in SILENT)


def _traced(counter: Counter) -> bool:
    """Whether a layer's linework is mostly lines and arcs (an outline traced stroke by stroke)."""
    total = _linework(counter)
    return total > 0 and 2 * sum(counter.get(k, 0) for k in _OPEN_STROKES) >= total


def room_outline_layers(counts: Mapping[str, Counter], roles: Mapping[str, str | None],
                        guessed: set[str]) -> dict[str, str]:
    """The layers whose linework is the rooms' outlines, hence the walls,
    and why each (for 'mapkit layers'); see the module docstring.

    ``counts``: entity counts per layer and type; ``roles``: each layer's
    role so far; ``guessed``: the layers whose role came from their name
    (not from an option), the only ones this may change."""
    candidates = {name for name in guessed
                  if roles.get(name) in _REPLACEABLE and _linework(counts.get(name, Counter()))}
    wall_linework = sum(_linework(counts[n]) for n, r in roles.items() if r == "walls" and n in counts)

    families: dict[str, list[str]] = {}
    for name in sorted(candidates):
        stem = room_stem(name)
        if stem is not None and _traced(counts[name]):
            families.setdefault(stem, []).append(name)
    families = {s: names for s, names in families.items() if len(names) >= PER_ROOM_MIN_LAYERS}
    per_room = [n for names in families.values() for n in names]
    out: dict[str, str] = {}
    if per_room and sum(_linework(counts[n]) for n in per_room) > wall_linework:
        for stem, names in families.items():
            shown = _NUMBERED.match(names[0].strip()).group("stem")
            for n in names:
                out[n] = (f"one of {len(names)} per-room layers '{shown}*' (a stem and a running number, "
                          f"lines tracing one room each): the rooms' outlines are walls")
        for n in sorted(candidates - set(per_room)):
            if is_space_name(n) and _traced(counts[n]):
                out[n] = "named for a room or a space, in a drawing of one layer per room: its outline is walls"
        return out
    if wall_linework == 0:
        for n in sorted(candidates):
            if is_general_space_name(n):
                out[n] = "named for rooms or spaces, and no layer holds walls: the rooms' outlines are walls"
    return out


def room_faces(rooms: list[Stroke], doors: list[Stroke]) -> Polygon | MultiPolygon:
    """Where the rooms of a plan drawn one layer per room are, metres.

    ``rooms``: the strokes of the room-outline layers; ``doors``: the door
    strokes, which close the outlines where a room opens into the next one.
    The rooms are the faces that the outlines and door lines enclose
    together. In a plan with door lines, a face with no door on its outline
    (none ``MIN_OPENING_WIDTH`` long) is no room anyone enters: a pocket
    that neighbouring rooms' walls close off (an area no room was drawn
    for), an island in a room (a pillar, a fountain drawn on the room's
    layer), a niche a room's own lines close off."""
    walls = [_line(s) for s in rooms if len(s.coords) >= 2]
    door_lines = [_line(s) for s in doors if len(s.coords) >= 2]
    if not walls:
        return Polygon()
    noded = unary_union(walls + door_lines)
    faces = [f for f in shapely.get_parts(shapely.polygonize(shapely.get_parts(noded))) if f.area > 0]
    if door_lines:
        door_zone = unary_union(door_lines).buffer(SNAP_GAP)
        faces = [f for f in faces if f.exterior.intersection(door_zone).length >= MIN_OPENING_WIDTH]
    return unary_union(faces) if faces else Polygon()


def entered_spaces(enclosed: list[Polygon], door_gaps: list[Polygon], bridges: list[Polygon],
                   rooms: Polygon | MultiPolygon) -> list[Polygon]:
    """The rooms of a plan drawn one layer per room that its rooms' faces
    (:func:`room_faces`) miss: the spaces all barriers enclose that a door
    opens into, or an undrawn opening joins to a room, less than
    ``ROOM_FACES_COVER_SHARE`` of each in the faces.

    A room's layer may leave its outline open where other things close it
    for a person reading the plan: a living room drawn as three lines, its
    fourth side the staircase's walls and an open-to-sky void's parapet.
    Its lines enclose no face; the walls built from all of them do, and
    the doors into it say it is a room. A space no door or opening leads
    into (a shaft, a void, a pocket between rooms) stays out.

    ``enclosed``: the spaces the union of walls, obstacles, door gaps and
    ``bridges`` encloses (its holes, metres); ``door_gaps``: the doors' gap
    footprints; ``bridges``: the undrawn openings between facing wall ends
    (:func:`.enclosure.end_bridges`: a walkway's open end into the room it
    leaves), joining a space only to one already inside; ``rooms``: the
    rooms' faces."""
    pending = [h for h in enclosed
               if h.area > 0 and h.intersection(rooms).area < ROOM_FACES_COVER_SHARE * h.area]
    if not pending:
        return []
    reached = [g.buffer(SNAP_GAP) for g in door_gaps]
    openings = [b.buffer(SNAP_GAP) for b in bridges]

    def touched(space: Polygon, zones: list[Polygon]) -> list[int]:
        return [k for k, z in enumerate(zones) if space.exterior.intersection(z).length >= MIN_OPENING_WIDTH]

    out: list[Polygon] = []
    inside = rooms
    while pending:
        joined = [h for h in pending if touched(h, reached)]
        if not joined:
            joined = [h for h in pending
                      if any(passable(bridges[k], unary_union([inside, h])) for k in touched(h, openings))]
        if not joined:
            break
        out += joined
        pending = [h for h in pending if all(h is not j for j in joined)]
        inside = unary_union([inside, *joined])
    return out


def _line(s: Stroke) -> LineString:
    """A stroke as a line; an open one lengthened by ``SNAP_GAP`` at both
    ends, so that strokes drawn to meet but a hair apart (rounded
    coordinates: 514.46 against 514.5) cross and close the room."""
    if s.closed:
        return LineString(np.vstack([s.coords, s.coords[:1]]))
    pts = np.array(s.coords, dtype=float)
    for end, inner in ((0, 1), (-1, -2)):
        d = pts[end] - pts[inner]
        n = float(np.hypot(*d))
        if n > 0:
            pts[end] = pts[end] + d / n * SNAP_GAP
    return LineString(pts)


def door_lines_apart(doors: list[Stroke], first_group: int) -> list[Stroke]:
    """The door strokes of a plan drawn one layer per room, each straight
    door line a door of its own (a group of its own, numbered from
    ``first_group``) when the doors are all drawn as straight lines: there
    a door line is a passage between two rooms, and lines that meet end to
    end (the ends of a row of escalator lanes, a lane wall ending between
    each two) are as many doors. Door symbols of other shapes (a leaf and
    its swing, a block) are left as they are."""
    if not doors or any(s.group is not None or s.closed or len(s.coords) != 2 for s in doors):
        return doors
    return [replace(s, group=first_group + k) for k, s in enumerate(doors)]


def door_line_opening(item, walls) -> Polygon | None:
    """The opening of a door line in a plan drawn one layer per room when
    no wall gap fits it (the rooms' outlines end on it at an angle, or it
    is wider than a door leaf: a shop front, the end of an escalator lane):
    the line itself, ``THIN_WALL`` deep, when both its ends meet walls and
    it does not run along one. None otherwise.

    ``item``: one door drawing (lines, metres); ``walls``: the wall solids."""
    lines = [g for g in shapely.get_parts(item) if isinstance(g, LineString)]
    if len(lines) != 1 or lines[0].length < MIN_OPENING_WIDTH:
        return None
    line = lines[0]
    ends = [shapely.Point(line.coords[0]), shapely.Point(line.coords[-1])]
    if any(walls.distance(p) > JAMB_REACH for p in ends):
        return None
    if walls.intersection(line).length > 0.5 * line.length:
        return None
    return line.buffer(THIN_WALL / 2.0, cap_style="flat")

"""Draw the bundled example plan ``maps/flat.dxf``: a two-bedroom flat.

The plan is drawn the way an architect's CAD file looks, so that the DXF
importer meets the same things it meets in real drawings:

* millimetres (``$INSUNITS = 4``), walls as double lines on ``A-WALL``
  with jamb lines closing every opening and clean corners and T-junctions;
* doors (``A-DOOR``) and windows (``A-GLAZ``) as block references placed in
  the wall gaps, some doors mirrored with a negative x scale;
* columns (``A-COLS``) as hatched squares and a circle;
* furniture (``A-FURN``, with nested blocks), room labels and dimensions
  (``A-ANNO``) that an importer must ignore;
* two deliberate drawing faults: one wall line drawn twice and one 5 mm gap
  where two wall lines should meet (see ``DIRT`` below).

The wall linework is derived, not typed: every wall is a polygon, the
polygons are unioned, the openings cut out, and the outline of the result is
written as LINE entities. That gives the faces, the jambs and the junctions
exactly as a draughtsman would draw them. The output is deterministic (fixed
header metadata, sorted wall lines), so the committed file can be checked
against this module (:func:`write`).

Usage::

    python tools/make_flat.py [--out maps/flat.dxf]

Coordinates below are in millimetres; x east, y north, origin at the
south-west outer corner of the building.
"""

from __future__ import annotations

import math
from pathlib import Path

import ezdxf
from ezdxf import bbox, zoom
from ezdxf.enums import TextEntityAlignment
from shapely.geometry import Point, Polygon, box
from shapely.ops import unary_union

DEFAULT_OUT = Path(__file__).resolve().parents[2] / "maps" / "flat.dxf"

EXTERIOR = 300  # exterior wall thickness
PARTITION = 100  # interior partition thickness
WET_WALL = 120  # partition carrying the bathroom services
LEAF = 40  # door leaf thickness as drawn

LAYERS = {
    # name: (ACI colour, linetype, lineweight in 1/100 mm)
    "A-WALL": (7, "Continuous", 50),
    "A-DOOR": (4, "Continuous", 18),
    "A-GLAZ": (5, "Continuous", 18),
    "A-COLS": (1, "Continuous", 35),
    "A-FURN": (8, "Continuous", 13),
    "A-FURN-OVHD": (8, "DASHED", 13),
    "A-ANNO": (2, "Continuous", 18),
}

# --- walls -----------------------------------------------------------------

# Centre line of the exterior wall, counter-clockwise. The living room's
# south wall steps out into a three-sided bay with 45-degree sides.
EXTERIOR_CENTRE = [
    (150, 150),
    (4150, 150),
    (4750, -450),
    (6550, -450),
    (7150, 150),
    (10850, 150),
    (10850, 8350),
    (150, 8350),
]

# Interior partitions as face-to-face rectangles (xmin, ymin, xmax, ymax).
PARTITIONS = {
    "bedrooms / corridor": (300, 5000, 10700, 5100),
    "bedroom 1 / bathroom": (3900, 5100, 4000, 8200),
    "bathroom / bedroom 2": (6200, 5100, 6200 + WET_WALL, 8200),
    "corridor / kitchen, living": (300, 3800, 8100, 3900),
    "living / hall": (8000, 300, 8100, 3800),
    "hall / WC": (8100, 1900, 10700, 2000),
    "storage / corridor": (1500, 3900, 1600, 5000),
    "kitchen / living (stub)": (3200, 2000, 3300, 3800),
}

# Rooms: name, label position, area shown on the label (m^2, or None).
ROOMS = [
    ("BEDROOM 1", (2100, 7000), True),
    ("BATHROOM", (4900, 6400), False),
    ("BEDROOM 2", (7700, 7000), True),
    ("STORAGE", (900, 4450), False),
    ("CORRIDOR", (4800, 4450), False),
    ("ENTRANCE HALL", (9100, 3300), False),
    ("WC", (9300, 700), False),
    ("KITCHEN", (1900, 2700), True),
    ("LIVING ROOM", (5600, 800), True),
]

# --- openings ----------------------------------------------------------------
# A door is given by its hinge and latch points on the face of the wall on
# the side it swings into, and the direction it swings into.
DOORS = [
    # name, block width, hinge (x, y), latch (x, y), swing direction
    ("entrance", 900, (10700, 4500), (10700, 3600), (-1, 0)),
    ("bedroom 1", 800, (3700, 5100), (2900, 5100), (0, 1)),
    ("bathroom", 800, (4200, 5100), (5000, 5100), (0, 1)),
    ("bedroom 2", 800, (6500, 5100), (7300, 5100), (0, 1)),
    ("living room", 900, (7700, 3800), (6800, 3800), (0, -1)),
    ("storage", 800, (1600, 4900), (1600, 4100), (1, 0)),
    ("WC", 800, (9500, 1900), (10300, 1900), (0, -1)),
]

# A window is given by the two ends of its opening on the outer wall face,
# ordered so that the building lies to the left of start -> end.
WINDOWS = [
    ("bedroom 1", 1500, (2800, 8500), (1300, 8500)),
    ("bathroom", 600, (5400, 8500), (4800, 8500)),
    ("bedroom 2", 1500, (9300, 8500), (7800, 8500)),
    ("kitchen", 1200, (0, 2500), (0, 1300)),
    ("living room bay", 1200, (5050, -600), (6250, -600)),
    ("WC", 600, (9800, 0), (10400, 0)),
]

# Columns: two square concrete columns and a round one.
SQUARE_COLUMNS = [
    ("kitchen opening", (3100, 300, 3400, 600)),
    ("living room corner", (7650, 300, 8000, 650)),
]
ROUND_COLUMNS = [("living room", (6900, 2000), 150)]

# Deliberate faults, as found in real drawings.
DIRT = {
    # This wall line (west face of the bedroom 1 / bathroom partition) is
    # written twice.
    "duplicate": ((3900, 5100), (3900, 8200)),
    # This wall line (outer face of the north wall at the north-east corner)
    # stops 5 mm short of the corner it should reach.
    "gap_at": (11000, 8500),
    "gap": 5.0,
}

# --- furniture -----------------------------------------------------------------
# Blocks stand with their back (the side against a wall) on local y = 0 and
# their body towards -y; they are inserted on the wall face, and the rotation
# turns the back to the wall named.
AGAINST = {"north": 0, "west": 90, "south": 180, "east": -90}

FURNITURE = [
    # block, insertion point, rotation
    ("BED_DOUBLE", (300, 6700), AGAINST["west"]),
    ("BED_DOUBLE", (10700, 6700), AGAINST["east"]),
    ("SOFA", (5000, 3800), AGAINST["north"]),
    ("TABLE_4", (4500, 1500), 90),
    ("KITCHEN_COUNTER", (300, 300), AGAINST["west"]),
    ("BATHTUB", (4850, 8200), AGAINST["north"]),
    ("TOILET", (6200, 6500), AGAINST["east"]),
    ("BASIN", (6200, 5650), AGAINST["east"]),
    ("TOILET", (8600, 300), AGAINST["south"]),
    ("BASIN", (8100, 1300), AGAINST["west"]),
    ("WARDROBE", (10700, 2850), AGAINST["east"]),
]

DIMENSIONS = [
    # p1, p2, a point on the dimension line, angle of the dimension line
    ((0, 8500), (11000, 8500), (0, 9300), 0),
    ((11000, 0), (11000, 8500), (11800, 0), 90),
    ((300, 8200), (3900, 8200), (0, 7900), 0),
    ((300, 3800), (3200, 3800), (0, 3550), 0),
    ((0, 3800), (0, 5100), (-800, 0), 90),
]


# --- geometry helpers ----------------------------------------------------------


def wall_outline():
    """All walls with the openings cut out, as one shapely geometry."""
    centre = Polygon(EXTERIOR_CENTRE)
    half = EXTERIOR / 2
    exterior = centre.buffer(half, join_style="mitre").difference(
        centre.buffer(-half, join_style="mitre")
    )
    walls = unary_union([exterior, *(box(*r) for r in PARTITIONS.values())])
    # a door's hinge and latch lie on the face it swings away from, so the
    # wall is behind them; the cut is as deep as the thickest wall
    cuts = [_opening_box(hinge, latch, EXTERIOR, (-swing[0], -swing[1]))
            for _, _, hinge, latch, swing in DOORS]
    cuts += [_opening_box(start, end, EXTERIOR, _left(start, end))
             for _, _, start, end in WINDOWS]
    return walls.difference(unary_union(cuts))


def _left(a, b):
    """Unit normal to the left of the direction a -> b."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    n = math.hypot(dx, dy)
    return (-dy / n, dx / n)


def _opening_box(a, b, depth, normal, margin=50.0):
    """Rectangle on a -> b reaching ``depth`` (+margin) along ``normal``.

    Starts ``margin`` behind the face, so it cuts the wall band cleanly
    whichever face a and b lie on, without reaching any other wall.
    """
    nx, ny = normal
    back = [(p[0] - nx * margin, p[1] - ny * margin) for p in (a, b)]
    front = [(p[0] + nx * (depth + margin), p[1] + ny * (depth + margin))
             for p in (b, a)]
    return Polygon(back + front)


def wall_lines(outline):
    """The outline's edges as sorted ((x1, y1), (x2, y2)) tuples in mm.

    Collinear vertices are dropped, so each wall face between two corners or
    junctions is one line, and coordinates are rounded to 1/1000 mm.
    """
    polys = getattr(outline, "geoms", [outline])
    lines = []
    for poly in polys:
        for ring in [poly.exterior, *poly.interiors]:
            pts = [(round(x, 3), round(y, 3)) for x, y in ring.coords[:-1]]
            pts = _drop_collinear(pts)
            for i, p in enumerate(pts):
                q = pts[(i + 1) % len(pts)]
                lines.append(tuple(sorted([p, q])))
    return sorted(lines)


def _drop_collinear(pts):
    out = list(pts)
    changed = True
    while changed:
        changed = False
        for i in range(len(out)):
            a, b, c = out[i - 1], out[i], out[(i + 1) % len(out)]
            cross = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0])
            if abs(cross) < 1e-6 * (1 + math.dist(a, b) * math.dist(b, c)):
                del out[i]
                changed = True
                break
    return out


def add_dirt(lines):
    """Apply ``DIRT`` to the wall lines; returns the list to write."""
    out = []
    corner = DIRT["gap_at"]
    applied = []
    for p, q in lines:
        if corner in (p, q) and p[1] == q[1]:  # the horizontal face at the corner
            far, near = (p, q) if q == corner else (q, p)
            d = DIRT["gap"] / math.dist(far, near)
            near = (near[0] + (far[0] - near[0]) * d, near[1] + (far[1] - near[1]) * d)
            p, q = far, near
            applied.append("gap")
        out.append((p, q))
        if (p, q) == DIRT["duplicate"]:
            out.append((p, q))
            applied.append("duplicate")
    # a layout change must not make the faults disappear silently
    if sorted(applied) != ["duplicate", "gap"]:
        raise RuntimeError(f"DIRT no longer matches the walls: applied {applied}")
    return out


def insert_transform(hinge, latch, swing):
    """Rotation (deg) and x scale placing a door block at ``hinge``.

    Door blocks open along local +x from the hinge and swing into local +y.
    If the swing side is to the right of hinge -> latch, the block is
    mirrored (x scale -1) instead of turned over.
    """
    ux, uy = latch[0] - hinge[0], latch[1] - hinge[1]
    cross = ux * swing[1] - uy * swing[0]
    if cross > 0:
        return math.degrees(math.atan2(uy, ux)) % 360, 1
    return math.degrees(math.atan2(-uy, -ux)) % 360, -1


# --- blocks --------------------------------------------------------------------


def define_blocks(doc):
    for width in sorted({w for _, w, *_ in DOORS}):
        blk = doc.blocks.new(f"DOOR_{width}", base_point=(0, 0))
        blk.add_lwpolyline([(0, 0), (LEAF, 0), (LEAF, width), (0, width)], close=True)
        blk.add_arc((0, 0), width, 0, 90)

    for width in sorted({w for _, w, *_ in WINDOWS}):
        blk = doc.blocks.new(f"WIN_{width}", base_point=(0, 0))
        for y in (0, EXTERIOR / 2, EXTERIOR):  # outer frame, glass, inner frame
            blk.add_line((0, y), (width, y))

    _define_furniture(doc)


def _rect(blk, x0, y0, x1, y1, **kw):
    return blk.add_lwpolyline([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], close=True, **kw)


def _rounded_rect(blk, x0, y0, x1, y1, r):
    b = math.tan(math.radians(22.5))  # bulge of a quarter circle
    pts = [
        (x0 + r, y0, 0), (x1 - r, y0, b), (x1, y0 + r, 0), (x1, y1 - r, b),
        (x1 - r, y1, 0), (x0 + r, y1, b), (x0, y1 - r, 0), (x0, y0 + r, b),
    ]
    return blk.add_lwpolyline(pts, format="xyb", close=True)


def _define_furniture(doc):
    # Chair, also used nested inside the dining table block.
    chair = doc.blocks.new("CHAIR")
    _rect(chair, -220, -200, 220, 200)
    _rect(chair, -220, -250, 220, -200)

    table = doc.blocks.new("TABLE_4")
    _rect(table, -700, -400, 700, 400)
    for x in (-350, 350):
        table.add_blockref("CHAIR", (x, -520))
        table.add_blockref("CHAIR", (x, 520), dxfattribs={"rotation": 180})

    bed = doc.blocks.new("BED_DOUBLE")  # 1600 x 2000, head at the wall
    _rect(bed, -800, -2000, 800, 0)
    _rect(bed, -800, -50, 800, 0)  # headboard
    for x in (-420, 420):
        _rounded_rect(bed, x - 330, -400, x + 330, -100, 80)
    bed.add_lwpolyline([(-800, -650), (800, -650), (550, -900)])  # turned-back cover

    sofa = doc.blocks.new("SOFA")  # 2200 x 900
    b = math.tan(math.radians(22.5))
    sofa.add_lwpolyline(
        [(-1100, 0, 0), (-1100, -800, b), (-1000, -900, 0), (1000, -900, b),
         (1100, -800, 0), (1100, 0, 0)],
        format="xyb", close=True,
    )
    sofa.add_line((-950, -200), (950, -200))  # back cushion
    sofa.add_line((-950, -900), (-950, -200))  # arms
    sofa.add_line((950, -900), (950, -200))
    sofa.add_line((0, -900), (0, -200))  # seat cushions

    sink = doc.blocks.new("SINK")  # centred, nested in the counter
    _rect(sink, -400, -230, 400, 230)
    _rounded_rect(sink, -360, -190, 100, 190, 60)
    sink.add_circle((-130, 0), 25)
    sink.add_lwpolyline([(160, -170), (360, -170), (360, 170), (160, 170)])

    counter = doc.blocks.new("KITCHEN_COUNTER")  # 3000 x 600, runs along +x
    _rect(counter, 0, -600, 3000, 0)
    counter.add_blockref("SINK", (1600, -300))
    _rect(counter, 380, -570, 1000, -30)  # hob
    for x, y, r in ((530, -430, 90), (850, -430, 70), (530, -170, 70), (850, -170, 90)):
        counter.add_circle((x, y), r)
    # wall cabinets above, drawn dashed as overhead
    counter.add_line((0, -350), (3000, -350), dxfattribs={"layer": "A-FURN-OVHD"})

    tub = doc.blocks.new("BATHTUB")  # 1700 x 750
    _rect(tub, -850, -750, 850, 0)
    _rounded_rect(tub, -780, -680, 780, -70, 200)
    tub.add_circle((-620, -375), 30)

    toilet = doc.blocks.new("TOILET")  # tank 400 x 180, bowl in front
    _rect(toilet, -200, -180, 200, 0)
    toilet.add_ellipse((0, -430), major_axis=(0, -250), ratio=0.72)

    basin = doc.blocks.new("BASIN")  # 550 x 420
    _rect(basin, -275, -420, 275, 0)
    basin.add_ellipse((0, -220), major_axis=(200, 0), ratio=0.7)

    wardrobe = doc.blocks.new("WARDROBE")  # 1200 x 600, door leaves hinted
    _rect(wardrobe, -600, -600, 600, 0)
    wardrobe.add_line((-600, -600), (0, 0))
    wardrobe.add_line((0, -600), (600, 0))


# --- drawing -------------------------------------------------------------------


def setup_document():
    doc = ezdxf.new("R2010", setup=["linetypes"])
    doc.units = ezdxf.units.MM
    doc.header["$INSUNITS"] = 4
    doc.header["$MEASUREMENT"] = 1
    doc.header["$LUNITS"] = 2
    doc.header["$LTSCALE"] = 20
    for name, (color, linetype, lineweight) in LAYERS.items():
        doc.layers.add(name, color=color, linetype=linetype, lineweight=lineweight)
    doc.styles.add("ARCH", font="arial.ttf")
    doc.dimstyles.new(
        "ARCH-100",
        dxfattribs={
            "dimtxsty": "ARCH",
            "dimtxt": 180,
            "dimasz": 120,
            "dimblk": "ARCHTICK",
            "dimexe": 120,
            "dimexo": 150,
            "dimgap": 50,
            "dimtad": 1,
            "dimdec": 0,
            "dimclrd": 2,
            "dimclre": 2,
        },
    )
    return doc


def draw(doc):
    msp = doc.modelspace()
    define_blocks(doc)

    for p, q in add_dirt(wall_lines(wall_outline())):
        msp.add_line(p, q, dxfattribs={"layer": "A-WALL"})

    for _, width, hinge, latch, swing in DOORS:
        rotation, xscale = insert_transform(hinge, latch, swing)
        msp.add_blockref(
            f"DOOR_{width}", hinge,
            dxfattribs={"layer": "A-DOOR", "rotation": rotation, "xscale": xscale},
        )

    for _, width, start, end in WINDOWS:
        rotation = math.degrees(math.atan2(end[1] - start[1], end[0] - start[0])) % 360
        msp.add_blockref(f"WIN_{width}", start,
                         dxfattribs={"layer": "A-GLAZ", "rotation": rotation})

    for _, (x0, y0, x1, y1) in SQUARE_COLUMNS:
        outline = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
        msp.add_lwpolyline(outline, close=True, dxfattribs={"layer": "A-COLS"})
        hatch = msp.add_hatch(color=256, dxfattribs={"layer": "A-COLS"})
        hatch.paths.add_polyline_path(outline, is_closed=True)
    for _, centre, radius in ROUND_COLUMNS:
        msp.add_circle(centre, radius, dxfattribs={"layer": "A-COLS"})

    for name, point, rotation in FURNITURE:
        msp.add_blockref(name, point, dxfattribs={"layer": "A-FURN", "rotation": rotation})

    _annotate(msp)

    ext = bbox.extents(msp)
    extmin, extmax = ext.extmin, ext.extmax
    # ezdxf copies the layout's extents to $EXTMIN/$EXTMAX when saving
    msp.dxf.extmin = (extmin[0], extmin[1], 0)
    msp.dxf.extmax = (extmax[0], extmax[1], 0)
    zoom.extents(msp, factor=1.05)


def _annotate(msp):
    anno = {"layer": "A-ANNO", "style": "ARCH"}
    areas = _room_areas()
    for name, (x, y), with_area in ROOMS:
        if with_area:
            text = f"{name}\\P{areas[name]:.1f} m²"
            mtext = msp.add_mtext(text, dxfattribs={**anno, "char_height": 200})
            mtext.set_location((x, y), attachment_point=5)
        else:
            msp.add_text(name, height=160, dxfattribs=anno).set_placement(
                (x, y), align=TextEntityAlignment.MIDDLE_CENTER
            )
    for p1, p2, base, angle in DIMENSIONS:
        dim = msp.add_linear_dim(base=base, p1=p1, p2=p2, angle=angle,
                                 dimstyle="ARCH-100", dxfattribs={"layer": "A-ANNO"})
        dim.render()


def _room_areas():
    """Floor areas (m^2) of the labelled rooms, from the wall outline."""
    inside = Polygon(EXTERIOR_CENTRE).buffer(-EXTERIOR / 2, join_style="mitre")
    partitions = unary_union([box(*r) for r in PARTITIONS.values()])
    # the kitchen / living opening is closed on its centre line for areas
    split = box(3200, 300, 3300, 2000)
    spaces = inside.difference(partitions).difference(split)
    areas = {}
    for name, (x, y), with_area in ROOMS:
        if with_area:
            face = next(g for g in spaces.geoms if g.contains(Point(x, y)))
            areas[name] = face.area / 1e6
    return areas


def write(path):
    """Draw the plan and save it to ``path``, byte for byte reproducibly."""
    path = Path(path)
    fixed = ezdxf.options.write_fixed_meta_data_for_testing
    # constant creation/save stamps and GUIDs instead of the clock
    ezdxf.options.write_fixed_meta_data_for_testing = True
    try:
        doc = setup_document()
        draw(doc)
        # ezdxf registers the CLASS entries of the entity types in use from a
        # set; registering them first in sorted order fixes their order
        for dxftype in sorted(doc.entitydb.dxf_types_in_use()):
            doc.classes.add_class(dxftype)
        path.parent.mkdir(parents=True, exist_ok=True)
        doc.saveas(path)
    finally:
        ezdxf.options.write_fixed_meta_data_for_testing = fixed
    return path

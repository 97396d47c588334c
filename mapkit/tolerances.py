"""Every geometric tolerance of the map builder, in one documented place.

Lengths in metres, angles in degrees. Import the names, never repeat the
numbers: a tolerance that lives in two places drifts. The sizes of work
chunks (memory bounds, not geometry) are at the end, under "work sizes".
"""

from dataclasses import dataclass


@dataclass(frozen=True)
class GeometricZeros:
    """Where a computed number is zero: float noise, not geometry. One
    field per kind of quantity; the builder compares with these and never
    with a literal (``tests/test_layout.py`` holds it), so that the same
    zero meant in two places is one number. Unlike the tolerances below,
    they say nothing about drawings: only about float arithmetic.
    """

    #: A distance or length, metres, computed exactly up to float noise
    #: (coordinates metres to kilometres from the origin carry 1e-13 to
    #: 1e-10 m): below this it is none. A point this close to a line is on
    #: it, a radius this small is no radius, an extent this small has no scale.
    distance: float = 1e-9
    #: A length derived through several operations (GEOS's intersections,
    #: bisections) equals another within this, metres: a chord this much
    #: short of a whole probe still spans it, an annotated line this short
    #: has no direction, a distance band found by bisection is widened by it.
    derived_length: float = 1e-6
    #: Norms, lengths and areas are not divided by below this: a zero
    #: vector's direction is zero and an empty set's mean is zero, not NaN.
    divisor: float = 1e-12
    #: A ray meets an edge where the parameter along the edge is in [0, 1]
    #: within this: a ray through a shared vertex hits one of its edges.
    edge_parameter: float = 1e-12
    #: A ratio within this above a whole number is that number when
    #: rounded up (``ceil(3.0000000001)`` is 3: a span of exactly three
    #: cells takes three).
    whole_number: float = 1e-9
    #: A unit direction's component below this is zero (a click ray that
    #: does not point down never meets the floor).
    direction: float = 1e-9


#: The geometric zeros of the builder (:class:`GeometricZeros`).
ZERO = GeometricZeros()

#: Points closer than this are the same point (vertex merging, snapping of
#: CAD endpoints that should meet). Architects' drawings are exact to well
#: under a millimetre, but exported files carry float noise.
MERGE = 1e-3

#: Dangling wall endpoints closer than this are joined (gaps in real drawings).
SNAP_GAP = 0.02

#: Occluders are shrunk by this in the definition of "visible", so that a
#: sight line grazing a wall face, or ending on the face it belongs to, is
#: not blocked by float noise. The region builder itself shrinks by the
#: larger ``VIS_BUILD_SHRINK`` (lists stay supersets); brute-force checks
#: shrink by twice this.
OCCLUSION_SHRINK = 1e-3

#: Two edges are collinear (and merge) if their directions differ by less
#: than this many degrees and their lines are closer than ``MERGE``.
COLLINEAR_DEG = 1.0

#: A polygon vertex is a real corner (a vertical edge is seen there) when the
#: outline turns by more than this many degrees. Curves flattened by the
#: importers turn by less at each vertex, so they make no vertical edges.
CORNER_DEG = 20.0

#: Curves (arcs, circles, ellipses, splines, bulges) are flattened so that
#: each chord deviates from the curve by at most this much.
CURVE_SAGITTA = 0.005

#: Largest turn per flattened curve step, degrees; keeps flattened vertices
#: below ``CORNER_DEG`` so a curve is never mistaken for corners.
CURVE_STEP_DEG = 10.0

#: Vertical or horizontal: a segment whose direction is within this many
#: degrees of the vertical (horizontal plane) is classified as such.
AXIS_DEG = 2.0

#: Footprints are closed by this much (metres) before outlines are taken, so
#: that an opening drawn a hair away from its wall does not leave a sliver
#: (the edge stage, :mod:`mapkit.edges`).
FOOTPRINT_CLOSE_GAP = 5 * MERGE

#: Rooms of their own ceiling heights (:mod:`mapkit.edges`): a room's pass
#: takes only the walls within this of it. Walls exist only next to rooms,
#: so where this cuts a wall it runs along another room, nearer that room.
ZONE_REACH = 1.0

# ---- plan reconstruction (mapkit.importers.dxf) -----------------------------

#: Single wall lines that bound no solid are thickened to this total width.
THIN_WALL = 0.1

#: A closed outline standing alone (a column, a solid block) with at most
#: this area, square metres, is solid even outside any enclosure.
COLUMN_MAX_AREA = 1.0

#: Door and window jambs: wall material within this distance of the opening's
#: drawing counts as touching it (door blocks stop a little short of the wall).
JAMB_REACH = 0.1

#: Openings narrower than this are drawing noise, not a passage or a window.
MIN_OPENING_WIDTH = 0.3

#: If closed outlines enclose less than this fraction of the walls' convex
#: hull, the plan is open (a pavilion): the interior comes from a floor layer
#: or the hull instead.
OPEN_PLAN_FRACTION = 0.25

#: Two wall ends facing each other in line at most this far apart are an
#: opening (a window whose glass is not drawn, a doorway without a door):
#: shut to tell the inside from the outside. Wide enough for a wide window
#: or a double door; farther apart, the walls are two walls.
BRIDGE_MAX_GAP = 4.0

#: A plan without a closed outline (nor a floor layer) is closed from its
#: walls: gaps in its outer walls up to this wide, metres, are bridged (a
#: building's typical opening: a double door, a garage door, an entrance
#: beside a corner where no wall end faces another; a recess of the facade
#: narrower than this becomes inside too). A wider gap leaves the plan open:
#: it is refused, naming --floor (:mod:`mapkit.importers.dxf.closure`).
OUTLINE_MAX_GAP = 3.0

#: A floor layer's outline beyond the outer walls' closed footprint is
#: inside the building when more than this share of its rim runs along that
#: footprint (:func:`mapkit.importers.dxf.reconstruct._floor_within_building`):
#: the building then surrounds more of it than the outside does (an atrium
#: or a courtyard open through a ramp or an entrance wider than
#: ``OUTLINE_MAX_GAP``). A terrace laid along one side of the building meets
#: it along under half its rim (one side of four), one drawn apart not at all.
FLOOR_SURROUNDED_SHARE = 0.5

#: Mitre limit (times the offset) of that closing's offsets: square corners
#: stay square; sharper ones are bevelled rather than spiking far out.
OUTLINE_MITRE_LIMIT = 2.0

#: Room fills (zone layers) leave the walls between them implicit: the thin
#: strips between fills are walls. Where the drawn walls already cover at
#: least this share of those strips, the walls are drawn and the rest of
#: the strips are doorways and openings (a facility-management plan's room
#: hatches stop at the wall faces and across the doors): no strip is added.
ZONE_WALLS_DRAWN_SHARE = 0.5

#: A pocket door's leaf (one line inside a wall, running to its end) is at
#: most this long, metres (a wide single leaf); a longer line in a wall on
#: the door layer is something else (:mod:`mapkit.importers.dxf.pocket_doors`).
POCKET_DOOR_MAX_LEAF = 1.5

#: Wall ends are "in line" and "facing" within this many degrees; an end
#: face is square to its wall within it too.
BRIDGE_ANGLE_DEG = 15.0

#: A part of the free space touches a door or doorway (it is entered, a
#: room, not a shaft or a light well: :mod:`mapkit.importers.dxf.reachable`)
#: within the robot's radius plus this, metres: the free space stops the
#: radius short of a gap narrower than the robot, and buffering rounds that
#: by well under this. Far below the thinnest wall (``THIN_WALL``), so a
#: room beside a door's jamb, behind a partition, is not touched.
DOOR_REACH_SLACK = 0.02

#: Free-space pieces smaller than this, square metres, are slivers between
#: walls, not places a camera can stand.
MIN_FREE_AREA = 0.05

#: No coordinate of a building lies farther than this from its file's
#: origin, metres (UTM northings reach 10^7 m): a farther one is a damaged
#: value (1e308 where the rest spans metres), and the squares and buffers of
#: such values overflow. Importers of coordinates given as numbers (segments
#: files, ZInD) refuse it, naming where it is.
MAX_COORDINATE = 1e8

# ---- segments files (mapkit/importers/segments.py) -----------------------
#: Two end heights within this many metres are one level (a horizontal
#: segment; the floor and ceiling levels).
SEGMENTS_LEVEL = 0.02
#: Without "walls", the floor-level segments are wall faces this thick
#: (metres): they hide what is behind them.
SEGMENTS_WALL_FACE = 0.1
#: Without an "outline", gaps between floor-level segments up to this wide
#: (metres: a double door) are shut to find the rooms they enclose.
SEGMENTS_CLOSE_GAP = 1.5

#: Stairs drawn on a wall layer (mapkit/importers/dxf/stairs.py): a run of
#: treads is at least ``STAIR_MIN_TREADS`` straight lines, each
#: ``STAIR_TREAD_LENGTH`` metres long (a flight's width: a narrow service
#: stair to a wide entrance flight), parallel, starting and ending level
#: with each other within ``STAIR_TREAD_ALIGN`` metres, one after the other
#: at one spacing (the going) in ``STAIR_GOING`` metres (building codes ask
#: 0.22 to 0.35 m; outdoor steps reach 0.4 m), each spacing within
#: ``STAIR_GOING_EVEN`` metres of the run's first. Lines at a regular
#: spacing of their own are rare in a plan's walls otherwise: window
#: frames lie 0.05 to 0.1 m apart, partitions a metre or more.
STAIR_MIN_TREADS = 5
STAIR_TREAD_LENGTH = (0.6, 3.0)
STAIR_TREAD_ALIGN = 0.05
STAIR_GOING = (0.2, 0.4)
STAIR_GOING_EVEN = 0.02
#: A part of the free space lies in a stair well (the room the walls, with
#: door gaps and doorways shut, enclose around a run) when at least this
#: share of its area is inside it: the rest is the margin it reaches into
#: its door's gap. A part spreading through rooms is mostly outside.
STAIR_WELL_SHARE = 0.5

#: A plan whose building geometry lies wholly farther than this from the
#: file's origin, metres, is georeferenced (facility-management drawings in
#: a national grid, 1758 km out): it is moved to a local origin, the offset
#: kept in the map (``origin_offset_m``). A building drawn near its origin
#: reaches within this of it.
LOCAL_ORIGIN_BEYOND_M = 1000.0

#: A door swing drawn on a wall layer (mapkit/importers/dxf/door_swings.py):
#: its arc's radius is a door leaf's width, metres (a narrow cupboard door
#: to a wide single door); its sweep at most this many degrees (doors are
#: drawn anywhere from a few degrees open to square). Its leaf line starts
#: within ``DOOR_SWING_TIP_SHARE`` of the radius (at least
#: ``DOOR_SWING_SNAP`` metres) of one end of the arc, crosses the arc there
#: at ``DOOR_SWING_MIN_CROSSING_DEG`` or more (a leaf is radial; the wall a
#: rounded corner joins is tangent), and is ``DOOR_SWING_LEAF_LENGTH``
#: times the radius long: loosely drawn swings (hal9k's plan: arcs through
#: three points, leaves up to 1.6 radii) still count.
DOOR_SWING_RADIUS = (0.3, 1.5)
DOOR_SWING_MAX_SWEEP_DEG = 120.0
DOOR_SWING_SNAP = 0.05
DOOR_SWING_TIP_SHARE = 0.15
DOOR_SWING_MIN_CROSSING_DEG = 50.0
DOOR_SWING_LEAF_LENGTH = (0.6, 1.9)

#: A drawing no layer of which is named like walls: the layer of unknown
#: role holding at least this many door swings, in one unit only, is taken
#: as its walls, read in that unit (mapkit/importers/dxf/swing_layer.py):
#: as many as tell a drawing's units by its doors (``DOOR_UNITS_MIN_DOORS``).
#: The corpus's drawing sheet (ciq_building): 27 on its plans' layer, 2 on
#: a section's.
SWING_LAYER_MIN_SWINGS = 5
#: ... and only when most of the layer's door-sized arcs (radius in
#: ``DOOR_SWING_RADIUS``, sweep at most ``DOOR_SWING_MAX_SWEEP_DEG``) are
#: swings, at least ``SWING_LAYER_ARC_SHARE`` of them (ciq_building's
#: 'DETAILS' 27 of 27 in mm, hal9k's layer 0 13 of 13 in cm; a framing
#: plan's lettering, walldet_sample's 'F-0': 6 of 90, 12 and 28 in dm, m
#: and ft), and its swings hang in walls drawn with them (a layer of
#: doors alone, or of doors and furniture beside walls on another layer,
#: is no wall layer): at least ``SWING_LAYER_HINGED_SHARE`` of the swings'
#: hinges within ``SWING_LAYER_HINGE_GAP`` metres of the layer's other
#: linework (ciq_building: all 27 within 0.075 m, the jamb or the wall
#: face the leaf turns on), and that linework at least
#: ``SWING_LAYER_LINES_PER_SWING`` metres long per swing (ciq_building's
#: 'DETAILS': 52 m; a room of 3 x 3 m with its door, single-line walls:
#: 12 m; a door layer's frames and double-line leaves: 1 to 3 m).
SWING_LAYER_ARC_SHARE = 0.67
SWING_LAYER_HINGE_GAP = 0.15
SWING_LAYER_HINGED_SHARE = 0.5
SWING_LAYER_LINES_PER_SWING = 5.0

#: A room's outline (mapkit/importers/dxf/room_outlines.py) that the walls
#: cut into more than one part of at least this many square metres is
#: sealed in part (smaller parts are slivers between the outline and a wall
#: face).
ROOM_PART_MIN_AREA = 0.5

#: Jamb ticks (mapkit/importers/dxf/jamb_ticks.py): a straight wall stroke
#: at most this long, metres, that crosses a longer wall stroke within the
#: middle ``JAMB_TICK_MIDDLE_SHARE`` of its length, within
#: ``JAMB_TICK_ANGLE_DEG`` of square, marks an opening's jamb (hal9k's plan:
#: 8 to 11 cm ticks across single-line walls), not a wall. A wall joining
#: another ends on it; the shortest walls are longer than this.
JAMB_TICK_MAX_LENGTH = 0.25
JAMB_TICK_MIDDLE_SHARE = 0.5
JAMB_TICK_ANGLE_DEG = 20.0

#: A door drawn over an unbroken wall (mapkit/importers/dxf/openings.py,
#: ``cut_opening``) cuts an opening at most this wide, metres (a double
#: door; wider drawings over a wall are something else), whose footprint
#: lies at least this share in wall.
MAX_DOOR_WIDTH = 2.5
CUT_MIN_WALL_SHARE = 0.5
#: ... and which reaches at least this share across the wall under it: a
#: swing's hinge on a single-line wall lies on its centre line, half way
#: across, less where a wall joining there widens the piece under the
#: drawing (hal9k's plan: 0.39); a door drawn against a wall's face only
#: touches it (0).
CUT_MIN_REACH = 0.3
#: Two such cut openings that meet end to end are the leaves of one double
#: door when their union fills at least this share of its rotated bounding
#: box (in line, one wall; two doors meeting at a corner fill about half).
DOUBLE_DOOR_SQUARENESS = 0.95
#: A door swing over an unbroken wall (mapkit/importers/dxf/closed_leaf.py)
#: opens the wall where its leaf closes when the wall crosses the whole
#: doorway: each of this many probes across it, evenly spaced between the
#: jambs, meets wall. The closed leaf's direction snaps to the wall edges
#: within this many degrees of it (the two leaves of a double door drawn
#: meeting tip to tip close a few degrees off the wall; ciq_building: 13).
SWING_CUT_PROBES = 5
WALL_DIRECTION_SNAP_DEG = 15.0

#: Cross marks (mapkit/importers/dxf/cross_marks.py): the X across a box
#: that marks a lift or a shaft is two straight lines, each of strokes at
#: least ``CROSS_MARK_MIN_ARM`` metres long (one, or two in line with a gap
#: of at most ``CROSS_MARK_MAX_GAP`` metres at the crossing: ciq_building's
#: lift, 0.4 m), crossing at ``CROSS_MARK_MIN_ANGLE_DEG`` or more, each
#: within ``CROSS_MARK_MIDDLE_SHARE`` of its half length of its middle (a
#: box's diagonals cross at their middles; one stopping short where a door
#: swings, a little off it: 44 %), the shorter line at least
#: ``CROSS_MARK_LENGTH_RATIO`` of the longer (a box's diagonals are equal;
#: the one stopping short at a door, 0.88 of the other; a wall line crossed
#: by a chamfer, 0.3).
CROSS_MARK_LENGTH_RATIO = 0.75
CROSS_MARK_MIN_ARM = 0.3
CROSS_MARK_MAX_GAP = 0.5
CROSS_MARK_MIN_ANGLE_DEG = 30.0
CROSS_MARK_MIDDLE_SHARE = 0.5
#: Two strokes are one line (a diagonal drawn in two pieces) when their
#: directions differ by at most this many degrees.
CROSS_MARK_IN_LINE_DEG = 1.0

#: A stroke on a door layer whose bounding box's diagonal is longer than
#: this, metres, is not part of a door drawing (a leaf, its swing and the
#: jambs of the widest door, ``MAX_DOOR_WIDTH``, fit in a box under 4 m
#: across): a dimension chain or an outline drawn on the door layer (the
#: college floor's 122 m polyline on '门窗墙'), which would glue every door
#: it passes into one drawing. Left out of the doors.
DOOR_STROKE_MAX_SPAN = 2 * MAX_DOOR_WIDTH

#: Sheets (mapkit/importers/dxf/sheets.py): wall linework closer than
#: this, metres, belongs to one plan (a plan's wall strokes join around
#: its openings, and the widest opening is bridged at ``OUTLINE_MAX_GAP``
#: when a building is closed from its walls; plans side by side on a sheet
#: stand farther apart: the two storeys of the corpus's smh_dxf28 4.9 m); a
#: cluster with at least this share of the largest one's wall length is a
#: plan of its own, a smaller one (a column, a shed) stays with its plan.
SHEET_GAP_M = 3.0
SHEET_MIN_PLAN_SHARE = 0.2
#: ... and whose walls' bounding box covers at least this share of the
#: largest one's (storeys side by side cover about the same ground; an
#: annex beside a building does not).
SHEET_MIN_PLAN_AREA_SHARE = 0.5

#: Plans drawn one layer per room (mapkit/importers/dxf/room_layers.py):
#: at least this many layers named with one stem and a running number
#: ('Raum_001', 'Raum_002', 'Raum_003') are a drawing's rooms, one a layer
#: (two numbered layers are as often a storey's two halves or two sheets).
PER_ROOM_MIN_LAYERS = 3

#: A plan drawn one layer per room: a space all barriers enclose (walls,
#: rooms' outlines, doors) that a door opens into is a room of its own when
#: less than this share of it lies in the rooms' closed outlines (a room
#: whose layer's outline stays open, closed by the walls around it: a
#: living room closed by a staircase and an open-to-sky void); one mostly
#: inside them is a room already there (mapkit/importers/dxf/room_layers.py).
ROOM_FACES_COVER_SHARE = 0.5

#: A plan whose walls span less than this, metres, and leave no free space
#: is probably read in the wrong units (a gallery drawn at 1:10 in metres
#: spans 4.6 m): the refusal names the --units or --scale that makes it a
#: building's size (:func:`mapkit.importers.dxf.units.rescale_hint`).
SMALL_PLAN_M = 10.0

#: Plausible building extent, metres (largest side); outside it the drawing
#: units are probably wrong.
PLAUSIBLE_EXTENT = (1.0, 2000.0)

#: Typical building size, metres: unitless drawings get the unit that puts
#: their extent closest to this (in log scale).
TYPICAL_EXTENT = 20.0

#: Door widths as drawn tell a drawing's units where its header is wrong
#: (a mall level whose header says metres, its doors 10 m wide: drawn in
#: decimetres; a house that says feet, drawn in inches): with at least
#: ``DOOR_UNITS_MIN_DOORS`` door drawings whose median width (the longer
#: side of each one's minimum rotated rectangle: a leaf's swing, a door
#: line, a block) falls outside ``DOOR_WIDTH_PLAUSIBLE`` metres, the unit
#: that puts the median closest to ``TYPICAL_DOOR_WIDTH`` (in log scale)
#: is taken, if that median is plausible, with a warning. On the real
#: corpus (docs/benchmarks/drawings.md) the right units give medians of
#: 0.75 to 1.5 m (a college's double doors); the two wrong headers 9 and
#: 10 m.
DOOR_UNITS_MIN_DOORS = 5
DOOR_WIDTH_PLAUSIBLE = (0.5, 2.5)
TYPICAL_DOOR_WIDTH = 0.9

#: A drawing without units is read in the unit that puts both its doors'
#: median width near ``TYPICAL_DOOR_WIDTH`` and its walls' thickness (the
#: length-weighted median distance between the two lines of its
#: double-line walls, :mod:`mapkit.importers.dxf.wall_thickness`) near
#: this, metres, in log scale (:func:`mapkit.importers.dxf.units.units_from_evidence`):
#: interior partitions of 0.1 m to outer walls of 0.4 m. Two independent
#: signs tell centimetres from inches (a factor of 2.54) where either alone
#: may not. A plan whose header's unit makes it no building and that draws
#: no doors and no doorways is read in the unit of the header's system that
#: puts its extent and its walls' thickness closest to ``TYPICAL_EXTENT`` and
#: this (:func:`mapkit.importers.dxf.units.units_from_size_and_doors`): a
#: plan of 23 m with 0.6 m stone walls in metres is 2.3 m with 6 cm walls in
#: decimetres.
TYPICAL_WALL_THICKNESS = 0.2

#: Doorway gaps in the wall lines tell the units of a plan that draws no
#: door symbols (fewer than ``DOOR_UNITS_MIN_DOORS``), measured by
#: :mod:`mapkit.importers.dxf.doorway_gaps` before the units are known, so
#: as shares of the plan's extent: wall ends closer than
#: ``GAP_UNITS_TOUCH_SHARE`` of it to another line touch it (no free end);
#: ends farther apart than ``GAP_UNITS_REACH_SHARE`` of it are no doorway;
#: a wall end runs into a wall standing within ``GAP_UNITS_FACING_DEG``
#: degrees of square to it; its partner across a doorway is sought among
#: its ``GAP_UNITS_NEIGHBOURS`` nearest wall ends. With at least
#: ``DOOR_UNITS_MIN_DOORS`` gaps (as many as door drawings) whose median is no door's width
#: (``DOOR_WIDTH_PLAUSIBLE``), the unit of the same system (metric or
#: imperial) that puts it closest to ``TYPICAL_DOOR_WIDTH`` is taken
#: (:func:`mapkit.importers.dxf.units.units_from_gaps`) if at least
#: ``GAP_UNITS_AGREE_SHARE`` of the gaps are then a door's width and the
#: plan's extent and walls' thickness together come closer to
#: ``TYPICAL_EXTENT`` and ``TYPICAL_WALL_THICKNESS``. Gaps are a weaker sign than
#: door symbols (a gallery's openings, a corridor's width, doorways of 0.7
#: to 2 m): a unit only 3.3 times another (m, ft) is never told from them.
#: On the corpus (docs/benchmarks/drawings.md) the right units give medians
#: of 0.76 to 2.4 m (a hall's wide openings); the gallery drawn at a
#: fraction of its size in metres 0.063 m, which no unit mends: its
#: refusal names the --scale its doorways say
#: (:func:`mapkit.importers.dxf.units.scale_from_gaps`).
GAP_UNITS_TOUCH_SHARE = 1e-3
GAP_UNITS_REACH_SHARE = 0.2
GAP_UNITS_FACING_DEG = 30.0
GAP_UNITS_NEIGHBOURS = 16
GAP_UNITS_AGREE_SHARE = 0.5

#: Double-line wall ends are capped only if both lines run within this many
#: degrees of parallel and the cap is within this of square to them.
WALL_CAP_ANGLE_DEG = 15.0

#: A drawing entity whose centre lies farther from the median centre of
#: the plan's entities than this many times the distance that holds 90 % of
#: them (or than the typical entity's size, if larger) is far outside the
#: rest (a damaged coordinate, 1e9 where the plan
#: spans 20 m): it is left out with a warning instead of making the plan
#: look a million kilometres across. A title block beside the plan lies
#: within a few times that distance. Plans of fewer than
#: ``DXF_FAR_MIN_ENTITIES`` entities are not judged.
DXF_FAR_FACTOR = 100.0
DXF_FAR_MIN_ENTITIES = 10

#: The self-check (mapkit/importers/dxf/self_check.py): the map is refused
#: when it contradicts its own drawing. Each bound is what real buildings
#: allow, checked on the corpus's tuning half (docs/benchmarks/drawings.md):
#:
#: - the free space (grown back by the robot's radius: the rooms' floor)
#:   covers at least ``SELF_CHECK_MIN_FREE_SHARE`` of the building the
#:   drawing's linework outlines (walls take 5 to 33 % of a floor, stairs,
#:   shafts, balconies and recesses closed across their mouths the rest):
#:   right builds 0.46 to 0.88; rooms left out, a room outline on layer 0
#:   beside one partition, a sheet's other views built as walls 0.03 to
#:   0.31;
#: - walls take ``SELF_CHECK_WALL_SHARE`` of the floor (walls plus free
#:   space): a pavilion's freestanding walls 4 %, a stone house 33 %; a
#:   whole floor read as windows with a stray line as walls 0.04 %,
#:   elevations' hatches built as walls 80 %;
#: - at least ``SELF_CHECK_MIN_DOORS_USED`` of the door drawings are
#:   doors (a double door is two drawings, one door), judged from
#:   ``DOOR_UNITS_MIN_DOORS`` drawings;
#: - where the plan's doors were found, no part of the free space of
#:   ``ROOM_PART_MIN_AREA`` or more (smaller ones are slivers) is cut off
#:   from the rest with no door at it, where the drawing says where its
#:   rooms are: a door joins the rooms it opens (right builds with doors:
#:   one part; rooms whose doors were missed 8 to 120 m2).
SELF_CHECK_MIN_FREE_SHARE = 0.4
SELF_CHECK_WALL_SHARE = (0.01, 0.5)
SELF_CHECK_MIN_DOORS_USED = 0.5
#: The drawn building is judged on a grid of cells this wide, metres (a
#: door's width is several cells; a 100 m floor 160 000 cells; a sheet
#: larger than ``MAX_FLOOR_AREA_M2`` gets larger cells, 4 MB at most).
SELF_CHECK_CELL_M = 0.25

#: Block nesting deeper than this is a reference cycle in a broken file.
DXF_MAX_BLOCK_DEPTH = 32

#: Arcs and ellipses become at least this many cubic Bezier pieces per full
#: turn (at most 45 degrees each): a 45-degree cubic strays from its circle by
#: 4e-6 of the radius (a 90-degree one by 3e-4, 3 mm on a 10 m rotunda).
CURVE_BEZIER_PER_TURN = 8


# ---- ZInD annotations (mapkit.importers.zind) -------------------------------

#: ZInD draws each room's inner outline only; a wall this thick is put
#: around every room (the sample tour's rooms stand 6 to 47 cm apart).
ZIND_WALL_THICKNESS = 0.15

#: Gaps between neighbouring rooms' walls up to twice this are filled with
#: wall (a thick wall between two rooms is solid, not two skins and a void).
ZIND_WALL_GAP_CLOSE = 0.1

#: How far across the wall a door, window or opening is cut, from the face
#: of the room that annotates it: through both rooms' walls and the gap
#: between them.
ZIND_OPENING_REACH = 2 * (ZIND_WALL_THICKNESS + ZIND_WALL_GAP_CLOSE)

#: An annotated door, window or opening may lie this far inside its room's
#: outline and still cut the wall behind it.
ZIND_OPENING_SLACK = 0.05

#: A gap annotated from the room behind too (the same door seen from both
#: sides) overlaps this one by at least this fraction of the smaller, once
#: both are cut through the wall; the two rooms' annotations of one door
#: differ by centimetres.
ZIND_SAME_GAP_OVERLAP = 0.25

#: An opening whose annotated bottom is within this of the floor starts at
#: the floor (annotators click the floor line to a few centimetres).
ZIND_FLOOR_SNAP = 0.1

# ---- visibility and regions (mapkit.visibility, mapkit.vir) -----------------

#: Visibility polygons cast rays this many degrees either side of each wall
#: vertex (to see past it and onto it). At 10 m that is 2 nm.
VIS_RAY_OFFSET_DEG = 1e-8

#: Circles (distance limits, eps disks) become polygons of this many sides,
#: circumscribed or inscribed so that every approximation is a superset.
CIRCLE_SIDES = 64

#: Added to the region distance ``eps``: covers float noise in the distance a
#: caller measures between a point and a region.
VIR_EPS_SLACK = 1e-3

#: Smallest quadtree cell of the region partition, metres. Cells this small
#: that still straddle a visibility boundary keep every candidate segment.
VIR_MIN_CELL = 0.1

#: Neighbouring regions are merged (lists united) while the area-weighted mean
#: list length grows by at most this fraction: fewer regions, smaller maps.
VIR_MERGE_GROWTH = 0.15

#: Round joins of the region distance (eps) buffer: this many segments per
#: quarter circle; the radius is scaled so that the chords circumscribe the
#: true circle.
VIR_QUAD_SEGS = 4

#: A visibility polygon keeps the rays of a wall vertex unless both stop at
#: least this much short of it, metres (the vertex is hidden). Near a corner
#: grazed at a shallow angle a ray may stop a hair short of a visible one;
#: dropping it moves the outline by less than this, far below
#: ``OVERLAY_GRID``.
VIS_HIDDEN_SLACK = 1e-7

#: Visibility polygon vertices this close to the line through their
#: neighbours are dropped, metres: on that line, up to float noise.
VIS_COLLINEAR = ZERO.distance

#: Region lookup grid cell size, metres (:mod:`mapkit.assemble`): a few
#: regions per cell keeps queries cheap.
LOOKUP_GRID_CELL = 0.5

# ---- meshes (mapkit.importers.mesh) ------------------------------------------

#: Mesh heights within this of a level (the floor, the top of the walls)
#: count as on it: modellers leave objects a few millimetres off the floor.
MESH_LEVEL = 0.02

#: A glTF file (+Y up by its specification) is read z-up when this many times
#: more of its face area faces along z than along y: floors, ceilings and
#: furniture tops face up, and some exporters store z-up anyway.
MESH_UP_MARGIN = 2.0

#: An upward horizontal surface is (part of) the floor only if the faces at
#: its height cover at least this fraction of the model's bounding box seen
#: from above; table tops and wall tops are smaller.
MESH_FLOOR_FRACTION = 0.1

#: ... and only in the lowest half of the model's height (the ceiling: the
#: highest half): the tops of thick walls around a small room are large too.
MESH_FLOOR_RISE = 0.5

#: Walls modelled as single surfaces (no thickness) are given this
#: thickness, metres, so that they occlude and bound the free space.
MESH_THIN_WALL = 0.05

#: Single-surface walls meet at their ends (corners, T junctions): a
#: section line of them crosses under one other on average. Lines that
#: cross more than this many others each are faces across the building (a
#: damaged mesh: 8.8 for a hospital.stl with face lines duplicated, whose
#: thickening took minutes); such a section is refused. Sections of fewer
#: than ``MESH_SHEET_MIN_LINES`` lines are judged as that many (they are
#: fast whatever their tangle).
MESH_SHEET_CROSSINGS = 4.0
MESH_SHEET_MIN_LINES = 100

#: A connected surface whose border edges make more than this fraction of
#: its edge length is an open sheet (thickened as above); below it, a solid
#: with a few holes (a lost sliver, a scan gap).
MESH_OPEN_FRACTION = 0.05

#: Heights above the floor, metres, of the extra sections that find low
#: obstacles (parapets under windows, desks, table legs): the robot cannot
#: stand there although the camera sees over them.
MESH_OBSTACLE_HEIGHTS = (0.05, 0.3)

#: Walls-only meshes: at most this many section heights are searched for
#: rooms the walls enclose (doorways leave rooms open at low heights; the
#: wall above a door closes them).
MESH_MAX_SECTIONS = 12

#: Mesh edges shared by more than this many faces are feature edges without
#: further analysis (pathological non-manifold fans).
MESH_MAX_EDGE_FACES = 8

#: A face rises from an edge (a wall standing on the floor) when its normal
#: is within this many degrees of horizontal. Loose: walls lean a little in
#: scans, and a floor junction should stay a floor junction.
MESH_STEEP_DEG = 45.0

#: Sample spacing, metres, along segments when looking for overlapping
#: collinear pairs: pairs overlapping by more than this are always found.
MESH_OVERLAP_STEP = 0.05

#: Needle repair passes; each pass fixes every needle whose neighbour is not
#: claimed by another needle in the same pass.
MESH_NEEDLE_PASSES = 8

#: Hidden edges: sections probe this far above and below a horizontal edge,
#: metres: off the millimetre grid the vertices were welded to, so the plane
#: misses them.
MESH_HIDDEN_PROBE = 1.5 * MERGE

#: A horizontal edge is on a probed outline if within this distance of it,
#: metres. A face sloping away from the edge at angle a moves the outline
#: by ``MESH_HIDDEN_PROBE / tan(a)``: faces steeper than about 20 degrees
#: stay within reach. Buried pieces are cut this close to the surface they
#: enter.
MESH_HIDDEN_REACH = 4 * MERGE

#: The hidden-edge quadrant test looks this far to either side of an edge, metres.
MESH_HIDDEN_SIDE = 3 * MESH_HIDDEN_REACH

# ---- IFC models (mapkit.importers.ifc) ----------------------------------------

#: Projected triangles of an IFC element are unioned on a grid this fine,
#: metres: the faces of one solid share vertices up to float noise, and an
#: exact union of thousands of triangles leaves hairline seams.
IFC_GRID = 1e-4

#: Heights within this of each other are one level, metres: a door whose
#: opening starts this close to the storey's floor has no sill, walls whose
#: tops differ by less are one height, a stair's tread this close to a
#: storey's floor is on it.
IFC_LEVEL = 0.02

#: A slab is a storey's floor when its top is within this of the storey's
#: elevation, metres (floor finishes and screeds sit on or just under it).
IFC_SLAB_REACH = 0.5

#: Two openings whose footprints overlap by this fraction of the smaller
#: one are stacked in one gap (windows over windows, a fanlight over a
#: door): the scene takes them as one opening.
IFC_STACKED_OVERLAP = 0.5

#: At most this many distinct heights are probed for hidden edges; edges at
#: other heights are kept unchecked (a warning says so).
MESH_HIDDEN_MAX_LEVELS = 64

#: Overlay operations on visibility regions snap to this grid, metres: the
#: fixed precision makes GEOS far faster on the many nearly collinear edges
#: of overlapping visibility polygons; the shift (< 1e-5 m) is absorbed by
#: ``VIR_EPS_SLACK``.
OVERLAY_GRID = 1e-5

#: The region builder shrinks occluders by this for its sight tests, more
#: than ``OCCLUSION_SHRINK``: a line grazing a wall face near a segment on
#: that face is decided by the tolerance itself (1 mm there can swing a
#: shadow by decimetres farther out), so the lists must also hold what
#: slightly smaller walls would let through; brute-force checks use twice
#: ``OCCLUSION_SHRINK``, and this leaves a margin over them.
VIS_BUILD_SHRINK = 3e-3

#: Deepest quadtree level of the region partition: 2**11 = 2048 smallest
#: cells across the plan. Larger plans get smallest cells wider than
#: ``VIR_MIN_CELL`` (lists a little longer) instead of unbounded memory.
VIR_MAX_DEPTH = 11

#: A segment is treated as exactly vertical by the visibility code (one
#: sight test at its xy point) only if its end points' xy differ by less
#: than this; steeper-than-``AXIS_DEG`` but slanted segments are sampled
#: like any other, so a millimetre of slant never hides a grazing view.
VIS_VERTICAL_XY = 1e-6

#: The region builder overlays a pair of samples (or a vertical segment's
#: point) only if their visibility polygons come within this of the free
#: space, metres: farther, the piece cannot meet it (the overlay grid moves
#: a piece by under 1e-5 m) and would be cut away with the rest of the
#: region outside the free space. Outer faces of exterior walls and faces
#: in shafts no door leads to: a third of the pairs of the corpus's college
#: floor (daoshi_f1).
VIS_WITHIN_MARGIN = 1e-3

# ---- 3D model of a plan (mapkit.extrude) -------------------------------------

#: Footprints are closed and opened by this much, metres, with mitre joins,
#: so that an opening drawn a hair off its wall leaves no sliver or notch
#: (the edge stage cleans its footprints the same way, ``FOOTPRINT_CLOSE_GAP``).
EXTRUDE_CLEAN = 5 * MERGE

#: Footprints are snapped to this grid, metres, before boolean operations,
#: so that the differences between bands have no float-noise slivers.
EXTRUDE_GRID = MERGE / 10

# ---- limits of work (each raised by an option of mapkit build) ----------------
# Not geometry: inputs past them would run for minutes or take gigabytes, so
# they end in an error naming the limit and its option before the work.

#: Most drawing entities an import flattens (after expanding blocks and
#: MINSERT arrays; text and dimensions do not count): the example has 240,
#: the Barcelona pavilion 1200; 200 000 LINEs used to run past 120 s and a
#: MINSERT of 10^6 copies for minutes. ``--max-entities`` raises it.
DXF_MAX_ENTITIES = 100_000

#: Largest floor a map is built for, square metres (the bounding box of the
#: free space): the region builder's work and memory grow with it (an empty
#: room 200 m across: 11 s, 0.3 GB; 1000 m: 80 s, 2 GB; 1999 m: out of
#: memory). A large building's floor is 10^4 to 10^5 m2. ``--max-floor-area``
#: raises it.
MAX_FLOOR_AREA_M2 = 250_000.0

#: Most seconds the region stage (``mapkit.vir.build_regions``) may take per
#: 100 m2 of free space, predicted before it runs (``mapkit.region_cost``);
#: floors smaller than ``REGION_BOUND_MIN_AREA_M2`` are allowed as much as
#: that large (15 s). Real buildings need 0.5 to 7.2 (predicted; measured
#: 0.5 to 8.6), the detailed ones the most (pms_b001_f3's facility plan 7.2,
#: ciq_building's house with door swings and furniture on its wall layer
#: 7.0); a mesh whose faces cross the building leaves a tangle of wall edges
#: in its section (tests/data/fuzz/mesh_tangled_walls_slow_regions: 13.9
#: predicted, 15.5 measured, 27 s against 4 s for the undamaged mesh);
#: segments kilometres long over a small floor, thousands. The bound is a
#: rate, not a total: the largest corpus floor (daoshi_f1, 3400 m2) takes
#: 60 s, twice the tangle, and is as plain a building as any.
#: ``--max-region-seconds-per-100m2`` raises it.
MAX_REGION_SECONDS_PER_100M2 = 10.0
REGION_BOUND_MIN_AREA_M2 = 150.0

#: The region stage's peak memory, predicted before it runs to choose
#: between one piece and tiles (``mapkit.tiles``): a fixed part, MB, and MB
#: per m2 of free space it works on. Fitted on generated offices of 5 m
#: rooms, one piece, ``mapkit build`` peak resident memory on 2 cores
#: (``tools/bench_tiles.py``, docs/benchmarks/tiles.md): 10 x 10 rooms
#: (2,023 m2 of free space) 485 MB, 20 x 20 (8,130 m2) 1,669 MB; the line
#: through them, rounded. A tile works on the free space within its
#: segments' reach of its own square (checked on the tiles of 40 x 40 rooms).
REGION_PEAK_BASE_MB = 90.0
REGION_PEAK_MB_PER_M2 = 0.19

#: The peak memory a build aims to stay under when ``--memory-budget`` is
#: not given, MB: a floor predicted above it is built in tiles sized to it.
#: A fixed figure, not read from the machine, so that a plan and its options
#: give the same map on every machine; 2 GB runs on a laptop, and on a
#: 2-worker local cluster of a 8 GB one.
DEFAULT_MEMORY_BUDGET_MB = 2000.0

#: Tiles narrower than this many times the segments' reach (``max_range``
#: plus the region growth) are not made: each tile sweeps every segment
#: within reach of it, so a tile that narrow does (1 + 2 / this)^2 = 9 times
#: its own share of the work. A budget that needs narrower tiles is refused.
TILE_MIN_SIDE_PER_REACH = 1.0

#: Added to a tile's reach, metres: a segment farther than the reach from
#: the tile cannot be listed in it, up to the overlay grid (``OVERLAY_GRID``)
#: and float noise; 1 cm is far more than both.
TILE_REACH_SLACK = 0.01

#: The region stage's predicted seconds (``mapkit.region_cost``): per sight
#: test (a sample point against an occluder edge within --max-range of it),
#: per vertex of a sample point's visibility polygon (the overlays that
#: follow pay per vertex) and per sample point. Processor seconds (both
#: threads of -j 2) on the benchmarks' machine (2-core AMD EPYC) under load
#: 4 to 7, where the stage's wall time was 1.2 to 2.3 times them. Fitted
#: (non-negative least squares of the relative error) on the first 10
#: builds below, measured once; the table is a second measurement of all
#: 18, the last 8 held out of the fit (defaults unless named):
#:
#:   ======================  =========  ========  ====  ===========
#:   build                   predicted  measured  free  predicted s
#:                                 s         s    m2    per 100 m2
#:   ======================  =========  ========  ====  ===========
#:   daoshi_f1                    59.8      58.6  3382     1.8
#:   jps_einkauf                  35.5      37.4   643     5.5
#:   office 7 x 7 rooms           22.1      20.1   987     2.2
#:   office 4 x 4 rooms            5.8       5.3   319     1.8
#:   hospital.stl                  4.7       4.1   235     2.0
#:   qs_jiao --units cm            3.0       3.2   589     0.5
#:   smh_dxf28                     2.5       2.4    81     1.7
#:   maps/flat.dxf                 2.3       2.0    62     1.5
#:   pms_giraffe360                1.6       1.6    43     1.1
#:   apartment_a                   1.1       1.1    40     0.7
#:   held out:
#:   daoshi_f3                    67.6      65.0  2837     2.4
#:   pms_b001_f3                  28.2      33.9   392     7.2
#:   the tangled hospital (1)     24.0      26.7   172    13.9
#:   dmx_gallery --scale 14       12.5      14.8  1120     1.1
#:   ciq_building (2)             10.5      10.7    62     7.0
#:   anand_plan                    4.8       4.2   169     2.8
#:   hal9k                         2.6       2.5   124     1.7
#:   raytracer                     1.1       1.4    66     0.7
#:   ======================  =========  ========  ====  ===========
#:
#: (1) tests/data/fuzz/mesh_tangled_walls_slow_regions, refused. (2) with
#: ``--walls DETAILS --units mm``. Predicted / measured 0.82 to 1.18 (held
#: out 0.82 to 1.13). Without the vertex term (sight tests and points
#: only) the first measurement gave 0.54 to 1.49: the tangle and
#: ciq_building overestimated by half, the offices underestimated. The
#: per-test cost is the old sight-work estimate's 2 us; its fixed 150
#: tests a point were too few where polygons are large, too many where
#: they are small. The check itself takes 0.05 to 1.3 s (ciq_building).
#: Refit (``mapkit.region_cost``'s docstring says how) when the region
#: stage's speed changes. Measured again after the region builder learnt to
#: skip what cannot reach the free space (``VIS_WITHIN_MARGIN``; maps
#: unchanged), on a quiet machine (load 1.4 to 1.9): the stage's processor
#: seconds fell by up to 30 % (daoshi_f3 65 -> 48 s, ciq_building 10.7 ->
#: 7.7, the tangle 26.7 -> 22.5); these constants then predict 0.90 to 1.69
#: times the measured (held out: the tangle 13.9 s per 100 m2 against 13.1
#: measured, still refused; the corpus at most 7.2 against 6.4). A refit on
#: that run alone gave 1.25 us a test, 31 us a vertex, 114 us a point and
#: predicted the held-out tangle at 8.8 per 100 m2 (0.67 of measured), under
#: the limit: the vertex term's weight moves with the machine's load, so
#: the first fit, made under load, is kept: it errs on the slow side.
REGION_SECONDS_PER_SIGHT_TEST = 2.2e-6
REGION_SECONDS_PER_VISIBLE_VERTEX = 38e-6
REGION_SECONDS_PER_POINT = 140e-6

# ---- work sizes ---------------------------------------------------------------
# Memory bounds of vectorised steps, not geometry: results do not depend on them.

#: Rays x edges per numpy block in the visibility sweep: bounds its
#: temporaries (~4 MB, so that they stay in the processor's cache).
VIS_BLOCK = 50_000

#: Points x occluder edges per chunk of the batched sweep's range test
#: (:mod:`mapkit.visibility_batch`; booleans, about 4 MB).
VIS_NEAR_BLOCK = 4_000_000

#: Near occluder edges per chunk of the batched sweep: it casts four rays per
#: edge and keeps about twenty numbers per ray (about 30 MB).
VIS_SWEEP_EDGES = 50_000

#: Region lists are compared and packed this many listed segments (or
#: segment slots) at a time (bounds the temporaries to about 10 MB).
VIR_LIST_CHUNK = 250_000

#: Quadtree (cell, region) pairs tested per call of a shapely predicate.
VIR_PAIR_CHUNK = 500_000

#: The visibility sweep tries a point's nearest this many occluder edges
#: first, then batches twice as large (most sight rays end on the nearest
#: walls, a room's own few; see ``mapkit.visibility._nearest_hits``).
VIS_FIRST_EDGES = 8

#: Sample points whose edges in range are counted to predict the region
#: stage's time (the mean over them stands for all), and how many of them
#: are swept for their visibility polygons' vertices (a sweep costs up to
#: 10 ms a point in a detailed drawing: about 1 s at most for the check).
REGION_COST_PROBES = 512
REGION_COST_POLYGON_PROBES = 96

#: Points per chunk in the mesh sections' winding-number tests (memory:
#: chunk x segments booleans).
MESH_SECTION_CHUNK = 2_000_000

#: Ring edges x points per chunk when the extruder splits rings at foreign
#: vertices.
EXTRUDE_CHUNK = 4_000_000

"""Every geometric tolerance of the map builder, in one documented place.

Lengths in metres, angles in degrees. Import the names, never repeat the
numbers: a tolerance that lives in two places drifts.
"""

#: Points closer than this are the same point (vertex merging, snapping of
#: CAD endpoints that should meet). Architects' drawings are exact to well
#: under a millimetre, but exported files carry float noise.
MERGE = 1e-3

#: Dangling wall endpoints closer than this are joined (gaps in real drawings).
SNAP_GAP = 0.02

#: Occluders are shrunk by this before sight-line tests, so that a sight line
#: grazing a wall face, or ending on the face it belongs to, is not blocked
#: by float noise. Brute-force checks shrink by twice this.
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

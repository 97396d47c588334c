"""Read a mesh file into one welded triangle mesh: metres, z up, floor at z = 0.

Everything after this module may assume: one ``trimesh.Trimesh`` (node
transforms of a scene already applied), coordinates in metres, z up,
coincident vertices merged (split vertices would make every edge look like
a border), no degenerate or repeated faces, and the floor at z = 0.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np

from mapkit.errors import MapkitError
from mapkit.units import UNIT_METRES, canonical_units
from mapkit.importers.mesh.edges import edge_faces, face_normals
from mapkit.options import BuildOptions
from mapkit.tolerances import (
    AXIS_DEG,
    MERGE,
    MESH_FLOOR_FRACTION,
    MESH_FLOOR_RISE,
    MESH_LEVEL,
    MESH_NEEDLE_PASSES,
    MESH_UP_MARGIN,
    PLAUSIBLE_EXTENT,
)

log = logging.getLogger("mapkit")

#: y-up to z-up: +90 degrees about x, so +y becomes +z and +z becomes -y
#: (a proper rotation: the model is not mirrored).
Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def load_mesh(path: Path, options: BuildOptions):
    """The mesh of ``path`` ready for sectioning and edge extraction.

    Returns ``(mesh, info)``: a ``trimesh.Trimesh`` (metres, z up, welded,
    floor at z = 0) and a dict of what was decided (``units``, ``scale``,
    ``up``, ``floor``, ``floor_offset_m``, ``ceiling``, ``wall_height_m``:
    the ceiling height, ``warnings``).
    """
    import trimesh

    vertices, faces = read_triangles(path)
    up = options.up if options.up != "auto" else guess_up(vertices, faces, convention_up(path))
    if up == "y":
        vertices = vertices @ Y_UP_TO_Z_UP.T
    unit = canonical_units(options.units) if options.units else "m"
    factor = UNIT_METRES[unit] * options.scale
    vertices = vertices * factor

    extent = float(np.ptp(vertices, axis=0).max())
    lo, hi = PLAUSIBLE_EXTENT
    if not lo <= extent <= hi:
        raise MapkitError(
            f"{path}: the model is {extent:.3g} m across with units '{unit}' and scale {options.scale:g}, "
            f"not a building ({lo:g} to {hi:g} m); set --units (e.g. mm, cm) or --scale"
        )
    vertices, faces = weld(vertices, faces)
    if len(faces) == 0:
        raise MapkitError(f"{path}: every triangle is degenerate at this scale; check --units and --scale")

    floor_z, has_floor = find_floor(vertices, faces)
    vertices[:, 2] -= floor_z
    top, has_ceiling = find_ceiling(vertices, faces)
    warnings = []
    size_xy = float(np.ptp(vertices[:, :2], axis=0).max())
    height = float(vertices[:, 2].max())
    if height > size_xy:
        warnings.append(
            f"the model is {height:.3g} m tall but only {size_xy:.3g} m wide: is the up axis right? "
            f"(--up {'z' if up == 'y' else 'y'})"
        )
    for w in warnings:
        log.warning(w)
    info = {
        "units": unit,
        "scale": factor,
        "up": up,
        "floor": "floor faces" if has_floor else "lowest point (no floor faces)",
        "floor_faces": bool(has_floor),
        "floor_offset_m": float(floor_z),
        "ceiling": "ceiling faces" if has_ceiling else "highest point (no ceiling faces)",
        "wall_height_m": top,
        "vertices": int(len(vertices)),
        "faces": int(len(faces)),
        "warnings": warnings,
    }
    return trimesh.Trimesh(vertices=vertices, faces=faces, process=False), info


def read_triangles(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """All triangles of a mesh file as ``vertices`` (V, 3) float64 and ``faces`` (F, 3) int64.

    Scenes (glTF, multi-object OBJ) are flattened with every node's world
    transform applied; points, lines and other non-triangle geometry are
    skipped. Coordinates stay in the file's units and axes.
    """
    import trimesh

    if path.stat().st_size == 0:  # trimesh's own message for this is an index error
        raise MapkitError(f"{path}: the file is empty; export the model again")
    _check_binary_stl_length(path)
    _check_text_mesh_counts(path)
    try:
        with np.errstate(all="ignore"):  # NaN and overflowing values are refused below, without numpy's warnings
            loaded = trimesh.load(str(path), process=False)
    except FileNotFoundError as exc:  # the file exists (checked by the CLI): a buffer or texture it names does not
        raise MapkitError(f"{path}: a file it refers to is missing ({exc.filename or exc}); put it beside "
                          f"{path.name} or export the model as one .glb") from None
    except Exception as exc:  # trimesh raises anything from struct.error to KeyError on bad files
        reason = str(exc).splitlines()[0][:120] if str(exc) else type(exc).__name__
        raise MapkitError(f"{path}: not a readable {path.suffix} mesh ({reason}); check the file or export it again") from None
    parts = []
    if isinstance(loaded, trimesh.Scene):
        for node in loaded.graph.nodes_geometry:
            transform, name = loaded.graph[node]
            geom = loaded.geometry.get(name)
            if isinstance(geom, trimesh.Trimesh) and len(geom.faces):
                v = np.asarray(geom.vertices, dtype=np.float64)
                parts.append((v @ transform[:3, :3].T + transform[:3, 3], np.asarray(geom.faces, dtype=np.int64)))
    elif isinstance(loaded, trimesh.Trimesh) and len(loaded.faces):
        parts.append((np.asarray(loaded.vertices, dtype=np.float64), np.asarray(loaded.faces, dtype=np.int64)))
    if not parts:
        raise MapkitError(f"{path}: the file holds no triangles; export the model as a surface mesh")
    for v, _ in parts:  # a damaged OBJ line 'v 4' leaves trimesh's vertices one number wide
        if v.ndim != 2 or v.shape[1] != 3:
            raise MapkitError(f"{path}: its vertices are not (x, y, z) triples; the file is damaged, export it again")
    offsets = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
    vertices = np.concatenate([v for v, _ in parts])
    for (v, f) in parts:  # damaged binary files name vertices they do not hold
        if len(f) and (f.min() < 0 or f.max() >= len(v)):
            bad = int(f.max()) if f.max() >= len(v) else int(f.min())
            raise MapkitError(f"{path}: a face names vertex {bad} of {len(v)}; the file is damaged, export it again")
    faces = np.concatenate([f + o for (_, f), o in zip(parts, offsets)])
    if not np.isfinite(vertices).all():
        raise MapkitError(f"{path}: the mesh has non-finite coordinates (NaN or infinity); repair or re-export it")
    return vertices, faces


def _check_binary_stl_length(path: Path) -> None:
    """MapkitError if ``path`` is a binary STL shorter than its header's
    triangle count says (a cut download or copy): trimesh would read what
    is there, or nothing, without saying so. An 80-byte header, a uint32
    count, 50 bytes per triangle; ASCII STL starts with 'solid' and a
    binary one whose size fits its count is left alone."""
    if path.suffix.lower() != ".stl":
        return
    size = path.stat().st_size
    with open(path, "rb") as fh:
        head = fh.read(84)
    if len(head) < 84 or head[:5].lower() == b"solid":
        return
    count = int(np.frombuffer(head[80:84], dtype="<u4")[0])
    if size < 84 + 50 * count:
        raise MapkitError(f"{path}: the file is truncated (its header lists {count} triangles, it holds "
                          f"{max(size - 84, 0) // 50}); copy or export it again")


def _check_text_mesh_counts(path: Path) -> None:
    """MapkitError if a text mesh holds less than it says (a cut copy): an
    ASCII PLY or an OFF file with fewer data lines than its header's element
    counts, an OBJ file whose faces name vertices it does not hold. trimesh
    would build the part that is there without a word."""
    suffix = path.suffix.lower()
    if suffix not in (".ply", ".off", ".obj"):
        return
    with open(path, "rb") as fh:
        head = fh.read(5)
    if suffix == ".ply" and head[:3] != b"ply":
        return
    text = path.read_text(errors="replace")
    lines = text.splitlines()
    if suffix == ".ply":
        if "format ascii" not in text[:2000]:
            return
        try:
            end = next(i for i, ln in enumerate(lines) if ln.strip() == "end_header")
        except StopIteration:
            raise MapkitError(f"{path}: the PLY header never ends (truncated?); copy or export it again") from None
        declared = sum(int(ln.split()[2]) for ln in lines[:end] if ln.startswith("element ") and len(ln.split()) == 3
                       and ln.split()[2].isdigit())
        held = sum(1 for ln in lines[end + 1:] if ln.strip())
    elif suffix == ".off":
        body = [ln.split("#")[0].strip() for ln in lines]
        body = [ln for ln in body if ln]
        if not body or not body[0].upper().endswith("OFF") and not body[0].upper().startswith("OFF"):
            return
        first = body[0].split()
        counts = first[1:] if len(first) > 1 else (body[1].split() if len(body) > 1 else [])
        if len(counts) < 2 or not all(c.isdigit() for c in counts[:2]):
            return
        declared = int(counts[0]) + int(counts[1])
        held = len(body) - (1 if len(first) > 1 else 2)
    else:  # OBJ
        n_vertices = sum(1 for ln in lines if ln.startswith("v "))
        indices = [int(tok.split("/")[0]) for ln in lines if ln.startswith("f ") for tok in ln.split()[1:]
                   if tok.split("/")[0].lstrip("-").isdigit()]
        if not indices or max(indices) <= n_vertices:
            return
        declared, held = max(indices), n_vertices
    if held < declared:
        raise MapkitError(f"{path}: the file is truncated (it declares {declared} vertices and faces, it holds "
                          f"{held}); copy or export it again")


def weld(vertices: np.ndarray, faces: np.ndarray, tol: float = MERGE) -> tuple[np.ndarray, np.ndarray]:
    """Merge vertices closer than ``tol``.

    Vertices are clustered (k-d tree pairs within ``tol``, connected
    components), not rounded to a grid: two copies of a corner straddling a
    grid line would stay apart and leave a sliver that opens the mesh.
    Drops faces that collapse (two corners merged) and exact repeats (same
    corners in the same order), and removes needle triangles (corners in a
    line: T-junction fillers) by splitting their neighbour instead, so that
    a closed mesh stays closed. Returns the used vertices (V', 3) and the
    faces (F', 3) re-indexed.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    # Exact copies first (cheap), then clusters of the distinct points.
    distinct, inverse = _unique_rows(vertices)
    pairs = cKDTree(distinct).query_pairs(tol, output_type="ndarray")
    n = len(distinct)
    graph = coo_matrix((np.ones(len(pairs), dtype=np.int8), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, cluster = connected_components(graph, directed=False)
    first = np.full(cluster.max() + 1, -1)
    first[cluster[::-1]] = np.arange(n)[::-1]  # the lowest index stands for its cluster
    merged = distinct[first]
    faces = cluster[inverse.reshape(-1)][faces]
    ok = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 2] != faces[:, 0])
    faces = faces[ok]
    # Same triangle, same orientation: rotate each row to start at its smallest id.
    shift = np.argmin(faces, axis=1)
    rolled = np.take_along_axis(faces, (shift[:, None] + np.arange(3)) % 3, axis=1)
    _, keep = np.unique(rolled, axis=0, return_index=True)
    faces = faces[np.sort(keep)]
    faces = split_needles(merged, faces, tol)
    used, faces = np.unique(faces, return_inverse=True)
    return merged[used], faces.reshape(-1, 3)


def _unique_rows(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distinct rows of ``points`` (P, 3) and the (P,) index of each row in
    them; a lexsort, several times faster than ``np.unique(axis=0)``."""
    order = np.lexsort(points.T[::-1])
    ordered = points[order]
    new = np.r_[True, (ordered[1:] != ordered[:-1]).any(axis=1)]
    group = np.cumsum(new) - 1
    inverse = np.empty(len(points), dtype=np.int64)
    inverse[order] = group
    return ordered[new], inverse


def split_needles(vertices: np.ndarray, faces: np.ndarray, tol: float = MERGE) -> np.ndarray:
    """Replace needle triangles (height under ``tol``) by splitting the face
    across their long edge at the needle's middle corner.

    A needle (a, c, b) with c on the edge a-b fills a T-junction: the face
    (a, b, x) on the other side becomes (a, c, x) and (c, b, x), with its
    orientation kept, and the needle goes. Needles with no single plain
    neighbour across the long edge (two needles making a sliver) are kept.
    """
    for _ in range(MESH_NEEDLE_PASSES):
        tri = vertices[faces]
        side = np.roll(tri, -1, axis=1) - tri  # side k runs corner k -> k+1
        length = np.linalg.norm(side, axis=2)
        _, area = face_normals(vertices, faces)
        longest = np.argmax(length, axis=1)
        needle = area < 0.5 * tol * length[np.arange(len(faces)), longest]
        if not needle.any():
            return faces
        ids = np.nonzero(needle)[0]
        k = longest[ids]
        a = faces[ids, k]
        b = faces[ids, (k + 1) % 3]
        c = faces[ids, (k + 2) % 3]
        topo = edge_faces(faces)
        n = int(faces.max()) + 1
        edge_key = topo.edges[:, 0] * n + topo.edges[:, 1]
        e = np.searchsorted(edge_key, np.minimum(a, b) * n + np.maximum(a, b))
        # The neighbour: the other face on the long edge, if exactly one.
        single = topo.counts[e] == 2
        s0 = topo.starts[e]
        other = np.where(topo.face[s0] == ids, topo.face[np.minimum(s0 + 1, len(topo.face) - 1)], topo.face[s0])
        usable = single & ~needle[other]
        if not usable.any():
            return faces  # the rest have no plain neighbour: keep them (dropping would open the mesh)
        _, first = np.unique(np.where(usable, other, -1 - np.arange(len(ids))), return_index=True)
        claim = np.zeros(len(ids), dtype=bool)
        claim[first] = True
        fix = usable & claim
        nb = other[fix]
        row = faces[nb]
        # Rotate the neighbour to (p, q, x) with p-q its copy of the long edge.
        x = np.where((row != a[fix, None]) & (row != b[fix, None]), row, -1).max(axis=1)
        pos = np.argmax(row == x[:, None], axis=1)
        p = row[np.arange(len(nb)), (pos + 1) % 3]
        q = row[np.arange(len(nb)), (pos + 2) % 3]
        cc = c[fix]
        new = np.concatenate([np.stack([p, cc, x], axis=1), np.stack([cc, q, x], axis=1)])
        remove = np.zeros(len(faces), dtype=bool)
        remove[nb] = True
        remove[ids[fix]] = True
        faces = np.concatenate([faces[~remove], new])
    return faces


def find_floor(vertices: np.ndarray, faces: np.ndarray) -> tuple[float, bool]:
    """Height of the floor: the lowest large upward-facing horizontal surface.

    Only levels in the lowest ``MESH_FLOOR_RISE`` of the model's height
    count. Returns ``(z, True)``, or ``(lowest z, False)`` for a mesh
    without floor faces (walls only). See :func:`large_levels`.
    """
    levels = large_levels(vertices, faces, up=True)
    lo, hi = float(vertices[:, 2].min()), float(vertices[:, 2].max())
    # The tops of thick walls in a small room are large too: a floor is in
    # the lower part of the model.
    levels = levels[levels <= lo + MESH_FLOOR_RISE * (hi - lo)]
    if len(levels):
        return float(levels[0]), True
    return lo, False


def find_ceiling(vertices: np.ndarray, faces: np.ndarray, floor_z: float = 0.0) -> tuple[float, bool]:
    """Height of the ceiling: the lowest large downward-facing horizontal
    surface above the floor, in the top ``MESH_FLOOR_RISE`` of the model's
    height. Returns ``(z, True)``, or ``(highest z, False)``
    for a mesh without a ceiling."""
    levels = large_levels(vertices, faces, up=False)
    hi = float(vertices[:, 2].max())
    # Large undersides low in the model are lintels of wide openings or
    # table tops, not a ceiling.
    levels = levels[(levels > floor_z + MESH_LEVEL) & (levels >= hi - MESH_FLOOR_RISE * (hi - floor_z))]
    if len(levels):
        return float(levels[0]), True
    return hi, False


def convention_up(path: Path) -> str:
    """The up axis a mesh format declares: glTF's is +y; OBJ, PLY, STL and
    OFF declare none, and building models in them are mostly z-up."""
    return "y" if Path(path).suffix.lower() in (".glb", ".gltf") else "z"


def guess_up(vertices: np.ndarray, faces: np.ndarray, convention: str) -> str:
    """``"y"`` or ``"z"``: the format's ``convention``, but for a glTF file
    whose faces say it was stored z-up against the specification (as some
    exporters do): floors, ceilings and the tops of furniture face along
    the up axis, so a file holding ``MESH_UP_MARGIN`` times more face area
    facing along z than along y is read z-up. Files of the formats without
    a convention stay z-up (a walls-only model, with no floor, holds more
    area facing along a horizontal axis; ``--up y`` reads one stored y-up)."""
    if convention != "y":
        return convention
    normals, areas = face_normals(vertices, faces)
    along = np.abs(normals) >= math.cos(math.radians(AXIS_DEG))
    area_y, area_z = float(areas[along[:, 1]].sum()), float(areas[along[:, 2]].sum())
    return "z" if area_z > MESH_UP_MARGIN * area_y else "y"


def large_levels(vertices: np.ndarray, faces: np.ndarray, up: bool) -> np.ndarray:
    """Sorted heights (L,) of the large horizontal surfaces facing up (or down).

    Faces whose normal is within ``AXIS_DEG`` of +z (or -z) are grouped into
    levels (heights closer than ``MESH_LEVEL`` chain together); a level is
    large if its faces cover ``MESH_FLOOR_FRACTION`` of the plan's bounding
    box. Each height is the area-weighted mean of its faces.
    """
    normals, areas = face_normals(vertices, faces)
    sign = 1.0 if up else -1.0
    facing = sign * normals[:, 2] >= math.cos(math.radians(AXIS_DEG))
    box = np.ptp(vertices[:, :2], axis=0)
    need = MESH_FLOOR_FRACTION * float(box[0] * box[1])
    if not facing.any() or need <= 0:
        return np.zeros(0)
    z = vertices[faces[facing]][:, :, 2].mean(axis=1)
    order = np.argsort(z)
    z, a = z[order], areas[facing][order]
    level = np.r_[0, np.cumsum(np.diff(z) > MESH_LEVEL)]
    level_area = np.bincount(level, weights=a)
    big = np.nonzero(level_area >= need)[0]
    return np.array([np.average(z[level == k], weights=a[level == k]) for k in big])

"""Feature edges of synthetic meshes whose edges are known from their geometry."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import trimesh

from mapkit.importers.mesh.load import weld
from linemap.lmap import SegmentKind as K
from mapkit.importers.mesh.edges import edge_faces, feature_edges, merge_collinear

CREASE, MIN_LEN = 30.0, 0.2


def box(lo, hi) -> trimesh.Trimesh:
    """Axis-aligned box from corner ``lo`` to corner ``hi`` (metres)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2))


def welded(*meshes) -> trimesh.Trimesh:
    m = trimesh.util.concatenate(meshes)
    v, f = weld(np.asarray(m.vertices), np.asarray(m.faces))
    return trimesh.Trimesh(v, f, process=False)


def kinds_count(kinds) -> dict[str, int]:
    return {K(k).name: int(c) for k, c in zip(*np.unique(kinds, return_counts=True))}


def as_set(segments, digits=3) -> set:
    """Segments as a set of sorted end-point tuples, for order-free comparison."""
    out = set()
    for a, b in np.round(segments, digits) + 0.0:
        out.add(tuple(sorted([tuple(a), tuple(b)])))
    return out


def test_box_on_the_floor_has_its_twelve_edges():
    seg, kinds = feature_edges(box([0, 0, 0], [4, 3, 2.5]), CREASE, MIN_LEN)
    # 4 corners, 4 wall/floor junctions (a wall rises from each), 4 at the top.
    assert kinds_count(kinds) == {"FLOOR": 4, "CEILING": 4, "VERTICAL": 4}
    assert len(seg) == 12
    lengths = np.sort(np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1))
    assert np.allclose(lengths, [2.5] * 4 + [3] * 4 + [4] * 4)


def test_subdivided_faces_merge_back_into_the_same_edges():
    plain = box([0, 0, 0], [4, 3, 2.5])
    fine = plain.subdivide().subdivide()  # 16x the faces: interior edges are coplanar
    assert len(fine.faces) == 16 * len(plain.faces)
    s0, k0 = feature_edges(plain, CREASE, MIN_LEN)
    s1, k1 = feature_edges(fine, CREASE, MIN_LEN)
    assert as_set(s1) == as_set(s0)
    assert sorted(k1) == sorted(k0)


def test_split_vertices_make_every_edge_a_border_until_welded():
    m = box([0, 0, 0], [4, 3, 2.5])
    split = trimesh.Trimesh(m.vertices[m.faces].reshape(-1, 3), np.arange(36).reshape(-1, 3), process=False)
    raw, _ = feature_edges(split, CREASE, MIN_LEN)
    assert len(raw) > 12  # the quad diagonals show up as borders
    v, f = weld(np.asarray(split.vertices), np.asarray(split.faces))
    seg, _ = feature_edges(trimesh.Trimesh(v, f, process=False), CREASE, MIN_LEN)
    assert as_set(seg) == as_set(feature_edges(m, CREASE, MIN_LEN)[0])


def test_touching_wall_boxes_hide_their_shared_face():
    # Two 1 m wall pieces sharing a full end face: one 2 m wall to the eye.
    two = welded(box([0, 0, 0], [1, 0.2, 2.5]), box([1, 0, 0], [2, 0.2, 2.5]))
    assert (edge_faces(two.faces).counts == 4).sum() > 0  # the shared face's edges
    seg, kinds = feature_edges(two, CREASE, MIN_LEN)
    one, one_kinds = feature_edges(box([0, 0, 0], [2, 0.2, 2.5]), CREASE, MIN_LEN)
    # The 0.2 m end edges are not shorter than MIN_LEN (0.2), so they stay.
    assert as_set(seg) == as_set(one)
    assert sorted(kinds) == sorted(one_kinds)


def test_single_surface_wall_gives_its_border():
    quad = trimesh.Trimesh([[0, 0, 0], [3, 0, 0], [3, 0, 2.5], [0, 0, 2.5]], [[0, 1, 2], [0, 2, 3]], process=False)
    seg, kinds = feature_edges(quad, CREASE, MIN_LEN)
    assert kinds_count(kinds) == {"FLOOR": 1, "CEILING": 1, "VERTICAL": 2}


def test_edges_under_the_floor_are_cut_off():
    sunk = box([0, 0, -0.5], [1, 1, 2.0])
    seg, kinds = feature_edges(sunk, CREASE, MIN_LEN, floor_z=0.0)
    assert seg[:, :, 2].min() == pytest.approx(0.0)
    vertical = seg[kinds == K.VERTICAL]
    assert len(vertical) == 4 and np.allclose(vertical[:, :, 2].max(axis=1) - vertical[:, :, 2].min(axis=1), 2.0)
    # The box's own bottom is 0.5 m under the floor: gone; its top stays.
    assert kinds_count(kinds) == {"CEILING": 4, "VERTICAL": 4}


def test_crease_angle_decides_whether_a_faceted_column_has_verticals():
    col = trimesh.creation.cylinder(radius=0.3, height=2.5, sections=20)  # 18 degrees per facet
    col.apply_translation([0, 0, 1.25])
    seg30, k30 = feature_edges(col, 30.0, MIN_LEN)
    seg10, k10 = feature_edges(col, 10.0, MIN_LEN)
    assert (k30 == K.VERTICAL).sum() == 0
    assert (k10 == K.VERTICAL).sum() == 20


def test_short_pieces_are_dropped_and_obliques_classified():
    # A ramp: a wedge 2 m long rising to 1 m, 1.5 m wide. Its two sloping
    # edges (2.24 m) are oblique; with a 1.6 m minimum the 1 m and 1.5 m go.
    pts = np.array([[0, 0, 0], [2, 0, 0], [2, 0, 1.0], [0, 1.5, 0], [2, 1.5, 0], [2, 1.5, 1.0]])
    faces = [[0, 2, 1], [3, 4, 5], [0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [0, 3, 5], [0, 5, 2]]
    ramp = trimesh.Trimesh(pts, faces, process=False)
    seg, kinds = feature_edges(ramp, CREASE, MIN_LEN)
    assert (kinds == K.OBLIQUE).sum() == 2  # the two sloping top edges
    seg_long, k_long = feature_edges(ramp, CREASE, 1.6)
    assert len(seg_long) == 4  # two 2 m floor edges, two 2.24 m slopes
    assert np.linalg.norm(seg_long[:, 1] - seg_long[:, 0], axis=1).min() >= 1.6


def test_merge_collinear_joins_straight_chains_only():
    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(0, 5, 12))
    straight = np.c_[t, 2 * t, np.zeros_like(t)]  # one line in pieces
    arc = np.c_[np.cos(np.linspace(0, 0.2, 30)), np.sin(np.linspace(0, 0.2, 30)), np.ones(30)] * 10
    v = np.concatenate([straight, arc])
    edges = np.r_[np.c_[np.arange(11), np.arange(1, 12)], np.c_[np.arange(12, 41), np.arange(13, 42)]]
    seg, labels = merge_collinear(v, edges)
    assert len(np.unique(labels[:11])) == 1  # the straight chain is one segment
    assert np.allclose(sorted(map(tuple, seg[labels[0]])), sorted([tuple(straight[0]), tuple(straight[-1])]))
    # Consecutive arc pieces turn by 0.4 degrees (< COLLINEAR_DEG) but the
    # chain bows 5 cm off its chord: it stays in pieces.
    assert len(np.unique(labels[11:])) == 29


def test_bad_shapes_and_angles_are_rejected():
    with pytest.raises(ValueError, match="Expected vertices"):
        feature_edges(SimpleNamespace(vertices=np.zeros((3, 2)), faces=[[0, 1, 2]]), CREASE, MIN_LEN)
    with pytest.raises(ValueError, match="crease_deg"):
        feature_edges(box([0, 0, 0], [1, 1, 1]), 0.0, MIN_LEN)

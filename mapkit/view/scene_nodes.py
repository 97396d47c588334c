"""The static 3D layers of a map, each a handful of batched viser calls.

Batching is what keeps a map of a few thousand regions fast: one
line-segments node per segment kind, one mesh (per-vertex colours) for all
region fills, one line-segments node for all region outlines, one mesh for
the walls. Scene node names are part of the inspector's interface (tests and
the snapshot look for them): ``/segments/<kind>``, ``/walls``,
``/regions/fill``, ``/regions/outlines``, ``/plan/walls``, ``/plan/free``.

The floor decorations sit a few millimetres below z = 0 so that floor
junction segments (at z = 0) are drawn over them, not hidden.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh

from linemap.lmap import LineMap, SegmentKind
from mapkit.view import palette
from mapkit.view.geometry import Triangles, extrude, lift, ring_edges, unique_edges, wall_polygon

#: Heights of the floor layers (metres): fills lowest, then outlines, then
#: the highlights drawn by the inspector; model segments at z = 0 above all.
Z_FILL = -0.012
Z_OUTLINE = -0.008
Z_RETAINED = -0.006
Z_SELECTED = -0.004

#: Above this many regions the outlines start hidden (their toggle shows
#: them): thousands of screen-space lines cost about a second of the first
#: frame in software WebGL, and neighbouring fills already differ in colour.
OUTLINES_SHOWN_UP_TO = 2000

#: Line widths in screen pixels (independent of zoom, so a whole building stays legible).
SEGMENT_PX = 2.5
OUTLINE_PX = 1.0
HIGHLIGHT_PX = 4.5


@dataclass
class MapLayers:
    """Handles of the static layers, by the name of the GUI toggle that shows them."""

    handles: dict[str, list] = field(default_factory=dict)

    def visible(self, layer: str) -> bool:
        return all(h.visible for h in self.handles.get(layer, []))

    def set_visible(self, layer: str, visible: bool) -> None:
        for h in self.handles.get(layer, []):
            h.visible = visible


def segment_layer_name(kind: SegmentKind) -> str:
    return f"/segments/{kind.label}"


def add_segments(scene, m: LineMap, layers: MapLayers) -> None:
    """One line-segments node per segment kind present in the map."""
    for kind in SegmentKind:
        sel = m.kinds == kind
        if not sel.any():
            continue
        h = scene.add_line_segments(
            segment_layer_name(kind), m.segments[sel].astype(np.float32), palette.KIND_COLOURS[kind],
            thickness=SEGMENT_PX, thickness_units="screen",
        )
        layers.handles.setdefault(f"{kind.label} segments", []).append(h)


def add_walls(scene, m: LineMap, layers: MapLayers, height: float) -> trimesh.Trimesh | None:
    """The wall outlines extruded to ``height``, semi-transparent, double-sided."""
    if len(m.wall_offsets) < 2:
        return None
    mesh = extrude(wall_polygon(m), height)
    if len(mesh.faces) == 0:
        return None
    h = scene.add_mesh_simple(
        "/walls", mesh.vertices.astype(np.float32), mesh.faces.astype(np.uint32), color=palette.WALL,
        opacity=0.35, side="double", flat_shading=True, cast_shadow=False, receive_shadow=False,
    )
    layers.handles.setdefault("walls", []).append(h)
    return mesh


def region_fill_mesh(tris: Triangles, region_colour: np.ndarray) -> trimesh.Trimesh:
    """All region fills as one mesh, coloured per vertex.

    The colours travel as texture coordinates into a one-row palette texture
    rather than as a glTF ``COLOR_0`` attribute: viser's glTF path drops
    vertex colours (the fills came out white), while textured glTF is its
    common case. Each vertex samples the centre of its colour's texel, so
    filtering cannot blend neighbouring palette entries.
    """
    from PIL import Image

    k = len(palette.REGION_PALETTE)
    idx = region_colour[tris.owner] if len(tris.owner) else np.zeros(0, dtype=np.int64)
    u = (np.repeat(idx, 3) + 0.5) / k
    uv = np.c_[u, np.full(len(u), 0.5)]
    texture = Image.fromarray(palette.REGION_PALETTE.reshape(1, k, 3))
    material = trimesh.visual.material.PBRMaterial(
        baseColorTexture=texture, metallicFactor=0.0, roughnessFactor=1.0, doubleSided=True
    )
    verts = np.c_[tris.vertices, np.full(len(tris.vertices), Z_FILL)]
    mesh = trimesh.Trimesh(vertices=verts, faces=tris.faces, process=False)
    mesh.visual = trimesh.visual.TextureVisuals(uv=uv, material=material)
    return mesh


def add_regions(scene, m: LineMap, tris: Triangles, region_colour: np.ndarray, layers: MapLayers) -> None:
    """Region fills (one mesh) and outlines (one line-segments node)."""
    if len(tris.faces):
        mesh = region_fill_mesh(tris, region_colour)
        h = scene.add_mesh_trimesh("/regions/fill", mesh, cast_shadow=False, receive_shadow=False)
        layers.handles.setdefault("region fills", []).append(h)
    edges, _ = ring_edges(m.ring_points, m.ring_offsets)
    edges = unique_edges(edges)  # neighbours share most edges: half the lines to draw
    if len(edges):
        h = scene.add_line_segments(
            "/regions/outlines", lift(edges, Z_OUTLINE).astype(np.float32), palette.OUTLINE,
            thickness=OUTLINE_PX, thickness_units="screen", visible=m.n_regions <= OUTLINES_SHOWN_UP_TO,
        )
        layers.handles.setdefault("region outlines", []).append(h)


def add_plan(scene, plan, layers: MapLayers) -> None:
    """Overlay of an imported plan (a :class:`mapkit.scene.Scene`): the
    importer's wall outlines and free-space outline, drawn at floor level."""
    from mapkit.shapes import rings_of

    for name, geom, colour in (("/plan/walls", plan.walls, palette.PLAN_WALLS),
                               ("/plan/free", plan.free_space, palette.PLAN_FREE)):
        rings = rings_of(geom)
        if not rings:
            continue
        offsets = np.zeros(len(rings) + 1, dtype=np.int64)
        np.cumsum([len(p) for p, _ in rings], out=offsets[1:])
        edges, _ = ring_edges(np.concatenate([p for p, _ in rings]), offsets)
        h = scene.add_line_segments(name, lift(edges, 0.02).astype(np.float32), colour,
                                    thickness=1.5, thickness_units="screen")
        layers.handles.setdefault("plan overlay", []).append(h)


def add_map_layers(scene, m: LineMap, tris: Triangles, region_colour: np.ndarray, plan=None) -> MapLayers:
    """Every static layer of ``m`` (and of the source ``plan`` if given)."""
    layers = MapLayers()
    add_regions(scene, m, tris, region_colour, layers)
    add_segments(scene, m, layers)
    add_walls(scene, m, layers, float(m.meta.get("wall_height") or _segment_top(m)))
    if plan is not None:
        add_plan(scene, plan, layers)
    return layers


def _segment_top(m: LineMap) -> float:
    """Wall height when META records none: the highest segment, or 2.5 m."""
    top = float(m.segments[:, :, 2].max()) if m.n_segments else 0.0
    return top if top > 0 else 2.5

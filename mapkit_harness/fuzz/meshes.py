"""The ``mesh`` fuzz family: every mesh format (OBJ, OFF, ASCII and
binary PLY and STL, GLB) with damaged text lines or bytes (flipped bits,
overwritten floats, counts, truncation); then ``mapkit build`` and a built
map read by ``FOLLOW_UPS``.
"""

from __future__ import annotations

import random
from functools import lru_cache

from .cases import DATA, Case, follow_ups, source_bytes
from .mutations import mutate_bytes, mutate_lines


@lru_cache(maxsize=None)
def mesh_sources() -> dict[str, bytes]:
    """Every mesh format, from the committed meshes (hospital.stl exported
    to the formats not committed)."""
    import trimesh

    out = {"hospital.stl": source_bytes(DATA / "hospital.stl"),
           "simple_room.glb": source_bytes(DATA / "simple_room.glb")}
    for p in sorted((DATA / "mesh").glob("*.obj")):
        out[p.name] = source_bytes(p)
    hospital = trimesh.load(DATA / "hospital.stl", force="mesh")
    out["hospital.obj"] = trimesh.exchange.obj.export_obj(hospital).encode()
    out["hospital.off"] = trimesh.exchange.off.export_off(hospital).encode()
    out["hospital_ascii.ply"] = trimesh.exchange.ply.export_ply(hospital, encoding="ascii")
    out["hospital_binary.ply"] = trimesh.exchange.ply.export_ply(hospital, encoding="binary")
    out["hospital_ascii.stl"] = trimesh.exchange.stl.export_stl_ascii(hospital).encode()
    return out


def _is_text_mesh(name: str, blob: bytes) -> bool:
    return name.endswith((".obj", ".off")) or "ascii" in name


def mesh_case(rng: random.Random, name: str = "mesh") -> Case:
    """A damaged mesh of some format and ``mapkit build`` on it."""
    sources = mesh_sources()
    src = rng.choice(sorted(sources))
    blob = sources[src]
    if _is_text_mesh(src, blob) and rng.random() < 0.7:
        text, note = mutate_lines(blob.decode("latin-1"), rng)
        blob = text.encode("latin-1")
    else:
        blob, note = mutate_bytes(blob, rng)
    ext = "." + src.rsplit(".", 1)[1]
    return Case("mesh", name, {"model" + ext: blob}, ["mapkit", "build", "model" + ext, "-o", "out.lmap"],
                f"{src}: {note}", **follow_ups(["build"]))

"""Mesh edits with packed arrays (protocol/README.md, "add_mesh", "update_mesh" and
"replace_triangles"): new positions for listed vertices, a run of triangles replaced by others,
points and curve meshes with their radii, and vertex keys for deformation blur, with their arrays
packed as base64 little-endian (float32 positions and radii, uint32 indices and strands). On a
big mesh the server then refits or rebuilds only the clusters the edit touches.

    from strata_client import mesh_edits

    strata.edit([mesh_edits.update_vertices("terrain", dent_ids, dent_positions),
                 mesh_edits.replace_triangles("terrain", first=5120, count=512, triangles=cut)])
    strata.edit([mesh_edits.add_points("stars", centres, radii),
                 mesh_edits.add_curves("fur", control_points, radii, strands=[4] * 1000,
                                       basis="bspline")])
    # A cloth blurred along its motion over the frame: its vertices at 3 evenly spaced times.
    strata.edit([mesh_edits.vertex_keys("cloth", [at_open, at_middle, at_close])])

Arrays may be numpy arrays (positions (n, 3) or flat, triangles (n, 3) or flat, vertex ids (n,))
or sequences of numbers or of triples; numpy is imported only when an array is given.
"""

import base64
import struct
from typing import Any, Dict, Iterable, List, Sequence


def _flat(values: Any, width: int, what: str) -> List[Any]:
    """`values` as one flat list: rows of `width` numbers, or numbers already flat."""
    out: List[Any] = []
    for i, v in enumerate(values):
        if isinstance(v, (list, tuple)):
            if len(v) != width:
                raise ValueError(f"{what} {i} has {len(v)} numbers, not {width}")
            out.extend(v)
        else:
            out.append(v)
    if len(out) % width != 0:
        raise ValueError(f"{what}: {len(out)} numbers, not a multiple of {width}")
    return out


def _pack(values: Any, width: int, numpy_type: str, struct_code: str, what: str) -> str:
    if hasattr(values, "shape"):
        import numpy  # noqa: PLC0415 (numpy only when an array is given)
        flat = numpy.ascontiguousarray(numpy.asarray(values, dtype=numpy_type).reshape(-1))
        if flat.size % width != 0:
            raise ValueError(f"{what}: {flat.size} numbers, not a multiple of {width}")
        return base64.b64encode(flat.tobytes()).decode("ascii")
    flat_list = _flat(values, width, what)
    return base64.b64encode(struct.pack(f"<{len(flat_list)}{struct_code}", *flat_list)).decode(
        "ascii")


def pack_positions(positions: Any) -> str:
    """Base64 of little-endian float32 x y z triples."""
    return _pack(positions, 3, "<f4", "f", "position")


def pack_indices(values: Any, width: int = 3) -> str:
    """Base64 of little-endian uint32s (`width` per item: 3 for triangles, 1 for vertex ids)."""
    return _pack(values, width, "<u4", "I", "triangle" if width == 3 else "vertex id")


def pack_radii(radii: Any) -> str:
    """Base64 of little-endian float32s, one per vertex."""
    return _pack(radii, 1, "<f4", "f", "radius")


def pack_vertex_keys(keys: Sequence[Any]) -> str:
    """Base64 of keys 1.. of `keys` (each the positions of the same vertices at one key, key 0
    first) as motion_positions wants them: vertex after vertex, its keys 1.. in order."""
    if len(keys) < 2:
        raise ValueError("vertex keys: give at least 2 keys (key 0 is the positions)")
    import numpy  # noqa: PLC0415 (interleaving is numpy's job)
    arrays = [numpy.asarray(k, dtype="<f4").reshape(-1, 3) for k in keys]
    if any(a.shape != arrays[0].shape for a in arrays):
        raise ValueError("vertex keys: every key has the same number of vertices")
    return pack_positions(numpy.stack(arrays[1:], axis=1).reshape(-1, 3))


def vertex_keys(mesh: str, keys: Sequence[Any], offset: int = 0) -> Dict[str, Any]:
    """An update_mesh op giving vertices offset.. of `mesh` the positions of each key over the
    frame: keys[0] becomes their positions (key 0), keys[1:] their motion_positions. A mesh
    without vertex keys takes them only whole (offset 0, every vertex); a mesh with them keeps
    its number of keys (send motion_positions [] first to change it). Each such edit rebuilds
    the mesh's BLAS (Embree 3 has no refit for motion-blur BVHs)."""
    return {"op": "update_mesh", "mesh": mesh, "offset": int(offset),
            "positions_b64": pack_positions(keys[0]),
            "motion_positions_b64": pack_vertex_keys(keys)}


def remove_vertex_keys(mesh: str) -> Dict[str, Any]:
    """An update_mesh op removing `mesh`'s vertex keys: it stays at its positions all frame."""
    return {"op": "update_mesh", "mesh": mesh, "motion_positions": []}


def add_points(mesh_id: str, positions: Any, radii: Any, **fields: Any) -> Dict[str, Any]:
    """An add_mesh op of kind points: a sphere of radius `radii[i]` around each position.
    `fields` adds other members (material, name, build)."""
    return {"op": "add_mesh", "id": mesh_id, "kind": "points",
            "positions_b64": pack_positions(positions), "radii_b64": pack_radii(radii),
            **fields}


def add_curves(mesh_id: str, positions: Any, radii: Any, strands: Iterable[int],
               basis: str = "linear", style: str = "round", **fields: Any) -> Dict[str, Any]:
    """An add_mesh op of kind curves: strands of control vertices (`strands[k]` of them in
    strand k, in vertex order) with a radius each; `basis` linear, bezier, bspline or
    catmull_rom, `style` round (tubes) or flat (ribbons facing the ray)."""
    return {"op": "add_mesh", "id": mesh_id, "kind": "curves", "basis": basis, "style": style,
            "positions_b64": pack_positions(positions), "radii_b64": pack_radii(radii),
            "strands_b64": pack_indices(strands, 1), **fields}


def update_radii(mesh: str, radii: Any, offset: int = 0) -> Dict[str, Any]:
    """An update_mesh op giving vertices offset .. offset + len(radii) - 1 of a points or curve
    mesh new radii (a refit, like moved positions)."""
    return {"op": "update_mesh", "mesh": mesh, "offset": int(offset),
            "radii_b64": pack_radii(radii)}


def update_vertices(mesh: str, vertices: Iterable[int], positions: Any) -> Dict[str, Any]:
    """An update_mesh op giving new positions to listed vertices (a brush stroke, a dent):
    `positions[i]` goes to vertex `vertices[i]`."""
    return {"op": "update_mesh", "mesh": mesh, "vertices_b64": pack_indices(vertices, 1),
            "positions_b64": pack_positions(positions)}


def replace_triangles(mesh: str, first: int, count: int, triangles: Any) -> Dict[str, Any]:
    """A replace_triangles op: triangles first .. first + count - 1 of `mesh` are replaced by
    `triangles` (any number, over the mesh's existing vertices; empty cuts the run out)."""
    return {"op": "replace_triangles", "mesh": mesh, "first": int(first), "count": int(count),
            "indices_b64": pack_indices(triangles, 3)}

"""Local mesh edits (protocol/README.md, "update_mesh" and "replace_triangles"): new positions for
listed vertices, and a run of triangles replaced by others, with their arrays packed as base64
little-endian (float32 positions, uint32 indices). On a big mesh the server then refits or
rebuilds only the clusters the edit touches.

    from strata_client import mesh_edits

    strata.edit([mesh_edits.update_vertices("terrain", dent_ids, dent_positions),
                 mesh_edits.replace_triangles("terrain", first=5120, count=512, triangles=cut)])

Arrays may be numpy arrays (positions (n, 3) or flat, triangles (n, 3) or flat, vertex ids (n,))
or sequences of numbers or of triples; numpy is imported only when an array is given.
"""

import base64
import struct
from typing import Any, Dict, Iterable, List


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

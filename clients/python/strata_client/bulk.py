"""Bulk instance ops (protocol/README.md, "add_instances, update_instances, remove_instances"):
many instances in one edit, with transforms packed as base64 little-endian float32 3x4 rows.

    from strata_client import bulk

    xs = numpy.zeros((100_000, 3, 4), numpy.float32)
    xs[:, 0, 0] = xs[:, 1, 1] = xs[:, 2, 2] = 1
    xs[:, :, 3] = numpy.random.uniform(-50, 50, (100_000, 3))
    strata.edit([bulk.add_instances(bulk.id_range("tree-", 100_000), "tree", transforms=xs)])

Transforms may be a numpy array of shape (n, 3, 4), (n, 4, 4) or (n, 12), or a sequence of
12-number rows; numpy is imported only when an array is given.
"""

import base64
import struct
from typing import Any, Dict, Optional, Sequence, Union

Ids = Union[Sequence[str], Dict[str, Any]]
Transforms = Any  # a numpy array or a sequence of 12-number sequences


def id_range(prefix: str, count: int, first: int = 0) -> Dict[str, Any]:
    """Ids `prefix + str(first)` .. `prefix + str(first + count - 1)`."""
    return {"prefix": prefix, "first": first, "count": count}


def pack_transforms(transforms: Transforms) -> str:
    """Base64 of little-endian float32 3x4 row-major transforms, 48 bytes each."""
    if hasattr(transforms, "shape"):
        import numpy  # noqa: PLC0415 (numpy only when an array is given)
        rows = numpy.asarray(transforms, dtype="<f4")
        if rows.ndim == 3 and rows.shape[1:] == (4, 4):
            rows = rows[:, :3, :]
        elif not (rows.ndim == 3 and rows.shape[1:] == (3, 4)) and not (
                rows.ndim == 2 and rows.shape[1] == 12):
            raise ValueError(f"transforms of shape {rows.shape}: expected (n, 3, 4), "
                             "(n, 4, 4) or (n, 12)")
        return base64.b64encode(numpy.ascontiguousarray(rows).tobytes()).decode("ascii")
    out = bytearray()
    for i, row in enumerate(transforms):
        values = [float(v) for v in row]
        if len(values) != 12:
            raise ValueError(f"transform {i} has {len(values)} numbers, not 12 (3x4 row-major)")
        out += struct.pack("<12f", *values)
    return base64.b64encode(bytes(out)).decode("ascii")


def _ids(ids: Ids) -> Any:
    return ids if isinstance(ids, dict) else list(ids)


def add_instances(ids: Ids, mesh: Union[str, Sequence[str]], *,
                  transforms: Optional[Transforms] = None,
                  material: Union[None, str, Sequence[str]] = None,
                  parent: Optional[str] = None, visible: Optional[bool] = None) -> Dict[str, Any]:
    """An add_instances op: `mesh` and `material` are one id for all or a list, one per item."""
    op: Dict[str, Any] = {"op": "add_instances", "ids": _ids(ids),
                          "mesh": mesh if isinstance(mesh, str) else list(mesh)}
    if material is not None:
        op["material"] = material if isinstance(material, str) else list(material)
    if transforms is not None:
        op["transforms_b64"] = pack_transforms(transforms)
    if parent is not None:
        op["parent"] = parent
    if visible is not None:
        op["visible"] = visible
    return op


def update_instances(ids: Ids, *, transforms: Optional[Transforms] = None,
                     visible: Optional[bool] = None) -> Dict[str, Any]:
    """An update_instances op: new transforms (one per item) and/or visibility (for all)."""
    op: Dict[str, Any] = {"op": "update_instances", "ids": _ids(ids)}
    if transforms is not None:
        op["transforms_b64"] = pack_transforms(transforms)
    if visible is not None:
        op["visible"] = visible
    return op


def remove_instances(ids: Ids) -> Dict[str, Any]:
    """A remove_instances op."""
    return {"op": "remove_instances", "ids": _ids(ids)}

"""Level-of-detail groups (protocol/README.md, "Level of detail"): a group with "lod": true
whose children are levels, each drawn for the rays whose LOD distance from the group's origin
(the camera's distance, for camera rays) lies in its [lod_near, lod_far).

    from strata_client import lod

    strata.edit(lod.add_lod_group("tree", [("tree.high", "tree_high"), ("tree.low", "tree_low")],
                                  switch_distances=[40], transform={"translate": [5, 0, -20]}))
    strata.edit(lod.set_switch_distances(["tree.high", "tree.low"], [60]))

Level k is drawn from switch_distances[k - 1] (0 for the first level) to switch_distances[k]
(no limit for the last, unless `last_far` is given); moving the camera changes which level is
drawn and costs no BVH work.
"""

import math
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

Level = Union[Tuple[str, str], Dict[str, Any]]


def _ranges(levels: int, switch_distances: Sequence[float],
            last_far: Optional[float]) -> List[Tuple[float, Optional[float]]]:
    if levels < 1:
        raise ValueError("a level-of-detail group needs at least one level")
    if len(switch_distances) != levels - 1:
        raise ValueError(f"{levels} levels need {levels - 1} switch distances, "
                         f"not {len(switch_distances)}")
    edges = [0.0] + [float(d) for d in switch_distances]
    if last_far is not None:
        edges.append(float(last_far))
    for i, d in enumerate(edges):
        if not math.isfinite(d) or d < 0:
            raise ValueError(f"switch distance {d} is not a finite number >= 0")
        if i and d <= edges[i - 1]:
            raise ValueError(f"switch distances must increase: {edges[i - 1]} then {d}")
    ends: List[Optional[float]] = list(edges[1:])
    if last_far is None:
        ends.append(None)
    return list(zip(edges[:levels], ends))


def _range_fields(near: float, far: Optional[float]) -> Dict[str, Any]:
    fields: Dict[str, Any] = {"lod_near": near}
    if far is not None:
        fields["lod_far"] = far
    return fields


def add_lod_group(group_id: str, levels: Sequence[Level], switch_distances: Sequence[float],
                  *, parent: Optional[str] = None, transform: Optional[Dict[str, Any]] = None,
                  last_far: Optional[float] = None) -> List[Dict[str, Any]]:
    """Edits that add level-of-detail group `group_id` and one instance per level, finest first.

    A level is (instance id, mesh id), or a dict of add_instance fields (id and mesh at least;
    its parent and range are set here). The group's origin, where distances are measured from,
    is its transform's translation."""
    group: Dict[str, Any] = {"op": "add_group", "id": group_id, "lod": True}
    if parent is not None:
        group["parent"] = parent
    if transform is not None:
        group["transform"] = transform
    edits = [group]
    for level, (near, far) in zip(levels, _ranges(len(levels), switch_distances, last_far)):
        fields = dict(level) if isinstance(level, dict) else {"id": level[0], "mesh": level[1]}
        fields.update(op="add_instance", parent=group_id, **_range_fields(near, far))
        edits.append(fields)
    return edits


def set_switch_distances(level_ids: Sequence[str], switch_distances: Sequence[float], *,
                         last_far: Optional[float] = None) -> List[Dict[str, Any]]:
    """update_instance edits giving the levels `level_ids` (finest first) new switch
    distances: a TLAS update of those instances, no BLAS work."""
    ranges = _ranges(len(level_ids), switch_distances, last_far)
    return [{"op": "update_instance", "instance": level_id, "lod_near": near,
             "lod_far": 1e15 if far is None else far}
            for level_id, (near, far) in zip(level_ids, ranges)]

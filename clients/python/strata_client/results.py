"""Typed results: what the server answers, as dataclasses (protocol/README.md names every member).

The results that version 0.1 returned as plain dicts (rebuild reports, picks, import answers)
are dataclasses that are also that dict: `report.tlas.action` and `report["tlas"]["action"]`
read the same value, `json.dumps(report)` still works, and members a newer server adds are kept
in the dict (the protocol only ever adds members). Treat them as read-only.
"""

import datetime as _dt
from dataclasses import dataclass, field, fields
from typing import Any, Callable, Dict, List, Mapping, Optional, Type, TypeVar

J = TypeVar("J", bound="JsonObject")


def _member(convert: Callable[[Any], Any], **kwargs: Any) -> Any:
    """A dataclass field whose JSON value is converted by `convert` (a nested object or list)."""
    return field(metadata={"from_json": convert}, **kwargs)


class JsonObject(Dict[str, Any]):
    """Base of the dataclasses that are also the JSON object they were read from."""

    def __post_init__(self) -> None:
        self._set_members({f.name: getattr(self, f.name) for f in fields(self)})

    def _set_members(self, members: Mapping[str, Any]) -> None:
        super().clear()
        super().update(members)

    @classmethod
    def from_json(cls: Type[J], doc: Mapping[str, Any]) -> J:
        """Reads a JSON object; nested objects become their dataclasses in both views."""
        values: Dict[str, Any] = {}
        members = dict(doc)
        for f in fields(cls):
            if f.name not in doc:
                continue  # the field's default; the dict view leaves the member out, as sent
            value = doc[f.name]
            convert = f.metadata.get("from_json")
            if convert is not None and value is not None:
                value = convert(value)
            values[f.name] = value
            members[f.name] = value
        try:
            result = cls(**values)
        except TypeError as e:
            raise ValueError(f"{cls.__name__}: the answer lacks a member ({e})") from None
        result._set_members(members)
        return result


def _list_of(kind: Type[J]) -> Callable[[List[Mapping[str, Any]]], List[J]]:
    return lambda items: [kind.from_json(item) for item in items]


@dataclass(frozen=True, eq=False)
class BlasEntry(JsonObject):
    """One BLAS a commit rebuilt or refit: the mesh, why, its primitives and milliseconds.

    A clustered BLAS also says how many clusters it has and how many this commit refit and
    rebuilt (None for a BLAS built whole). A rebuild gives the BLAS's bytes; a mesh built with
    ``build.compact`` also its bytes at full size, before compaction (None otherwise)."""

    mesh: str
    reason: str
    primitives: int = 0
    ms: Optional[float] = None
    detail: Optional[str] = None
    clusters: Optional[int] = None
    clusters_refit: Optional[int] = None
    clusters_rebuilt: Optional[int] = None
    bytes: Optional[int] = None
    uncompacted_bytes: Optional[int] = None


@dataclass(frozen=True, eq=False)
class TlasMerge(JsonObject):
    """The incremental TLAS's background merge: swapped in by this commit, or still running."""

    swapped: bool
    running: bool
    cancelled: bool = False
    build_ms: Optional[float] = None


@dataclass(frozen=True, eq=False)
class TlasReport(JsonObject):
    """What a commit did to the TLAS. A plan has action, instances and strategy only."""

    action: str
    instances: int
    strategy: str
    ms: Optional[float] = None
    static_instances: Optional[int] = None
    dynamic_instances: Optional[int] = None
    stale_copies: Optional[int] = None
    static_array: Optional[bool] = None
    dynamic_array: Optional[bool] = None
    static_rebuild: Optional[str] = None
    merge: Optional[TlasMerge] = _member(TlasMerge.from_json, default=None)


@dataclass(frozen=True, eq=False)
class Compaction(JsonObject):
    """The meshes built with ``build.compact``: how many, their BLAS bytes at full size
    (measured at their last builds) and compacted, and the difference."""

    meshes: int
    uncompacted_bytes: int
    bytes: int
    saved_bytes: int


@dataclass(frozen=True, eq=False)
class MemoryBytes(JsonObject):
    """Bytes the acceleration structures hold (a report's also says what compaction saved)."""

    blas: int
    tlas: int
    compaction: Optional[Compaction] = _member(Compaction.from_json, default=None)


@dataclass(frozen=True, eq=False)
class SceneBudget(JsonObject):
    """What a scene may hold: triangles, vertices, instances and texture MiB."""

    max_triangles: int
    max_vertices: int
    max_instances: int
    max_texture_mb: int


@dataclass(frozen=True, eq=False)
class SceneSummary(JsonObject):
    """One scene of GET /v1/scenes: its name, version, totals, acceleration memory, whether
    it is kept in the data directory, and its budget."""

    name: str
    version: int
    meshes: int
    instances: int
    triangles: int
    vertices: int
    memory_bytes: MemoryBytes = _member(MemoryBytes.from_json)
    durable: bool = False
    budget: SceneBudget = _member(SceneBudget.from_json, default=None)


@dataclass(frozen=True, eq=False)
class CommitPhases(JsonObject):
    """Milliseconds of a commit's parts."""

    plan_ms: float
    blas_ms: float
    tlas_ms: float
    sync_ms: float


@dataclass(frozen=True, eq=False)
class RebuildReport(JsonObject):
    """A rebuild report (POST /v1/commit, GET /v1/plan, a render's X-Strata-Report).

    A plan (`planned` true) has no `ms` and no `phases`.
    """

    version: int
    planned: bool
    tlas: TlasReport = _member(TlasReport.from_json)
    blas_rebuilds: int = 0
    blas_refits: int = 0
    rebuilt: List[BlasEntry] = _member(_list_of(BlasEntry), default_factory=list)
    refit: List[BlasEntry] = _member(_list_of(BlasEntry), default_factory=list)
    released: List[str] = field(default_factory=list)
    primitives_built: int = 0
    primitives_refit: int = 0
    clusters_rebuilt: int = 0
    clusters_refit: int = 0
    world_transforms: int = 0
    instances_changed: int = 0
    memory_bytes: Optional[MemoryBytes] = _member(MemoryBytes.from_json, default=None)
    ms: Optional[float] = None
    phases: Optional[CommitPhases] = _member(CommitPhases.from_json, default=None)
    entries_truncated: bool = False


@dataclass(frozen=True, eq=False)
class Hit(JsonObject):
    """What a pick's ray hit: client ids, the groups from the root down to the instance's parent,
    the distance along the unit camera ray, and world-space position and normal."""

    instance: str
    mesh: str
    distance: float
    primitive: int
    position: List[float]
    normal: List[float]
    group_path: List[str] = field(default_factory=list)
    user_id: int = 0
    name: str = ""


@dataclass(frozen=True, eq=False)
class ImportResult(JsonObject):
    """The answer to POST /v1/assets: the version after the import and the ids it created."""

    version: int
    applied: int
    format: str
    meshes: List[str] = field(default_factory=list)
    materials: List[str] = field(default_factory=list)
    groups: List[str] = field(default_factory=list)
    instances: List[str] = field(default_factory=list)
    textures: List[str] = field(default_factory=list)
    warnings: List[str] = field(default_factory=list)
    model: Optional[str] = None
    bounds: Optional[Dict[str, List[float]]] = None  #: {"min", "max"} of its instances


@dataclass(frozen=True, eq=False)
class KeptIds(JsonObject):
    """What a re-import made exactly as the scene held it: neither removed nor added."""

    textures: List[str] = field(default_factory=list)
    materials: List[str] = field(default_factory=list)
    meshes: List[str] = field(default_factory=list)


@dataclass(frozen=True, eq=False)
class ReimportResult(ImportResult):
    """The answer to PUT /v1/assets/{id}: an ImportResult, whether an asset was replaced (False:
    a first import), what was kept unchanged (no BLAS work) and the ids that are gone."""

    replaced: bool = False
    kept: KeptIds = _member(KeptIds.from_json, default=None)
    removed: List[str] = field(default_factory=list)


@dataclass(frozen=True, eq=False)
class AssetCounts(JsonObject):
    """How many objects of each kind an asset owns."""

    textures: int
    materials: int
    meshes: int
    groups: int
    instances: int


@dataclass(frozen=True, eq=False)
class Asset(JsonObject):
    """An imported asset (GET /v1/assets): its id (its group's, the prefix of what it owns), the
    file it came from, its counts and the world bounds of its instances (None: none). Read
    with Client.asset(id), it also lists the ids it owns; from the listing those are empty."""

    id: str
    file: str
    counts: AssetCounts = _member(AssetCounts.from_json)
    bounds: Optional[Dict[str, List[float]]] = None
    name: str = ""
    textures: List[str] = field(default_factory=list)
    materials: List[str] = field(default_factory=list)
    meshes: List[str] = field(default_factory=list)
    groups: List[str] = field(default_factory=list)
    instances: List[str] = field(default_factory=list)


@dataclass(frozen=True, eq=False)
class AssetDeleteResult(JsonObject):
    """The answer to DELETE /v1/assets/{id}: the new version and the ids removed, by kind."""

    version: int
    applied: int
    removed: Dict[str, List[str]] = field(default_factory=dict)


@dataclass(frozen=True, eq=False)
class UndoResult(JsonObject):
    """The answer to POST /v1/undo (`undone`) or POST /v1/redo (`redone`): the new version, the
    version whose batch it took back or applied again (`target`, either way), and how many edits
    it applied."""

    version: int
    applied: int
    undone: Optional[int] = None
    redone: Optional[int] = None

    @property
    def target(self) -> int:
        """The version whose batch this undo took back, or this redo applied again."""
        target = self.undone if self.undone is not None else self.redone
        if target is None:
            raise ValueError("UndoResult: the answer has neither undone nor redone")
        return target


@dataclass(frozen=True, eq=False)
class HistoryStack(JsonObject):
    """The undo or the redo stack: how many batches it holds and the version the next undo
    (redo) takes back (applies again), None when it is empty."""

    depth: int
    next: Optional[int] = None


@dataclass(frozen=True, eq=False)
class HistoryEntry(JsonObject):
    """One version of the scene: when it was made (`time`, RFC 3339 UTC), by what (`kind`
    "edit", "undo" or "redo"; `target` the version an undo or redo took back or applied again),
    its batch's `message`, how many edits it had and of which ops (`ops`, op name to count), and
    whether it is on the undo stack now (`undoable`)."""

    version: int
    time: str
    kind: str
    edits: int
    undoable: bool
    ops: Dict[str, int] = field(default_factory=dict)
    target: Optional[int] = None
    message: Optional[str] = None

    @property
    def datetime(self) -> _dt.datetime:
        """`time` as an aware datetime in UTC."""
        return _dt.datetime.fromisoformat(self.time.replace("Z", "+00:00"))


@dataclass(frozen=True, eq=False)
class History(JsonObject):
    """One page of GET /v1/history: the scene's versions newest first (`entries`), the cursor of
    the next, older page (None on the last), the current `version`, the `oldest` version the
    history holds, the `undo` and `redo` stacks and the bytes they hold."""

    version: int
    undo: HistoryStack = _member(HistoryStack.from_json)
    redo: HistoryStack = _member(HistoryStack.from_json)
    entries: List[HistoryEntry] = _member(_list_of(HistoryEntry), default_factory=list)
    oldest: Optional[int] = None
    held_bytes: int = 0
    next_cursor: Optional[str] = None


@dataclass
class RenderInfo:
    """What a render answered besides the image: the version the frame shows (ETag), the one-line
    summary of the commit it ran (X-Strata-Rebuild), that commit's full report
    (X-Strata-Report; None if absent), the content type, the samples per pixel in the frame
    (X-Strata-Samples) and, for a split render, who rendered each band (X-Strata-Split)."""

    version: Optional[int]
    rebuild: str
    content_type: str
    report: Optional[RebuildReport] = field(default=None, repr=False)
    samples: Optional[int] = None
    split: Optional[str] = None


@dataclass(frozen=True)
class Frame:
    """A rendered frame: the encoded image (PNG or EXR bytes, as the server sent them) and what
    the render answered besides."""

    image: bytes = field(repr=False)
    info: RenderInfo


@dataclass(frozen=True)
class Page:
    """One page of a listing (GET /v1/scene/{collection}): its documents, the cursor of the next
    page (None on the last) and the scene version every item was read at."""

    items: List[Dict[str, Any]]
    next_cursor: Optional[str]
    version: int

    @classmethod
    def from_json(cls, doc: Mapping[str, Any]) -> "Page":
        return cls(list(doc["items"]), doc.get("next_cursor"), doc["version"])


_STANDARD_PROBLEM_MEMBERS = ("type", "title", "status", "detail", "edit_index", "pointer")


@dataclass(frozen=True)
class Problem:
    """A problem document (RFC 9457): the stable `type` URI, `title`, `status`, `detail`, the
    offending edit's position and a JSON pointer into the request where they apply, and the
    members beyond those (`extensions`, e.g. an invalid asset's `file` and `element`)."""

    type: str
    title: str
    status: int
    detail: str = ""
    edit_index: Optional[int] = None
    pointer: Optional[str] = None
    extensions: Dict[str, Any] = field(default_factory=dict)

    @classmethod
    def from_json(cls, doc: Mapping[str, Any], status: int) -> "Problem":
        """Reads a problem document; `status` is the HTTP status, used if the body has none."""
        extra = {k: v for k, v in doc.items() if k not in _STANDARD_PROBLEM_MEMBERS}
        return cls(str(doc.get("type", "about:blank")), str(doc.get("title", "")),
                   int(doc.get("status", status)), str(doc.get("detail", "")),
                   doc.get("edit_index"), doc.get("pointer"), extra)

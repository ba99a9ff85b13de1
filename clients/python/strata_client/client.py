"""The blocking client: one keep-alive http.client connection, typed results, problem documents
as exceptions."""

import http.client
from typing import Any, Dict, Iterable, Iterator, List, Optional, Tuple, TypeVar

from strata_client import _api
from strata_client._api import IfMatch
from strata_client.errors import ProblemError
from strata_client.arrays import FrameArrays, frame_arrays
from strata_client.png import png_to_array
from strata_client.results import (Asset, AssetDeleteResult, Frame, History, HistoryEntry, Hit,
                                   ImportResult, Page, RebuildReport, ReimportResult, RenderInfo,
                                   SceneSummary, UndoResult)

__all__ = ["Client", "ProblemError", "RenderInfo"]

T = TypeVar("T")

# Failures of a kept-alive connection the server closed while it was idle: they happen before
# the server reads the request, so sending it again applies nothing twice.
_STALE_CONNECTION = (http.client.RemoteDisconnected, BrokenPipeError, ConnectionResetError,
                     http.client.CannotSendRequest)


class Client:
    """A connection to strata-server.

    `url` is scheme://host[:port] (http or https); `token` the bearer token of a server started
    with --token-file. One HTTP/1.1 connection is kept alive across requests and reopened when
    the server has closed it (an idle keep-alive connection, a restart). Usable as a context
    manager; close() releases the connection. Not thread-safe: use one Client per thread.

    `scene`: every scene endpoint (edits, renders, history, ...) works on that named scene
    (/v1/scenes/{scene}/...) instead of the default one; see create_scene().
    """

    def __init__(self, url: str = "http://127.0.0.1:7070", token: Optional[str] = None,
                 timeout: float = 300.0, scene: Optional[str] = None):
        self._endpoint = _api.parse_url(url)
        self.url = self._endpoint.url
        self._token = token
        self._timeout = timeout
        #: The named scene this client works on; None: the default scene.
        self.scene_name = None if scene is None else _api.check_scene_name(scene)
        self._conn: Optional[http.client.HTTPConnection] = None
        #: What the last render answered besides the image.
        self.last_render: Optional[RenderInfo] = None

    # -- connection -----------------------------------------------------------------------------

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Closes the connection (a later request opens a new one)."""
        if self._conn is not None:
            self._conn.close()
            self._conn = None

    def _connection(self) -> http.client.HTTPConnection:
        if self._conn is None:
            e = self._endpoint
            cls = http.client.HTTPSConnection if e.https else http.client.HTTPConnection
            self._conn = cls(e.host, e.port, timeout=self._timeout)
        return self._conn

    def _send(self, request: _api.Request) -> _api.Response:
        """Sends one request and reads the whole answer; a connection the server closed while
        idle is reopened and the request sent again once."""
        headers = _api.request_headers(request, self._token)
        for attempt in (0, 1):
            reused = self._conn is not None
            conn = self._connection()
            try:
                answer = self._exchange(conn, request, headers)
            except _STALE_CONNECTION:
                self.close()
                if reused and attempt == 0:
                    continue
                raise
            except (OSError, http.client.HTTPException):
                self.close()
                raise
            if answer.headers.get("connection", "").lower() == "close":
                self.close()
            return answer
        raise AssertionError("unreachable")

    @staticmethod
    def _exchange(conn: http.client.HTTPConnection, request: _api.Request,
                  headers: Dict[str, str]) -> _api.Response:
        try:
            conn.request(request.method, request.target, body=request.body, headers=headers)
        except (BrokenPipeError, ConnectionResetError) as send_error:
            # The server may have answered and closed before reading the whole body (a 413 for
            # a body over its limit): that answer is the result. None: the connection was stale.
            try:
                response = conn.getresponse()
            except (OSError, http.client.HTTPException):
                raise send_error from None
        else:
            response = conn.getresponse()
        data = response.read()
        return _api.Response(response.status,
                             {k.lower(): v for k, v in response.getheaders()}, data)

    def _call(self, call: "_api.Call[T]") -> T:
        call = _api.in_scene(call, self.scene_name)
        return call.result(self._send(call.request))

    # -- scenes ---------------------------------------------------------------------------------

    def scenes(self) -> List[SceneSummary]:
        """Every scene on the server, the default one first (GET /v1/scenes)."""
        return self._call(_api.scenes())

    def scene_summary(self, name: str) -> SceneSummary:
        """One scene's version, totals, memory and budget (GET /v1/scenes/{name})."""
        return self._call(_api.scene_summary(name))

    def create_scene(self, name: str, max_triangles: Optional[int] = None,
                     max_vertices: Optional[int] = None, max_instances: Optional[int] = None,
                     max_texture_mb: Optional[int] = None) -> SceneSummary:
        """Creates the named scene, empty (PUT /v1/scenes/{name}), or finds it when it exists.
        The limits lower its budget below the server's --max-scene-* flags (UnprocessableError
        above them); SceneConflictError when it exists with another budget. Work in it with
        for_scene(name), or a Client made with scene=name."""
        return self._call(_api.create_scene(name, {
            "max_triangles": max_triangles, "max_vertices": max_vertices,
            "max_instances": max_instances, "max_texture_mb": max_texture_mb}))

    def delete_scene(self, name: str) -> None:
        """Deletes the named scene with its history and files (DELETE /v1/scenes/{name});
        NotFoundError when there is none, SceneConflictError for "default"."""
        self._call(_api.delete_scene(name))

    def for_scene(self, name: Optional[str]) -> "Client":
        """A new Client on the same server and token, working on scene `name` (None: the
        default scene)."""
        return Client(self.url, self._token, self._timeout, scene=name)

    # -- endpoints ------------------------------------------------------------------------------

    def edit(self, edits: Iterable[Dict[str, Any]], if_match: IfMatch = None,
             message: Optional[str] = None) -> int:
        """Applies a batch (POST /v1/edits); returns the new scene version.

        `if_match`: apply only at this version (an int, or an entity tag such as '"7"' or '*');
        otherwise VersionMismatchError (412) with the current version in `current_version`.
        `message`: a note kept with the new version in history() (UTF-8, at most 1024 bytes, no
        control characters).
        """
        return self._call(_api.edit(edits, if_match, message))

    def undo(self, if_match: IfMatch = None) -> UndoResult:
        """Takes back the newest batch on the undo stack (POST /v1/undo): its inverse is applied
        as a new version. Returns the new `version`, the version taken back (`target`, also
        `undone`) and `applied`. Repeat to go further back.

        NothingToUndoError (409) when the undo stack is empty; `if_match` as for edit().
        """
        return self._call(_api.undo(False, if_match))

    def redo(self, if_match: IfMatch = None) -> UndoResult:
        """Applies again the batch the newest undo took back (POST /v1/redo), as a new version;
        `target` (also `redone`) is the version redone. A new edit empties the redo stack:
        NothingToUndoError (409) then, and when nothing was undone. `if_match` as for edit().
        """
        return self._call(_api.undo(True, if_match))

    def history(self, limit: Optional[int] = None, cursor: Optional[str] = None) -> History:
        """One page of the scene's versions, newest first (GET /v1/history): `entries`
        (HistoryEntry: version, time, kind, target, message, edits, ops, undoable), the
        `undo` and `redo` stacks, and `next_cursor` for the next, older page (None on the last).
        `limit`: 1 to 1000 entries (the server's default: 50)."""
        return self._call(_api.history(limit, cursor))

    def history_entries(self, page_size: int = 1000) -> Iterator[HistoryEntry]:
        """Every version the history holds, newest first (GET /v1/history, following cursors).
        A version made while iterating is not listed; the rest are, each once."""
        cursor: Optional[str] = None
        while True:
            page = self.history(page_size, cursor)
            yield from page.entries
            if page.next_cursor is None:
                return
            cursor = page.next_cursor

    def import_asset(self, path: str, prefix: Optional[str] = None, fmt: Optional[str] = None,
                     instance: bool = True, parent: Optional[str] = None,
                     if_match: IfMatch = None) -> ImportResult:
        """Imports a glTF (.glb or .gltf), OBJ or PLY file, or an FBX, COLLADA (.dae), STL, 3DS,
        OFF, ... file read through assimp (POST /v1/assets) as one batch;
        returns the answer: version, applied, format, the ids created (meshes, materials,
        groups, instances, textures), warnings, and model when it went as an archive.

        An .obj that names MTL files (and the map_Kd images they name), or a .gltf with external
        buffers or images, is sent as a tar archive of them all, built in memory (asset_pack.py);
        a file they name that is missing locally raises FileNotFoundError before anything is
        sent. With `fmt` given, the file is sent alone.

        `prefix` starts every id it creates (default: the file name's stem); `fmt` is glb, gltf,
        obj, ply, fbx, dae, stl, ... (default: from the extension); `instance=False` creates meshes and materials
        only; `parent` names the group the asset's own group joins (default: the root). A file
        Strata cannot read raises UnprocessableError (422) whose body names the "file" and the
        "element" at fault.
        """
        return self._call(_api.import_asset(path, prefix, fmt, instance, parent, if_match))

    def assets(self, *, at_version: Optional[int] = None) -> List[Asset]:
        """Every imported asset (GET /v1/assets): id, file, counts (AssetCounts) and the world
        bounds of its instances; with `at_version`, as they were at that version."""
        return self._call(_api.assets(at_version))

    def asset(self, id: str, *, at_version: Optional[int] = None) -> Asset:
        """One asset with the ids of everything it owns (GET /v1/assets/{id}): its group and
        every object whose id begins with its id and a '.'. NotFoundError when no asset has it."""
        return self._call(_api.asset(id, at_version))

    def delete_asset(self, id: str, if_match: IfMatch = None) -> AssetDeleteResult:
        """Removes everything an asset owns in one batch (DELETE /v1/assets/{id}). An object
        outside the asset that still uses part of it raises UnprocessableError (in-use) and
        changes nothing."""
        return self._call(_api.delete_asset(id, if_match))

    def reimport_asset(self, id: str, path: str, fmt: Optional[str] = None,
                       instance: bool = True, parent: Optional[str] = None,
                       if_match: IfMatch = None) -> ReimportResult:
        """Imports a file in place of asset `id` in one batch (PUT /v1/assets/{id}): the same
        ids where the structure is the same, the asset's group where it was (unless `parent`
        is given), and textures, materials and meshes that did not change kept as they are
        (`kept`; no BLAS work). `replaced` is False when no asset had the id. Files are read
        and packed as import_asset does."""
        return self._call(_api.reimport_asset(id, path, fmt, instance, parent, if_match))

    def commit(self) -> RebuildReport:
        """Runs a commit (POST /v1/commit); returns its rebuild report."""
        return self._call(_api.commit())

    def plan(self) -> RebuildReport:
        """What the next commit would do (GET /v1/plan), as a report with planned true."""
        return self._call(_api.plan())

    def render_frame(self, width: int = 640, height: int = 360, fmt: str = "png",
                     **opts: Any) -> Frame:
        """Renders a frame (POST /v1/render); returns the encoded image with its RenderInfo.

        Every other request member passes through `opts`: spp, aovs, compression, accumulate,
        exposure, filter ("none" or "atrous"), split, time (the scene time the animated
        instances show in this frame; the scene keeps its own), camera={"eye": [...],
        "target": [...], "up": [...], "fov_y_deg": ...}, frame={"group": id} or
        {"instance": id} (aims the camera at it). `at_version=N` renders the scene as it was at
        version N (a time-zone aware datetime: as it was at that time, the newest version made
        by then) (from the server's data directory; NotFoundError when it holds no such
        version). Also sets `last_render`.
        """
        frame = self._call(_api.render(width, height, fmt, opts))
        self.last_render = frame.info
        return frame

    def render(self, width: int = 640, height: int = 360, fmt: str = "png",
               **opts: Any) -> bytes:
        """render_frame(), returning the encoded image only; `last_render` holds the rest."""
        return self.render_frame(width, height, fmt, **opts).image

    def render_array(self, width: int = 640, height: int = 360, **opts: Any) -> Any:
        """The frame as one numpy array (height, width, channels): with fmt="png" (the default)
        the tone-mapped image as uint8, with fmt="npz" the linear beauty as float32. numpy is
        imported only when this is called; render_arrays() gives the AOVs too."""
        fmt = opts.pop("fmt", "png")
        if fmt == "npz":
            return self.render_arrays(width, height, **opts)["beauty"]
        if fmt != "png":
            raise ValueError("render_array reads png or npz frames; for the AOVs of an EXR "
                             "frame as arrays, use render_arrays()")
        return png_to_array(self.render(width, height, "png", **opts))

    def render_arrays(self, width: int = 640, height: int = 360, **opts: Any) -> FrameArrays:
        """The frame and its AOVs (`aovs=["depth", "instance_id"]`) as numpy arrays, linear and
        at full precision (format npz), with the client ids behind the id AOVs."""
        frame = self.render_frame(width, height, "npz", **opts)
        return frame_arrays(frame)

    def stats(self) -> Dict[str, Any]:
        """Counters, the last report and memory (GET /v1/stats)."""
        return self._call(_api.stats())

    def scene(self, kind: Optional[str] = None, id: Optional[str] = None, *,
              at_version: Optional[int] = None) -> Dict[str, Any]:
        """The scene summary (GET /v1/scene), or one object's document with kind "meshes",
        "instances", "materials", "groups", "lights" or "textures" and its id
        (GET /v1/scene/{kind}/{id}); with `at_version`, as it was at that version."""
        return self._call(_api.scene(kind, id, at_version))

    def page(self, collection: str, limit: int = 100, cursor: Optional[str] = None, *,
             group: Optional[str] = None, mesh: Optional[str] = None,
             visible: Optional[bool] = None, parent: Optional[str] = None) -> Page:
        """One page of a listing (GET /v1/scene/{collection}): collection is one of
        scene()'s kinds, or "children" with `group`. `cursor` is the previous page's
        next_cursor; `mesh` and `visible` filter instances, `parent` instances and groups."""
        return self._call(_api.page(collection, limit, cursor, group,
                                    {"mesh": mesh, "visible": visible, "parent": parent}))

    def _walk(self, collection: str, page_size: int, group: Optional[str] = None,
              **filters: Any) -> Iterator[Dict[str, Any]]:
        cursor: Optional[str] = None
        while True:
            page = self.page(collection, page_size, cursor, group=group, **filters)
            yield from page.items
            if page.next_cursor is None:
                return
            cursor = page.next_cursor

    def instances(self, page_size: int = 1000, mesh: Optional[str] = None,
                  visible: Optional[bool] = None,
                  parent: Optional[str] = None) -> Iterator[Dict[str, Any]]:
        """Every instance (GET /v1/scene/instances, following cursors page by page), optionally
        only those of one mesh, only (in)visible ones, or only the children of group `parent`
        ("" for the root). Each item is the document scene("instances", id) returns."""
        return self._walk("instances", page_size, mesh=mesh, visible=visible, parent=parent)

    def groups(self, page_size: int = 1000,
               parent: Optional[str] = None) -> Iterator[Dict[str, Any]]:
        """Every group (GET /v1/scene/groups, following cursors), optionally only the children
        of group `parent` ("" for the root)."""
        return self._walk("groups", page_size, parent=parent)

    def children(self, group: str, page_size: int = 1000) -> Iterator[Dict[str, Any]]:
        """A group's direct children (GET /v1/scene/groups/{id}/children, following cursors):
        its groups, then its instances, each document with "kind" "group" or "instance"."""
        return self._walk("children", page_size, group=group)

    def tree(self, depth: int = 1, group: Optional[str] = None,
             max_nodes: Optional[int] = None) -> Dict[str, Any]:
        """The scene graph nested `depth` levels deep from the root or from `group`
        (GET /v1/scene/tree): {"groups": [...], "instances": [...], "truncated": bool, ...}."""
        return self._call(_api.tree(depth, group, max_nodes))

    def meshes(self, page_size: int = 1000) -> Iterator[Dict[str, Any]]:
        """Every mesh (GET /v1/scene/meshes, following cursors)."""
        return self._walk("meshes", page_size)

    def materials(self, page_size: int = 1000) -> Iterator[Dict[str, Any]]:
        """Every material (GET /v1/scene/materials, following cursors)."""
        return self._walk("materials", page_size)

    def textures(self, page_size: int = 1000) -> Iterator[Dict[str, Any]]:
        """Every texture (GET /v1/scene/textures, following cursors): id, width, height, format,
        encoded_bytes, decoded_bytes."""
        return self._walk("textures", page_size)

    def lights(self, page_size: int = 1000) -> Iterator[Dict[str, Any]]:
        """Every point, spot and rect light (GET /v1/scene/lights, following cursors)."""
        return self._walk("lights", page_size)

    def pick(self, x: int, y: int, width: int, height: int,
             camera: Optional[Dict[str, Any]] = None,
             time: Optional[float] = None) -> Optional[Hit]:
        """What lies under pixel (x, y) of a width x height frame (POST /v1/pick), seen from
        the scene camera or from `camera` (the render's override), with the animated instances
        at the scene's time or at `time` (the render's): a Hit, or None."""
        return self.pick_many([(x, y)], width, height, camera, time)[0]

    def pick_many(self, pixels: Iterable[Tuple[int, int]], width: int, height: int,
                  camera: Optional[Dict[str, Any]] = None,
                  time: Optional[float] = None) -> List[Optional[Hit]]:
        """pick() for many pixels at once (at most 10000), one ray each, all at one version."""
        return self._call(_api.pick_many(pixels, width, height, camera, time))


"""The asyncio client: Client's methods as coroutines, with the same typed results and problems,
over a few kept-alive HTTP/1.1 connections (asyncio streams, standard library only).

    async with AsyncClient("http://127.0.0.1:7070") as strata:
        version = await strata.edit([...])
        report = await strata.commit()
        async for instance in strata.instances():
            ...
"""

import asyncio
import functools
from typing import Any, AsyncIterator, Dict, Iterable, List, Optional, Tuple, TypeVar

from strata_client import _api
from strata_client._aio_http import Connection, RemoteDisconnected
from strata_client._api import IfMatch
from strata_client.arrays import FrameArrays, frame_arrays
from strata_client.png import png_to_array
from strata_client.results import (Asset, AssetDeleteResult, Frame, History, HistoryEntry, Hit,
                                   ImportResult, Page, RebuildReport, ReimportResult, RenderInfo,
                                   SceneSummary, UndoResult)

__all__ = ["AsyncClient"]

T = TypeVar("T")


class AsyncClient:
    """An asyncio connection to strata-server.

    `url`, `token` and `timeout` (seconds per request) as for Client. Requests made
    concurrently (asyncio.gather, several tasks) run on up to `max_connections` connections at
    once, each kept alive for the next request; more wait for one to be free. A connection the
    server closed while idle is reopened and the request sent again once, as Client does. Use
    it as an async context manager, or await close(). Use it from one event loop.
    """

    def __init__(self, url: str = "http://127.0.0.1:7070", token: Optional[str] = None,
                 timeout: float = 300.0, max_connections: int = 4, scene: Optional[str] = None):
        if max_connections < 1:
            raise ValueError("max_connections must be at least 1")
        self._endpoint = _api.parse_url(url)
        self.url = self._endpoint.url
        self._token = token
        self._timeout = timeout
        #: The named scene this client works on (as Client's `scene`); None: the default one.
        self.scene_name = None if scene is None else _api.check_scene_name(scene)
        self._max_connections = max_connections
        self._idle: List[Connection] = []
        # Made on first use, inside the running loop (before Python 3.10 a semaphore binds to
        # the loop current when it is made).
        self._slots: Optional[asyncio.Semaphore] = None
        #: What the last render answered besides the image (render_frame gives it per call).
        self.last_render: Optional[RenderInfo] = None

    # -- connections ----------------------------------------------------------------------------

    async def __aenter__(self) -> "AsyncClient":
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    async def close(self) -> None:
        """Closes the idle connections (a later request opens a new one)."""
        idle, self._idle = self._idle, []
        for conn in idle:
            conn.close()
        for conn in idle:
            await conn.wait_closed()

    async def _send(self, request: _api.Request) -> _api.Response:
        headers = _api.request_headers(request, self._token)
        if self._slots is None:
            self._slots = asyncio.Semaphore(self._max_connections)
        async with self._slots:
            for attempt in (0, 1):
                reused = attempt == 0 and bool(self._idle)  # a retry gets a new one
                conn = self._idle.pop() if reused else await asyncio.wait_for(
                    Connection.open(self._endpoint), self._timeout)
                try:
                    response = await asyncio.wait_for(
                        conn.exchange(request.method, request.target, headers, request.body),
                        self._timeout)
                except RemoteDisconnected:
                    conn.close()
                    if reused and attempt == 0:
                        continue
                    raise
                except BaseException:
                    conn.close()
                    raise
                if conn.reusable:
                    self._idle.append(conn)
                else:
                    conn.close()
                return response
        raise AssertionError("unreachable")

    async def _call(self, call: "_api.Call[T]") -> T:
        call = _api.in_scene(call, self.scene_name)
        return call.result(await self._send(call.request))

    # -- scenes: the same as Client's ---------------------------------------------------------

    async def scenes(self) -> List[SceneSummary]:
        """Every scene on the server, the default one first (GET /v1/scenes)."""
        return await self._call(_api.scenes())

    async def scene_summary(self, name: str) -> SceneSummary:
        """One scene's summary (GET /v1/scenes/{name})."""
        return await self._call(_api.scene_summary(name))

    async def create_scene(self, name: str, max_triangles: Optional[int] = None,
                           max_vertices: Optional[int] = None,
                           max_instances: Optional[int] = None,
                           max_texture_mb: Optional[int] = None) -> SceneSummary:
        """Creates or finds the named scene (PUT /v1/scenes/{name}), as Client.create_scene."""
        return await self._call(_api.create_scene(name, {
            "max_triangles": max_triangles, "max_vertices": max_vertices,
            "max_instances": max_instances, "max_texture_mb": max_texture_mb}))

    async def delete_scene(self, name: str) -> None:
        """Deletes the named scene (DELETE /v1/scenes/{name})."""
        await self._call(_api.delete_scene(name))

    def for_scene(self, name: Optional[str]) -> "AsyncClient":
        """A new AsyncClient on the same server and token, working on scene `name`."""
        return AsyncClient(self.url, self._token, self._timeout, self._max_connections,
                           scene=name)

    # -- endpoints: the same as Client's (see its docstrings) ----------------------------------

    async def edit(self, edits: Iterable[Dict[str, Any]], if_match: IfMatch = None,
                   message: Optional[str] = None) -> int:
        """Applies a batch (POST /v1/edits), with `message` kept in the history; returns the
        new scene version."""
        return await self._call(_api.edit(edits, if_match, message))

    async def undo(self, if_match: IfMatch = None) -> UndoResult:
        """Takes back the newest batch on the undo stack (POST /v1/undo), as Client.undo."""
        return await self._call(_api.undo(False, if_match))

    async def redo(self, if_match: IfMatch = None) -> UndoResult:
        """Applies again the batch the newest undo took back (POST /v1/redo), as Client.redo."""
        return await self._call(_api.undo(True, if_match))

    async def history(self, limit: Optional[int] = None,
                      cursor: Optional[str] = None) -> History:
        """One page of the scene's versions, newest first (GET /v1/history), as Client.history."""
        return await self._call(_api.history(limit, cursor))

    async def history_entries(self, page_size: int = 1000) -> AsyncIterator[HistoryEntry]:
        """Every version the history holds, newest first, following cursors (`async for`)."""
        cursor: Optional[str] = None
        while True:
            page = await self.history(page_size, cursor)
            for entry in page.entries:
                yield entry
            if page.next_cursor is None:
                return
            cursor = page.next_cursor

    async def import_asset(self, path: str, prefix: Optional[str] = None,
                           fmt: Optional[str] = None, instance: bool = True,
                           parent: Optional[str] = None,
                           if_match: IfMatch = None) -> ImportResult:
        """Imports a model file (POST /v1/assets); the files are read in a worker thread."""
        build = functools.partial(_api.import_asset, path, prefix, fmt, instance, parent,
                                  if_match)
        call = await asyncio.get_running_loop().run_in_executor(None, build)
        return await self._call(call)

    async def assets(self, *, at_version: Optional[int] = None) -> List[Asset]:
        """Every imported asset (GET /v1/assets), as Client.assets."""
        return await self._call(_api.assets(at_version))

    async def asset(self, id: str, *, at_version: Optional[int] = None) -> Asset:
        """One asset with the ids it owns (GET /v1/assets/{id}), as Client.asset."""
        return await self._call(_api.asset(id, at_version))

    async def delete_asset(self, id: str, if_match: IfMatch = None) -> AssetDeleteResult:
        """Removes everything an asset owns (DELETE /v1/assets/{id}), as Client.delete_asset."""
        return await self._call(_api.delete_asset(id, if_match))

    async def reimport_asset(self, id: str, path: str, fmt: Optional[str] = None,
                             instance: bool = True, parent: Optional[str] = None,
                             if_match: IfMatch = None) -> ReimportResult:
        """Imports a file in place of asset `id` (PUT /v1/assets/{id}), as
        Client.reimport_asset; the files are read in a worker thread."""
        build = functools.partial(_api.reimport_asset, id, path, fmt, instance, parent,
                                  if_match)
        call = await asyncio.get_running_loop().run_in_executor(None, build)
        return await self._call(call)

    async def commit(self) -> RebuildReport:
        """Runs a commit (POST /v1/commit); returns its rebuild report."""
        return await self._call(_api.commit())

    async def plan(self) -> RebuildReport:
        """What the next commit would do (GET /v1/plan)."""
        return await self._call(_api.plan())

    async def render_frame(self, width: int = 640, height: int = 360, fmt: str = "png",
                           **opts: Any) -> Frame:
        """Renders a frame (POST /v1/render): the encoded image and its RenderInfo."""
        frame = await self._call(_api.render(width, height, fmt, opts))
        self.last_render = frame.info
        return frame

    async def render(self, width: int = 640, height: int = 360, fmt: str = "png",
                     **opts: Any) -> bytes:
        """render_frame(), returning the encoded image only; `last_render` holds the rest."""
        return (await self.render_frame(width, height, fmt, **opts)).image

    async def render_array(self, width: int = 640, height: int = 360, **opts: Any) -> Any:
        """Client.render_array: uint8 for fmt="png" (the default), linear float32 for "npz"."""
        fmt = opts.pop("fmt", "png")
        if fmt == "npz":
            return (await self.render_arrays(width, height, **opts))["beauty"]
        if fmt != "png":
            raise ValueError("render_array reads png or npz frames; for the AOVs of an EXR "
                             "frame as arrays, use render_arrays()")
        return png_to_array(await self.render(width, height, "png", **opts))

    async def render_arrays(self, width: int = 640, height: int = 360,
                            **opts: Any) -> FrameArrays:
        """Client.render_arrays: the frame and its AOVs as numpy arrays (format npz)."""
        return frame_arrays(await self.render_frame(width, height, "npz", **opts))

    async def stats(self) -> Dict[str, Any]:
        """Counters, the last report and memory (GET /v1/stats)."""
        return await self._call(_api.stats())

    async def scene(self, kind: Optional[str] = None, id: Optional[str] = None, *,
                    at_version: Optional[int] = None) -> Dict[str, Any]:
        """The scene summary, or one object's document (GET /v1/scene[/{kind}/{id}]); with
        `at_version`, as it was at that version."""
        return await self._call(_api.scene(kind, id, at_version))

    async def page(self, collection: str, limit: int = 100, cursor: Optional[str] = None, *,
                   group: Optional[str] = None, mesh: Optional[str] = None,
                   visible: Optional[bool] = None, parent: Optional[str] = None) -> Page:
        """One page of a listing (GET /v1/scene/{collection}), as Client.page."""
        return await self._call(_api.page(collection, limit, cursor, group,
                                          {"mesh": mesh, "visible": visible, "parent": parent}))

    async def _walk(self, collection: str, page_size: int, group: Optional[str] = None,
                    **filters: Any) -> AsyncIterator[Dict[str, Any]]:
        cursor: Optional[str] = None
        while True:
            page = await self.page(collection, page_size, cursor, group=group, **filters)
            for item in page.items:
                yield item
            if page.next_cursor is None:
                return
            cursor = page.next_cursor

    def instances(self, page_size: int = 1000, mesh: Optional[str] = None,
                  visible: Optional[bool] = None,
                  parent: Optional[str] = None) -> AsyncIterator[Dict[str, Any]]:
        """Every instance, following cursors (`async for`); filters as Client.instances."""
        return self._walk("instances", page_size, mesh=mesh, visible=visible, parent=parent)

    def groups(self, page_size: int = 1000,
               parent: Optional[str] = None) -> AsyncIterator[Dict[str, Any]]:
        """Every group, following cursors (`async for`)."""
        return self._walk("groups", page_size, parent=parent)

    def children(self, group: str, page_size: int = 1000) -> AsyncIterator[Dict[str, Any]]:
        """A group's direct children: its groups, then its instances (`async for`)."""
        return self._walk("children", page_size, group=group)

    async def tree(self, depth: int = 1, group: Optional[str] = None,
                   max_nodes: Optional[int] = None) -> Dict[str, Any]:
        """The scene graph nested `depth` levels deep (GET /v1/scene/tree)."""
        return await self._call(_api.tree(depth, group, max_nodes))

    def meshes(self, page_size: int = 1000) -> AsyncIterator[Dict[str, Any]]:
        """Every mesh, following cursors (`async for`)."""
        return self._walk("meshes", page_size)

    def materials(self, page_size: int = 1000) -> AsyncIterator[Dict[str, Any]]:
        """Every material, following cursors (`async for`)."""
        return self._walk("materials", page_size)

    def textures(self, page_size: int = 1000) -> AsyncIterator[Dict[str, Any]]:
        """Every texture, following cursors (`async for`)."""
        return self._walk("textures", page_size)

    def lights(self, page_size: int = 1000) -> AsyncIterator[Dict[str, Any]]:
        """Every light, following cursors (`async for`)."""
        return self._walk("lights", page_size)

    async def pick(self, x: int, y: int, width: int, height: int,
                   camera: Optional[Dict[str, Any]] = None,
                   time: Optional[float] = None) -> Optional[Hit]:
        """What lies under pixel (x, y) of a width x height frame (POST /v1/pick), or None."""
        return (await self.pick_many([(x, y)], width, height, camera, time))[0]

    async def pick_many(self, pixels: Iterable[Tuple[int, int]], width: int, height: int,
                        camera: Optional[Dict[str, Any]] = None,
                        time: Optional[float] = None) -> List[Optional[Hit]]:
        """pick() for many pixels at once (at most 10000), all at one version."""
        return await self._call(_api.pick_many(pixels, width, height, camera, time))

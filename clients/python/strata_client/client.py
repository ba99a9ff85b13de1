"""The HTTP client: one keep-alive connection, JSON in and out, problem documents as exceptions."""

import http.client
import json
import os
import urllib.parse
from typing import Any, Dict, Iterable, Iterator, List, Optional, Tuple, Union

from strata_client.asset_pack import pack_asset
from strata_client.png import decode_png


class ProblemError(Exception):
    """A request Strata refused, carrying its problem document (RFC 9457, protocol/README.md).

    Attributes: status (HTTP status), title, detail, edit_index (the offending edit's position
    in the batch, or None), pointer (a JSON pointer into the request, or None), type (the
    problem type URI), etag (the ETag header, e.g. the current version after a 412), body (the
    whole document as a dict, or the raw text for answers that are not problem documents).
    """

    def __init__(self, status: int, title: str, detail: str = "", edit_index: Optional[int] = None,
                 pointer: Optional[str] = None, type: str = "", etag: Optional[str] = None,
                 body: Any = None):
        self.status = status
        self.title = title
        self.detail = detail
        self.edit_index = edit_index
        self.pointer = pointer
        self.type = type
        self.etag = etag
        self.body = body
        super().__init__(str(self))

    def __str__(self) -> str:
        text = f"{self.status} {self.title}"
        if self.detail:
            text += f": {self.detail}"
        return text


class RenderInfo:
    """What the last render answered besides the image: the version the frame shows, the
    one-line summary of its commit (X-Strata-Rebuild), that commit's full rebuild report
    (X-Strata-Report, a dict; None if absent) and the content type."""

    def __init__(self, version: Optional[int], rebuild: str, content_type: str,
                 report: Optional[Dict[str, Any]] = None):
        self.version = version
        self.rebuild = rebuild
        self.content_type = content_type
        self.report = report

    def __repr__(self) -> str:
        return f"RenderInfo(version={self.version!r}, rebuild={self.rebuild!r})"


def _etag_version(tag: Optional[str]) -> Optional[int]:
    if not tag:
        return None
    tag = tag.strip()
    if len(tag) >= 2 and tag[0] == '"' and tag[-1] == '"':
        tag = tag[1:-1]
    return int(tag) if tag.isdigit() else None


class Client:
    """A connection to strata-server.

    `url` is scheme://host[:port] (http or https); `token` the bearer token of a server started
    with --token-file. One HTTP/1.1 connection is kept alive across requests and reopened when
    the server has closed it (an idle keep-alive connection, a restart). Usable as a context
    manager; close() releases the connection. Not thread-safe: use one Client per thread.
    """

    def __init__(self, url: str = "http://127.0.0.1:7070", token: Optional[str] = None,
                 timeout: float = 300.0):
        parts = urllib.parse.urlsplit(url)
        if parts.scheme not in ("http", "https") or not parts.hostname:
            raise ValueError(f"server URL {url!r} must be http://host[:port] or https://host[:port]")
        if parts.path not in ("", "/") or parts.query or parts.fragment:
            raise ValueError(f"server URL {url!r} must not have a path")
        self.url = f"{parts.scheme}://{parts.netloc}"
        self._https = parts.scheme == "https"
        self._host = parts.hostname
        self._port = parts.port
        self._token = token
        self._timeout = timeout
        self._conn: Optional[http.client.HTTPConnection] = None
        self.last_render: Optional[RenderInfo] = None

    # -- connection -----------------------------------------------------------------------------

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Closes the connection (a later request opens a new one)."""
        if self._conn is not None:
            self._conn.close()
            self._conn = None

    def _connection(self) -> http.client.HTTPConnection:
        if self._conn is None:
            cls = http.client.HTTPSConnection if self._https else http.client.HTTPConnection
            self._conn = cls(self._host, self._port, timeout=self._timeout)
        return self._conn

    def _request(self, method: str, path: str, body: Optional[bytes] = None,
                 headers: Optional[Dict[str, str]] = None):
        """Sends one request; returns (status, headers, body bytes).

        A connection the server closed while idle is reopened and the request sent again once:
        that failure happens before the server reads the request, so nothing is applied twice.
        """
        send_headers = {"Accept": "application/json"}
        if body is not None:
            send_headers["Content-Type"] = "application/json"
        if self._token:
            send_headers["Authorization"] = f"Bearer {self._token}"
        send_headers.update(headers or {})
        for attempt in (0, 1):
            reused = self._conn is not None
            conn = self._connection()
            try:
                conn.request(method, path, body=body, headers=send_headers)
                response = conn.getresponse()
                data = response.read()
            except (http.client.RemoteDisconnected, BrokenPipeError, ConnectionResetError,
                    http.client.CannotSendRequest):
                self.close()
                if reused and attempt == 0:
                    continue
                raise
            except (OSError, http.client.HTTPException):
                self.close()
                raise
            if response.getheader("Connection", "").lower() == "close":
                self.close()
            return response.status, response, data
        raise AssertionError("unreachable")

    def _json(self, method: str, path: str, body: Any = None,
              headers: Optional[Dict[str, str]] = None) -> Dict[str, Any]:
        payload = None if body is None else json.dumps(body).encode("utf-8")
        status, response, data = self._request(method, path, payload, headers)
        if not 200 <= status < 300:
            raise self._problem(status, response, data)
        return json.loads(data)

    @staticmethod
    def _problem(status: int, response, data: bytes) -> ProblemError:
        etag = response.getheader("ETag")
        try:
            doc = json.loads(data)
        except ValueError:
            doc = None
        if isinstance(doc, dict) and "title" in doc:
            return ProblemError(doc.get("status", status), doc.get("title", ""),
                                doc.get("detail", ""), doc.get("edit_index"), doc.get("pointer"),
                                doc.get("type", ""), etag, doc)
        text = data[:200].decode("utf-8", "replace")
        return ProblemError(status, f"HTTP {status}", text, etag=etag, body=text)

    # -- endpoints ------------------------------------------------------------------------------

    def edit(self, edits: Iterable[Dict[str, Any]], if_match: Union[int, str, None] = None) -> int:
        """Applies a batch (POST /v1/edits); returns the new scene version.

        `if_match`: apply only at this version (an int, or an entity tag such as '"7"' or '*');
        otherwise ProblemError with status 412 and the current version in `etag`.
        """
        headers = {}
        if if_match is not None:
            headers["If-Match"] = f'"{if_match}"' if isinstance(if_match, int) else if_match
        return self._json("POST", "/v1/edits", {"edits": list(edits)}, headers)["version"]

    def import_asset(self, path: str, prefix: Optional[str] = None, fmt: Optional[str] = None,
                     instance: bool = True, parent: Optional[str] = None,
                     if_match: Union[int, str, None] = None) -> Dict[str, Any]:
        """Imports a glTF (.glb or .gltf), OBJ or PLY file (POST /v1/assets) as one batch;
        returns the answer: {"version", "applied", "format", "textures", "meshes", "materials",
        "groups", "instances", "warnings"} (and "model" when it went as an archive).

        An .obj that names MTL files (and the map_Kd images they name), or a .gltf with external
        buffers or images, is sent as a tar archive of them all, built in memory (asset_pack.py);
        a file they name that is missing locally raises FileNotFoundError before anything is
        sent. With `fmt` given, the file is sent alone.

        `prefix` starts every id it creates (default: the file name's stem); `fmt` is glb, gltf,
        obj or ply (default: from the extension); `instance=False` creates meshes and materials
        only; `parent` names the group the asset's own group joins (default: the root). A file Strata cannot read raises ProblemError 422 whose body names the "file" and
        the "element" at fault.
        """
        if fmt is None:
            packed = pack_asset(path)
            data = packed.data
        else:
            with open(path, "rb") as f:
                data = f.read()
            packed = None
        query = {"name": os.path.basename(path)}
        if packed is not None and packed.archive:
            query = {"name": os.path.splitext(os.path.basename(path))[0] + ".tar", "format": "tar"}
        if prefix is not None:
            query["prefix"] = prefix
        if fmt is not None:
            query["format"] = fmt
        if not instance:
            query["instance"] = "false"
        if parent is not None:
            query["parent"] = parent
        headers = {"Content-Type": "application/octet-stream"}
        if if_match is not None:
            headers["If-Match"] = f'"{if_match}"' if isinstance(if_match, int) else if_match
        target = "/v1/assets?" + urllib.parse.urlencode(query, quote_via=urllib.parse.quote)
        status, response, body = self._request("POST", target, data, headers)
        if not 200 <= status < 300:
            raise self._problem(status, response, body)
        return json.loads(body)

    def commit(self) -> Dict[str, Any]:
        """Runs a commit (POST /v1/commit); returns its rebuild report."""
        status, response, data = self._request("POST", "/v1/commit", b"")
        if not 200 <= status < 300:
            raise self._problem(status, response, data)
        return json.loads(data)

    def plan(self) -> Dict[str, Any]:
        """What the next commit would do (GET /v1/plan), as a report with "planned": true."""
        return self._json("GET", "/v1/plan")

    def render(self, width: int = 640, height: int = 360, fmt: str = "png", **opts: Any) -> bytes:
        """Renders a frame (POST /v1/render); returns the encoded image.

        Every other request member passes through `opts`: spp, aovs, compression, accumulate,
        exposure, filter ("none" or "atrous"), camera={"eye": [...], "target": [...], "up": [...],
        "fov_y_deg": ...}.
        `last_render` then holds the version the frame shows and its commit's summary.
        """
        body = {"width": width, "height": height, "format": fmt}
        body.update(opts)
        status, response, data = self._request("POST", "/v1/render",
                                               json.dumps(body).encode("utf-8"))
        if not 200 <= status < 300:
            raise self._problem(status, response, data)
        report_text = response.getheader("X-Strata-Report")
        self.last_render = RenderInfo(_etag_version(response.getheader("ETag")),
                                      response.getheader("X-Strata-Rebuild", ""),
                                      response.getheader("Content-Type", ""),
                                      json.loads(report_text) if report_text else None)
        return data

    def render_array(self, width: int = 640, height: int = 360, **opts: Any):
        """Renders a PNG frame and returns it as a numpy array of shape (height, width, channels),
        dtype uint8. numpy is imported here, only when this is called. EXR is not decoded here:
        use render(fmt="exr") and an EXR reader."""
        fmt = opts.pop("fmt", "png")
        if fmt != "png":
            raise NotImplementedError("render_array decodes PNG only; use render(fmt='exr') "
                                      "and an EXR reader such as OpenEXR")
        import numpy as np  # lazily: the rest of the client needs only the standard library

        w, h, channels, pixels = decode_png(self.render(width, height, "png", **opts))
        return np.frombuffer(pixels, dtype=np.uint8).reshape(h, w, channels)

    def stats(self) -> Dict[str, Any]:
        """Counters, the last report and memory (GET /v1/stats)."""
        return self._json("GET", "/v1/stats")

    def scene(self, kind: Optional[str] = None, id: Optional[str] = None) -> Dict[str, Any]:
        """The scene summary (GET /v1/scene), or one object's state with kind "meshes",
        "instances", "materials", "groups", "lights" or "textures" and its id (GET /v1/scene/{kind}/{id})."""
        if kind is None:
            return self._json("GET", "/v1/scene")
        if kind not in ("meshes", "instances", "materials", "groups", "lights",
                        "textures") or not id:
            raise ValueError("scene(kind, id): kind is 'meshes', 'instances', 'materials', "
                             "'groups', 'lights' or 'textures'")
        return self._json("GET", f"/v1/scene/{kind}/{urllib.parse.quote(id, safe='')}")

    def _list(self, collection: str, page_size: int, **filters: Any) -> Iterator[Dict[str, Any]]:
        query = {"limit": str(page_size)}
        for key, value in filters.items():
            if value is not None:
                query[key] = ("true" if value else "false") if isinstance(value, bool) else value
        while True:
            page = self._json("GET", f"/v1/scene/{collection}?{urllib.parse.urlencode(query)}")
            yield from page["items"]
            if page.get("next_cursor") is None:
                return
            query["cursor"] = page["next_cursor"]

    def instances(self, page_size: int = 1000, mesh: Optional[str] = None,
                  visible: Optional[bool] = None,
                  parent: Optional[str] = None) -> Iterator[Dict[str, Any]]:
        """Every instance (GET /v1/scene/instances, following cursors page by page), optionally
        only those of one mesh, only (in)visible ones, or only the children of group `parent`
        ("" for the root). Each item is the document scene("instances", id) returns."""
        return self._list("instances", page_size, mesh=mesh, visible=visible, parent=parent)

    def groups(self, page_size: int = 1000,
               parent: Optional[str] = None) -> Iterator[Dict[str, Any]]:
        """Every group (GET /v1/scene/groups, following cursors), optionally only the children
        of group `parent` ("" for the root)."""
        return self._list("groups", page_size, parent=parent)

    def children(self, group: str, page_size: int = 1000) -> Iterator[Dict[str, Any]]:
        """A group's direct children (GET /v1/scene/groups/{id}/children, following cursors):
        its groups, then its instances, each document with "kind" "group" or "instance"."""
        return self._list(f"groups/{urllib.parse.quote(group, safe='')}/children", page_size)

    def tree(self, depth: int = 1, group: Optional[str] = None,
             max_nodes: Optional[int] = None) -> Dict[str, Any]:
        """The scene graph nested `depth` levels deep from the root or from `group`
        (GET /v1/scene/tree): {"groups": [...], "instances": [...], "truncated": bool, ...}."""
        query: Dict[str, str] = {"depth": str(depth)}
        if group is not None:
            query["group"] = group
        if max_nodes is not None:
            query["max_nodes"] = str(max_nodes)
        return self._json("GET", f"/v1/scene/tree?{urllib.parse.urlencode(query)}")

    def meshes(self, page_size: int = 1000) -> Iterator[Dict[str, Any]]:
        """Every mesh (GET /v1/scene/meshes, following cursors)."""
        return self._list("meshes", page_size)

    def materials(self, page_size: int = 1000) -> Iterator[Dict[str, Any]]:
        """Every material (GET /v1/scene/materials, following cursors)."""
        return self._list("materials", page_size)

    def textures(self, page_size: int = 1000) -> Iterator[Dict[str, Any]]:
        """Every texture (GET /v1/scene/textures, following cursors): id, width, height, format,
        encoded_bytes, decoded_bytes."""
        return self._list("textures", page_size)
    def lights(self, page_size: int = 1000) -> Iterator[Dict[str, Any]]:
        """Every point, spot and rect light (GET /v1/scene/lights, following cursors)."""
        return self._list("lights", page_size)

    def pick(self, x: int, y: int, width: int, height: int,
             camera: Optional[Dict[str, Any]] = None) -> Optional[Dict[str, Any]]:
        """What lies under pixel (x, y) of a width x height frame (POST /v1/pick): a dict with
        instance, mesh, group_path, primitive, distance, position, normal and user_id, or
        None."""
        return self.pick_many([(x, y)], width, height, camera)[0]

    def pick_many(self, pixels: Iterable[Tuple[int, int]], width: int, height: int,
                  camera: Optional[Dict[str, Any]] = None) -> List[Optional[Dict[str, Any]]]:
        """pick() for many pixels at once (at most 10000), one ray each, all at one version."""
        body: Dict[str, Any] = {"width": width, "height": height,
                                "pixels": [[int(px), int(py)] for px, py in pixels]}
        if camera is not None:
            body["camera"] = camera
        return self._json("POST", "/v1/pick", body)["hits"]

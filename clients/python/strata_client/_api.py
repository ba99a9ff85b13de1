"""The endpoints, without I/O: each function builds a request and says how to read its answer.

Client (blocking, http.client) and AsyncClient (asyncio) send the same Call objects, so both
speak the protocol the same way and give the same typed results.
"""

import datetime
import json
import os
import re
import urllib.parse
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, Generic, Iterable, List, Optional, Tuple, TypeVar, Union

from strata_client._version import __version__
from strata_client.asset_pack import pack_asset
from strata_client.errors import etag_version, problem_error
from strata_client.results import (Asset, AssetDeleteResult, Frame, History, Hit, ImportResult,
                                   Page, RebuildReport, ReimportResult, RenderInfo, SceneSummary,
                                   UndoResult)

T = TypeVar("T")

USER_AGENT = f"strata-client-python/{__version__}"

SCENE_KINDS = ("meshes", "instances", "materials", "groups", "lights", "textures")

#: An If-Match precondition: a version, or an entity tag such as '"7"' or '*'.
IfMatch = Union[int, str, None]


@dataclass
class Request:
    """One HTTP request; `target` is the path and query."""

    method: str
    target: str
    body: Optional[bytes] = None
    headers: Dict[str, str] = field(default_factory=dict)


@dataclass
class Response:
    """One HTTP answer, header names in lower case."""

    status: int
    headers: Dict[str, str]
    body: bytes


@dataclass
class Call(Generic[T]):
    """A request and how to read a 2xx answer to it."""

    request: Request
    read: Callable[[Response], T]

    def result(self, response: Response) -> T:
        """The typed result, or the ProblemError the answer carries."""
        if not 200 <= response.status < 300:
            raise problem_error(response.status, response.headers, response.body)
        return self.read(response)


@dataclass(frozen=True)
class Endpoint:
    """Where a client connects: scheme, host and port of a server URL that has no path."""

    scheme: str
    host: str
    port: Optional[int]
    netloc: str

    @property
    def url(self) -> str:
        return f"{self.scheme}://{self.netloc}"

    @property
    def https(self) -> bool:
        return self.scheme == "https"


def parse_url(url: str) -> Endpoint:
    """Checks a server URL: scheme://host[:port], http or https, no path, query or fragment."""
    parts = urllib.parse.urlsplit(url)
    if parts.scheme not in ("http", "https") or not parts.hostname:
        raise ValueError(f"server URL {url!r} must be http://host[:port] or https://host[:port]")
    if parts.path not in ("", "/") or parts.query or parts.fragment:
        raise ValueError(f"server URL {url!r} must not have a path")
    return Endpoint(parts.scheme, parts.hostname, parts.port, parts.netloc)


def request_headers(request: Request, token: Optional[str]) -> Dict[str, str]:
    """The headers every request carries, then the request's own."""
    headers = {"Accept": "application/json", "User-Agent": USER_AGENT}
    if request.body is not None:
        headers["Content-Type"] = "application/json"
    if token:
        headers["Authorization"] = f"Bearer {token}"
    headers.update(request.headers)
    return headers


def _json_body(value: Any) -> bytes:
    return json.dumps(value).encode("utf-8")


def _read_json(response: Response) -> Any:
    return json.loads(response.body)


def _if_match(if_match: IfMatch) -> Dict[str, str]:
    if if_match is None:
        return {}
    return {"If-Match": f'"{if_match}"' if isinstance(if_match, int) else if_match}


def _quote(segment: str) -> str:
    return urllib.parse.quote(segment, safe="")


_SCENE_NAME = re.compile(r"[a-z0-9][a-z0-9_-]{0,63}")


def check_scene_name(name: str) -> str:
    """`name` when it is a scene name (1 to 64 of a-z, 0-9, '-' and '_', starting with a letter
    or digit); ValueError otherwise."""
    if not isinstance(name, str) or not _SCENE_NAME.fullmatch(name):
        raise ValueError(f"{name!r} is not a scene name: 1 to 64 characters, lowercase letters, "
                         "digits, '-' and '_', starting with a letter or digit")
    return name


def in_scene(call: "Call[T]", scene: Optional[str]) -> "Call[T]":
    """`call` sent to the named scene `scene` (/v1/X as /v1/scenes/{scene}/X); unchanged for
    None and for the directory of scenes itself."""
    target = call.request.target
    if scene is None or not target.startswith("/v1/") or target.startswith("/v1/scenes"):
        return call
    request = Request(call.request.method, f"/v1/scenes/{scene}/" + target[4:],
                      call.request.body, call.request.headers)
    return Call(request, call.read)


# -- endpoints --------------------------------------------------------------------------------

def scenes() -> Call[List[SceneSummary]]:
    return Call(Request("GET", "/v1/scenes"),
                lambda r: [SceneSummary.from_json(s) for s in _read_json(r)["scenes"]])


def scene_summary(name: str) -> Call[SceneSummary]:
    return Call(Request("GET", f"/v1/scenes/{check_scene_name(name)}"),
                lambda r: SceneSummary.from_json(_read_json(r)))


def create_scene(name: str, budget: Dict[str, Optional[int]]) -> Call[SceneSummary]:
    limits = {k: v for k, v in budget.items() if v is not None}
    body = _json_body({"budget": limits}) if limits else b""
    return Call(Request("PUT", f"/v1/scenes/{check_scene_name(name)}", body),
                lambda r: SceneSummary.from_json(_read_json(r)))


def delete_scene(name: str) -> Call[None]:
    return Call(Request("DELETE", f"/v1/scenes/{check_scene_name(name)}"), lambda r: None)


def edit(edits: Iterable[Dict[str, Any]], if_match: IfMatch = None,
         message: Optional[str] = None) -> Call[int]:
    batch: Dict[str, Any] = {"edits": list(edits)}
    if message is not None:
        batch["message"] = message
    return Call(Request("POST", "/v1/edits", _json_body(batch), _if_match(if_match)),
                lambda r: int(_read_json(r)["version"]))


def undo(redo: bool, if_match: IfMatch = None) -> Call[UndoResult]:
    """POST /v1/undo, or POST /v1/redo with `redo`."""
    return Call(Request("POST", "/v1/redo" if redo else "/v1/undo", b"", _if_match(if_match)),
                lambda r: UndoResult.from_json(_read_json(r)))


def history(limit: Optional[int], cursor: Optional[str]) -> Call[History]:
    query = {}
    if limit is not None:
        query["limit"] = str(limit)
    if cursor is not None:
        query["cursor"] = cursor
    target = "/v1/history" + ("?" + urllib.parse.urlencode(query) if query else "")
    return Call(Request("GET", target), lambda r: History.from_json(_read_json(r)))


def _upload(path: str, fmt: Optional[str], instance: bool, parent: Optional[str],
            if_match: IfMatch) -> Tuple[bytes, Dict[str, str], Dict[str, str]]:
    """The body, query and headers of an upload of `path` (and its side files)."""
    archive = False
    if fmt is None:
        packed = pack_asset(path)
        data, archive = packed.data, packed.archive
    else:
        with open(path, "rb") as f:
            data = f.read()
    query = {"name": os.path.basename(path)}
    if archive:
        query = {"name": os.path.splitext(os.path.basename(path))[0] + ".tar", "format": "tar"}
    if fmt is not None:
        query["format"] = fmt
    if not instance:
        query["instance"] = "false"
    if parent is not None:
        query["parent"] = parent
    headers = {"Content-Type": "application/octet-stream"}
    headers.update(_if_match(if_match))
    return data, query, headers


def import_asset(path: str, prefix: Optional[str] = None, fmt: Optional[str] = None,
                 instance: bool = True, parent: Optional[str] = None,
                 if_match: IfMatch = None) -> Call[ImportResult]:
    """Reads the file (and its side files) now: FileNotFoundError or ValueError before sending."""
    data, query, headers = _upload(path, fmt, instance, parent, if_match)
    if prefix is not None:
        query["prefix"] = prefix
    target = "/v1/assets?" + urllib.parse.urlencode(query, quote_via=urllib.parse.quote)
    return Call(Request("POST", target, data, headers),
                lambda r: ImportResult.from_json(_read_json(r)))


def reimport_asset(id: str, path: str, fmt: Optional[str] = None, instance: bool = True,
                   parent: Optional[str] = None,
                   if_match: IfMatch = None) -> Call[ReimportResult]:
    """PUT /v1/assets/{id}; reads the file now, as import_asset."""
    data, query, headers = _upload(path, fmt, instance, parent, if_match)
    target = (f"/v1/assets/{_quote(id)}?" +
              urllib.parse.urlencode(query, quote_via=urllib.parse.quote))
    return Call(Request("PUT", target, data, headers),
                lambda r: ReimportResult.from_json(_read_json(r)))


def assets(at_version: Optional[int] = None) -> Call[List[Asset]]:
    return Call(Request("GET", _at_version("/v1/assets", at_version)),
                lambda r: [Asset.from_json(a) for a in _read_json(r)["assets"]])


def asset(id: str, at_version: Optional[int] = None) -> Call[Asset]:
    return Call(Request("GET", _at_version(f"/v1/assets/{_quote(id)}", at_version)),
                lambda r: Asset.from_json(_read_json(r)))


def delete_asset(id: str, if_match: IfMatch = None) -> Call[AssetDeleteResult]:
    return Call(Request("DELETE", f"/v1/assets/{_quote(id)}", None, _if_match(if_match)),
                lambda r: AssetDeleteResult.from_json(_read_json(r)))


def commit() -> Call[RebuildReport]:
    return Call(Request("POST", "/v1/commit", b""),
                lambda r: RebuildReport.from_json(_read_json(r)))


def plan() -> Call[RebuildReport]:
    return Call(Request("GET", "/v1/plan"), lambda r: RebuildReport.from_json(_read_json(r)))


def _render_info(response: Response) -> RenderInfo:
    report = response.headers.get("x-strata-report")
    samples = response.headers.get("x-strata-samples", "")
    return RenderInfo(etag_version(response.headers.get("etag")),
                      response.headers.get("x-strata-rebuild", ""),
                      response.headers.get("content-type", ""),
                      RebuildReport.from_json(json.loads(report)) if report else None,
                      int(samples) if samples.isdigit() else None,
                      response.headers.get("x-strata-split"))


def _at_version(path: str, at_version: "Union[int, datetime.datetime, None]") -> str:
    """`path` asking for the scene as it was at `at_version`: a version, or a time-zone aware
    datetime (at_time: the newest version made at or before it); None: the live scene."""
    if at_version is None:
        return path
    if isinstance(at_version, datetime.datetime):
        if at_version.tzinfo is None:
            raise ValueError("at_version as a time needs a time zone (datetime.timezone.utc)")
        stamp = at_version.astimezone(datetime.timezone.utc).isoformat(timespec="milliseconds")
        return f"{path}?at_time={urllib.parse.quote(stamp.replace('+00:00', 'Z'))}"
    if isinstance(at_version, bool) or not isinstance(at_version, int) or at_version < 0:
        raise ValueError("at_version is a scene version (a whole number >= 0) or a datetime")
    return f"{path}?at_version={at_version}"


def render(width: int, height: int, fmt: str, opts: Dict[str, Any]) -> Call[Frame]:
    opts = dict(opts)
    at_version = opts.pop("at_version", None)
    body: Dict[str, Any] = {"width": width, "height": height, "format": fmt}
    body.update(opts)
    return Call(Request("POST", _at_version("/v1/render", at_version), _json_body(body)),
                lambda r: Frame(r.body, _render_info(r)))


def stats() -> Call[Dict[str, Any]]:
    return Call(Request("GET", "/v1/stats"), _read_json)


def scene(kind: Optional[str], id: Optional[str],
          at_version: Optional[int] = None) -> Call[Dict[str, Any]]:
    if kind is None:
        return Call(Request("GET", _at_version("/v1/scene", at_version)), _read_json)
    if kind not in SCENE_KINDS or not id:
        raise ValueError("scene(kind, id): kind is one of " + ", ".join(map(repr, SCENE_KINDS))
                         + " and id is not empty")
    return Call(Request("GET", _at_version(f"/v1/scene/{kind}/{_quote(id)}", at_version)),
                _read_json)


def page(collection: str, limit: int, cursor: Optional[str], group: Optional[str],
         filters: Dict[str, Any]) -> Call[Page]:
    """A page of a collection, or of a group's children (collection "children", `group`)."""
    if collection == "children":
        if not group:
            raise ValueError("page('children', group=...): name the group")
        path = f"/v1/scene/groups/{_quote(group)}/children"
    elif collection in SCENE_KINDS:
        path = f"/v1/scene/{collection}"
    else:
        raise ValueError("page(collection): collection is one of "
                         + ", ".join(map(repr, SCENE_KINDS + ("children",))))
    query = {"limit": str(limit)}
    for key, value in filters.items():
        if value is not None:
            query[key] = ("true" if value else "false") if isinstance(value, bool) else str(value)
    if cursor is not None:
        query["cursor"] = cursor
    return Call(Request("GET", f"{path}?{urllib.parse.urlencode(query)}"),
                lambda r: Page.from_json(_read_json(r)))


def tree(depth: int, group: Optional[str], max_nodes: Optional[int]) -> Call[Dict[str, Any]]:
    query = {"depth": str(depth)}
    if group is not None:
        query["group"] = group
    if max_nodes is not None:
        query["max_nodes"] = str(max_nodes)
    return Call(Request("GET", f"/v1/scene/tree?{urllib.parse.urlencode(query)}"), _read_json)


def _hits(response: Response) -> List[Optional[Hit]]:
    return [None if h is None else Hit.from_json(h) for h in _read_json(response)["hits"]]


def pick_many(pixels: Iterable[Tuple[int, int]], width: int, height: int,
              camera: Optional[Dict[str, Any]],
              time: Optional[float] = None) -> Call[List[Optional[Hit]]]:
    body: Dict[str, Any] = {"width": width, "height": height,
                            "pixels": [[int(px), int(py)] for px, py in pixels]}
    if camera is not None:
        body["camera"] = camera
    if time is not None:
        body["time"] = float(time)
    return Call(Request("POST", "/v1/pick", _json_body(body)), _hits)

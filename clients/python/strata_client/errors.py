"""Problems as exceptions: every answer that is not 2xx raises a ProblemError, of the subclass
its status names, carrying the problem document (RFC 9457, protocol/README.md "Errors")."""

import json
from typing import Any, Dict, Mapping, Optional, Type

from strata_client.results import Problem

PROBLEM_TYPE_PREFIX = "https://strata.dev/problems/"


class ProblemError(Exception):
    """A request Strata refused, carrying its problem document.

    Attributes: status (HTTP status), title, detail, edit_index (the offending edit's position
    in the batch, or None), pointer (a JSON pointer into the request, or None), type (the
    problem type URI), etag (the ETag header, e.g. the current version after a 412), body (the
    whole document as a dict, or the raw text for answers that are not problem documents),
    problem (the document as a Problem dataclass), headers (the answer's headers, names in lower
    case). Catch a subclass (NotFoundError, VersionMismatchError, ...) to handle one status.
    """

    def __init__(self, status: int, title: str, detail: str = "",
                 edit_index: Optional[int] = None, pointer: Optional[str] = None,
                 type: str = "", etag: Optional[str] = None, body: Any = None,
                 headers: Optional[Mapping[str, str]] = None):
        self.status = status
        self.title = title
        self.detail = detail
        self.edit_index = edit_index
        self.pointer = pointer
        self.type = type
        self.etag = etag
        self.body = body
        self.headers: Dict[str, str] = dict(headers or {})
        extensions = {}
        if isinstance(body, dict):
            extensions = Problem.from_json(body, status).extensions
        self.problem = Problem(type or "about:blank", title, status, detail, edit_index, pointer,
                               extensions)
        super().__init__(str(self))

    def __str__(self) -> str:
        text = f"{self.status} {self.title}"
        if self.detail:
            text += f": {self.detail}"
        return text

    @property
    def problem_type(self) -> str:
        """The type's last part (`unknown-id`, `in-use`, ...; the table in protocol/README.md),
        or the whole URI when it is not one of Strata's."""
        if self.type.startswith(PROBLEM_TYPE_PREFIX):
            return self.type[len(PROBLEM_TYPE_PREFIX):]
        return self.type


class BadRequestError(ProblemError):
    """400: the request does not match the schema, or is not JSON."""


class UnauthorizedError(ProblemError):
    """401: a missing or wrong bearer token."""


class ForbiddenError(ProblemError):
    """403: with --tokens-file, the token's role in the scene does not allow the request."""


class NotFoundError(ProblemError):
    """404: an unknown route, or an unknown id in a URL."""


class VersionMismatchError(ProblemError):
    """412: If-Match named another version; `current_version` is the scene's version now."""

    @property
    def current_version(self) -> Optional[int]:
        return etag_version(self.etag)


class NothingToUndoError(ProblemError):
    """409: POST /v1/undo with no batch left to take back, or POST /v1/redo with nothing undone
    since the last edit; `current_version` is the scene's version now."""

    @property
    def current_version(self) -> Optional[int]:
        return etag_version(self.etag)


class SceneConflictError(ProblemError):
    """409 scene-conflict: deleting the default scene, creating a scene that exists with another
    budget, or one whose earlier namesake is still being deleted."""


class TooLargeError(ProblemError):
    """413: a body, array, frame or scene over one of the server's limits."""


class UnprocessableError(ProblemError):
    """422: the request matches the schema but cannot be applied (an unknown or duplicate id,
    an object in use, a value out of range, an asset Strata cannot read, ...)."""


class TooManyConnectionsError(ProblemError):
    """429: this client holds more connections than the server allows it."""


class UnavailableError(ProblemError):
    """503: shutting down, a render past its deadline, or a replica behind `min_version`."""


_BY_STATUS: Dict[int, Type[ProblemError]] = {
    400: BadRequestError,
    401: UnauthorizedError,
    403: ForbiddenError,
    404: NotFoundError,
    409: NothingToUndoError,
    412: VersionMismatchError,
    413: TooLargeError,
    422: UnprocessableError,
    429: TooManyConnectionsError,
    503: UnavailableError,
}


def etag_version(tag: Optional[str]) -> Optional[int]:
    """The scene version in an entity tag such as '"7"', or None."""
    if not tag:
        return None
    tag = tag.strip()
    if len(tag) >= 2 and tag[0] == '"' and tag[-1] == '"':
        tag = tag[1:-1]
    return int(tag) if tag.isdigit() else None


def problem_error(status: int, headers: Mapping[str, str], data: bytes) -> ProblemError:
    """The exception for an answer that is not 2xx (`headers` with names in lower case)."""
    cls = _BY_STATUS.get(status, ProblemError)
    etag = headers.get("etag")
    try:
        doc = json.loads(data)
    except ValueError:
        doc = None
    if isinstance(doc, dict) and str(doc.get("type", "")).endswith("/scene-conflict"):
        cls = SceneConflictError
    if isinstance(doc, dict) and "title" in doc:
        return cls(doc.get("status", status), doc.get("title", ""), doc.get("detail", ""),
                   doc.get("edit_index"), doc.get("pointer"), doc.get("type", ""), etag, doc,
                   headers)
    text = data[:200].decode("utf-8", "replace")
    return cls(status, f"HTTP {status}", text, etag=etag, body=text, headers=headers)

"""Starts a real strata-server on a free loopback port for tests, and stops it.

    with ServerProcess(binary) as server:
        ... server.url ...

The server is started with --port 0 and its log is read until it says which port it got, so
there is no race for a port; then, unless wait_ready=False, /readyz is polled until it answers 200
(a server with --data listens while it recovers its scene, answering 503 meanwhile).

Every answer a running ServerProcess gives an http.client connection of this process (urllib,
so tests/server/hostile.py's Server.call; the Python client; the readiness polls) is held to the
server's own OpenAPI description (GET /v1/openapi.json, fetched once per server): its status must
be documented for the route, its media type too, and a JSON body must match the documented
schema (Debian's python3-jsonschema, Draft 2020-12, which OpenAPI 3.1 uses). A mismatch raises
AssertionError where the answer arrives, failing the test. The asyncio client's answers
(strata_client._aio_http, when it is on the path) are checked the same way. Streams (/v1/stream, /v1/events) are
checked by status and media type only, their bodies left unread.
"""

import http.client
import io
import json
import os
import re
import signal
import subprocess
import tempfile
import time
import urllib.error
import urllib.parse
import urllib.request
from typing import Callable, Dict, List, Optional, Tuple

_LISTENING = re.compile(r"listening on (http://[0-9.]+:([0-9]+))")


class OpenApiCheck:
    """One OpenAPI document's routes and schemas, ready to check answers against."""

    _by_text: Dict[str, "OpenApiCheck"] = {}

    @classmethod
    def of(cls, text: str) -> "OpenApiCheck":
        """The checker of a document's text; servers of one binary share it (and its compiled
        schemas)."""
        if text not in cls._by_text:
            cls._by_text[text] = cls(json.loads(text))
        return cls._by_text[text]

    def __init__(self, document: dict):
        self.document = document
        self._routes: List[Tuple["re.Pattern[str]", dict]] = []
        for path, item in document["paths"].items():
            pattern = item.get("x-strata-pattern", path)  # a rest parameter: "{path...}"
            parts = []
            for segment in pattern.split("/")[1:]:
                if segment.startswith("{") and segment.endswith("...}"):
                    parts.append(".+")
                elif segment.startswith("{") and segment.endswith("}"):
                    parts.append("[^/]+")
                else:
                    parts.append(re.escape(segment))
            regex = "/" + "/".join(parts)
            self._routes.append((re.compile(regex + "$"), item))
        self._validators: Dict[str, object] = {}

    def _validator(self, ref: str):
        if ref not in self._validators:
            import jsonschema  # Debian's python3-jsonschema; only the suites that check need it
            schema = {"$ref": ref, "components": self.document["components"]}
            self._validators[ref] = jsonschema.Draft202012Validator(schema)
        return self._validators[ref]

    def _schema_errors(self, ref: str, body: bytes) -> List[str]:
        try:
            value = json.loads(body)
        except ValueError as e:
            return [f"the body is not JSON ({e})"]
        errors = sorted(self._validator(ref).iter_errors(value), key=lambda e: list(e.path))
        return [f"/{'/'.join(str(p) for p in e.path)}: {e.message[:300]}" for e in errors[:8]]

    def problems(self, method: str, target: str, status: int, content_type: str,
                 body: bytes) -> List[str]:
        """What is wrong with this answer to `method target`; empty when it is as documented."""
        path = target.split("?", 1)[0]
        if method == "HEAD":
            method, body = "GET", b""
        item = next((item for regex, item in self._routes if regex.match(path)), None)
        operation = item.get(method.lower()) if item else None
        media = (content_type or "").split(";", 1)[0].strip().lower()
        if operation is None:
            # No such route or method: the table's 404 or 405, the front end's refusals, or a
            # CORS preflight.
            if method == "OPTIONS" and status == 204:
                return []
            if status < 400 or media != "application/problem+json":
                return [f"status {status} ({media}) where only a problem can answer"]
            return self._schema_errors("#/components/schemas/Problem", body)
        answer = operation["responses"].get(str(status))
        if answer is not None and "$ref" in answer:  # "#/components/responses/..."
            answer = self.document["components"]["responses"][answer["$ref"].rsplit("/", 1)[1]]
        if answer is None:
            return [f"status {status} is not documented"]
        content = answer.get("content", {})
        if not body:
            return []
        if media not in content:
            return [f"status {status}: media type {media!r} is not documented "
                    f"({', '.join(content) or 'no body'})"]
        schema = content[media].get("schema")
        if schema is None or not (media.endswith("/json") or media.endswith("+json")):
            return []
        return self._schema_errors(schema["$ref"], body)


# The servers running now, by port: the answers they give are checked.
_RUNNING: Dict[int, "ServerProcess"] = {}
_STREAMS = ("multipart/x-mixed-replace", "text/event-stream")


def _check_http_client_answers() -> None:
    """Wraps http.client so that each answer from a running ServerProcess is checked before the
    caller reads it (the body is read here and handed back unchanged)."""
    cls = http.client.HTTPConnection
    if getattr(cls, "_strata_checked", False):
        return
    putrequest, putheader, getresponse = cls.putrequest, cls.putheader, cls.getresponse

    def record_request(self, method, url, *args, **kwargs):
        self._strata_request, self._strata_auth = (method, url), {}
        return putrequest(self, method, url, *args, **kwargs)

    def record_header(self, header, *values):
        if str(header).lower() == "authorization" and values:
            self._strata_auth = {"Authorization": str(values[0])}
        return putheader(self, header, *values)

    def checked_response(self):
        response = getresponse(self)
        server = _RUNNING.get(self.port) if self.host in ("127.0.0.1", "localhost") else None
        method, url = getattr(self, "_strata_request", ("GET", "/"))
        if "://" in url:  # an absolute target: keep its path and query
            parts = urllib.parse.urlsplit(url)
            url = (parts.path or "/") + ("?" + parts.query if parts.query else "")
        target = url
        if server is None or target.startswith("/v1/openapi.json"):
            return response
        media = (response.getheader("Content-Type") or "").split(";")[0].strip().lower()
        body = b"" if media in _STREAMS else response.read()
        if body:
            # Handed back unread, as the caller expects it.
            response.fp, response.length, response.chunked = io.BytesIO(body), len(body), False
        server.check_answer(method, target, response.status, dict(response.getheaders()), body,
                            getattr(self, "_strata_auth", {}))
        return response

    cls.putrequest, cls.putheader, cls.getresponse = record_request, record_header, \
        checked_response
    cls._strata_checked = True


def _check_async_client_answers() -> None:
    """Wraps the asyncio client's connection (clients/python, strata_client._aio_http) the same
    way, when that client is importable: each answer from a running ServerProcess is checked as
    it arrives."""
    try:
        from strata_client import _aio_http
    except ImportError:
        return  # the suites that use it put it on the path
    cls = _aio_http.Connection
    if getattr(cls, "_strata_checked", False):
        return
    exchange = cls.exchange

    async def checked_exchange(self, method, target, headers, body):
        response = await exchange(self, method, target, headers, body)
        peer = self._writer.get_extra_info("peername") or ("", 0)
        server = _RUNNING.get(peer[1]) if peer[0] in ("127.0.0.1", "::1") else None
        if server is not None and not target.startswith("/v1/openapi.json"):
            auth = {k: v for k, v in headers.items() if k.lower() == "authorization"}
            server.check_answer(method, target, response.status, dict(response.headers),
                                response.body, auth)
        return response

    cls.exchange = checked_exchange
    cls._strata_checked = True


class ServerProcess:
    """A strata-server child process. `args` are extra flags (e.g. ["--demo"])."""

    def __init__(self, binary: str, args: Optional[List[str]] = None, timeout: float = 30.0,
                 env: Optional[Dict[str, str]] = None,
                 preexec_fn: Optional[Callable[[], None]] = None, wait_ready: bool = True,
                 port: int = 0, default_flags: bool = True, check_answers: bool = True):
        """`env`: variables added to this process's environment (STRATA_TOKEN is not inherited).
        `preexec_fn` runs in the child before exec (resource limits, another user).
        `wait_ready`: return only once /readyz answers 200 (else as soon as it listens).
        `port`: a port chosen beforehand (servers that must know each other's, --peers); 0 lets
        the server pick a free one.
        `default_flags`: False runs exactly `binary` + `args` (no --host, --port, --log-level), for
        a deployment's own flags and environment (tests/server/test_compose_topology.py); the
        server must then log at info level and `port` must be the port it listens on.
        `check_answers`: False skips the OpenAPI check of this server's answers (benchmarks, whose
        timed loops must not include it, and machines without python3-jsonschema)."""
        self.check_answers = check_answers
        self._log = tempfile.NamedTemporaryFile(prefix="strata-server-", suffix=".log",
                                                delete=False)
        self.log_path = self._log.name
        full_env = {k: v for k, v in os.environ.items() if k != "STRATA_TOKEN"}
        full_env.update(env or {})
        flags = ["--host", "127.0.0.1", "--port", str(port), "--log-level", "info"]
        self.process = subprocess.Popen(
            [binary] + (flags if default_flags else []) + (args or []),
            stdout=self._log, stderr=subprocess.STDOUT, env=full_env, preexec_fn=preexec_fn)
        self.url = self._wait_for_port(timeout)
        self.port = int(self.url.rsplit(":", 1)[1])
        self._openapi: Optional[OpenApiCheck] = None
        _check_http_client_answers()
        _check_async_client_answers()
        _RUNNING[self.port] = self
        if wait_ready:
            self._wait_until_ready(timeout)

    def _wait_until_ready(self, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                with urllib.request.urlopen(self.url + "/readyz", timeout=5) as answer:
                    if answer.status == 200:
                        return
            except urllib.error.HTTPError as e:
                if e.code != 503:
                    raise
            except (urllib.error.URLError, ConnectionError):
                pass
            if self.process.poll() is not None:
                raise RuntimeError(f"strata-server exited with {self.process.returncode}:\n"
                                   + self.log())
            time.sleep(0.02)
        log = self.log()  # stop() removes the log file
        self.stop()
        raise RuntimeError("strata-server did not become ready:\n" + log)

    def _wait_for_port(self, timeout: float) -> str:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with open(self.log_path, encoding="utf-8", errors="replace") as log:
                match = _LISTENING.search(log.read())
            if match:
                return match.group(1)
            if self.process.poll() is not None:
                raise RuntimeError(f"strata-server exited with {self.process.returncode}:\n"
                                   + self.log())
            time.sleep(0.02)
        log = self.log()
        self.stop()
        raise RuntimeError("strata-server did not start listening:\n" + log)

    def openapi(self, headers: Optional[Dict[str, str]] = None) -> Optional[OpenApiCheck]:
        """The server's OpenAPI description, fetched once (with the caller's Authorization);
        None while it cannot be had (the server is starting, gone, or wants a token)."""
        if self._openapi is None:
            auth = {k: v for k, v in (headers or {}).items() if k.lower() == "authorization"}
            request = urllib.request.Request(self.url + "/v1/openapi.json", headers=auth)
            try:
                with urllib.request.urlopen(request, timeout=30) as answer:
                    self._openapi = OpenApiCheck.of(answer.read().decode())
            except (urllib.error.URLError, http.client.HTTPException, ConnectionError,
                    TimeoutError):
                return None
        return self._openapi

    def check_answer(self, method: str, target: str, status: int, headers: Dict[str, str],
                     body: bytes, request_headers: Optional[Dict[str, str]] = None) -> None:
        """Raises AssertionError when the answer is not what GET /v1/openapi.json documents for
        `method target` (status, media type, JSON schema)."""
        checker = self.openapi(request_headers) if self.check_answers else None
        if checker is None:
            return
        content_type = next((v for k, v in headers.items() if k.lower() == "content-type"), "")
        found = checker.problems(method, target, status, content_type, body)
        if found:
            raise AssertionError(f"{method} {target} answered {status}, not as "
                                 f"/v1/openapi.json documents it:\n  " + "\n  ".join(found) +
                                 f"\n  body: {body[:500]!r}")

    def log(self) -> str:
        """Everything the server has logged so far."""
        with open(self.log_path, encoding="utf-8", errors="replace") as log:
            return log.read()

    def _forget(self) -> None:
        if _RUNNING.get(self.port) is self:
            del _RUNNING[self.port]

    def kill(self) -> None:
        """SIGKILL, no grace: what a crash, an OOM kill or `kill -9` does."""
        self._forget()
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait()

    def stop(self) -> int:
        """Stops the server (SIGTERM: a graceful shutdown) and returns its exit code."""
        self._forget()
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._log.close()
        if os.path.exists(self.log_path):
            os.unlink(self.log_path)
        return self.process.returncode

    def __enter__(self) -> "ServerProcess":
        return self

    def __exit__(self, *exc) -> None:
        self.stop()

"""Tools for the adversarial suites: a real strata-server process with any flags and environment,
a raw-socket HTTP/1.1 client that can send anything (malformed, pipelined, trickled), and the
server's resident memory. Standard library only.
"""

import json
import os
import socket
import subprocess
import time
import urllib.error
import urllib.request
from typing import Dict, List, Optional, Tuple

from strata_process import ServerProcess

SERVER = os.environ.get("STRATA_SERVER_BINARY", "build/server/strata-server")


class Server(ServerProcess):
    """strata-server on a free loopback port (tests/python/strata_process.py), with what the
    adversarial suites need besides: memory, signals, and requests that return problems."""

    def __init__(self, args: Optional[List[str]] = None, env: Optional[Dict[str, str]] = None,
                 preexec_fn=None, wait_ready: bool = True, port: int = 0,
                 default_flags: bool = True):
        super().__init__(SERVER, args, env=env, preexec_fn=preexec_fn, wait_ready=wait_ready,
                         port=port, default_flags=default_flags)
        self.pid = self.process.pid

    def alive(self) -> bool:
        return self.process.poll() is None

    def rss_mb(self) -> float:
        with open(f"/proc/{self.pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
        return 0.0

    def signal(self, signo: int) -> None:
        self.process.send_signal(signo)

    def wait(self, timeout: float) -> Optional[int]:
        try:
            return self.process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            return None

    # Well-behaved requests, through urllib.
    def call(self, method: str, path: str, body=None, headers=None, timeout: float = 30.0):
        """(status, headers, body bytes); a problem answer is returned, not raised. The answer
        is held to the server's OpenAPI description on its way in (strata_process.py): an
        undocumented status or a body that does not match its schema fails the test."""
        data = body if isinstance(body, (bytes, type(None))) else json.dumps(body).encode()
        req = urllib.request.Request(f"http://127.0.0.1:{self.port}{path}", data=data,
                                     method=method, headers=headers or {})
        try:
            with urllib.request.urlopen(req, timeout=timeout) as r:
                return r.status, dict(r.headers), r.read()
        except urllib.error.HTTPError as e:
            return e.code, dict(e.headers), e.read()

    def json(self, method: str, path: str, body=None, headers=None) -> Tuple[int, dict]:
        status, _, data = self.call(method, path, body, headers)
        return status, json.loads(data) if data else {}

    def version(self, headers=None) -> int:
        return self.json("GET", "/v1/scene", headers=headers)[1]["version"]

    def counters(self, headers=None) -> dict:
        return self.json("GET", "/v1/stats", headers=headers)[1]["counters"]


class Response:
    def __init__(self, status: int, reason: str, headers: Dict[str, str], body: bytes):
        self.status, self.reason, self.headers, self.body = status, reason, headers, body

    def json(self):
        return json.loads(self.body)


class Conn:
    """One raw TCP connection: send any bytes, read HTTP/1.1 responses."""

    def __init__(self, port: int, timeout: float = 10.0):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=timeout)
        self.buf = b""

    def send(self, data: bytes) -> None:
        self.sock.sendall(data)

    def _fill(self) -> bool:
        chunk = self.sock.recv(65536)
        self.buf += chunk
        return bool(chunk)

    def response(self, head: bool = False) -> Response:
        """The next response (a 1xx interim one included); head: no body follows."""
        while b"\r\n\r\n" not in self.buf:
            if not self._fill():
                raise ConnectionError("closed before a response: %r" % self.buf[:200])
        raw, self.buf = self.buf.split(b"\r\n\r\n", 1)
        lines = raw.decode("latin-1").split("\r\n")
        _, status, reason = lines[0].split(" ", 2)
        headers = {}
        for line in lines[1:]:
            name, value = line.split(":", 1)
            headers[name.strip().lower()] = value.strip()
        length = 0 if head or int(status) < 200 else int(headers.get("content-length", "0"))
        while len(self.buf) < length:
            if not self._fill():
                raise ConnectionError("closed inside a body")
        body, self.buf = self.buf[:length], self.buf[length:]
        return Response(int(status), reason, headers, body)

    def closed_within(self, seconds: float) -> bool:
        """True when the server closes the connection within `seconds` (data is discarded)."""
        self.sock.settimeout(seconds)
        deadline = time.monotonic() + seconds
        try:
            while time.monotonic() < deadline:
                if not self.sock.recv(65536):
                    return True
        except socket.timeout:
            return False
        except (ConnectionResetError, BrokenPipeError):
            return True
        return False

    def close(self) -> None:
        try:
            self.sock.close()
        except OSError:
            pass


def request(method: str, target: str, headers: Optional[List[Tuple[str, str]]] = None,
            body: bytes = b"", host: bool = True, length: bool = True) -> bytes:
    """A request's bytes: Host and Content-Length added unless told not to."""
    lines = [f"{method} {target} HTTP/1.1"]
    if host:
        lines.append("Host: 127.0.0.1")
    for name, value in headers or []:
        lines.append(f"{name}: {value}")
    if body and length:
        lines.append(f"Content-Length: {len(body)}")
    return ("\r\n".join(lines) + "\r\n\r\n").encode("latin-1") + body


def exchange(port: int, data: bytes, head: bool = False, timeout: float = 10.0) -> Response:
    """Sends `data` on a new connection and returns the first response."""
    conn = Conn(port, timeout)
    try:
        conn.send(data)
        return conn.response(head)
    finally:
        conn.close()


def edits_body(*edits) -> bytes:
    return json.dumps({"edits": list(edits)}).encode()

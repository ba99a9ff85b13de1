"""A small HTTP/1.1 client connection on asyncio streams: one request at a time, keep-alive,
Content-Length and chunked answers. Enough for strata-server's JSON and image answers; the
endless streams (/v1/stream, /v1/events) are not read through it."""

import asyncio
import ssl
from typing import Dict, List, Optional, Tuple

from strata_client._api import Endpoint, Response

# Long enough for any header line a server or proxy may send (X-Strata-Report is at most 3 KiB).
_LINE_LIMIT = 1 << 20

#: Bodies from this size on are sent after the server's `100 Continue`, so that a body over its
#: limit is answered (413) before it is sent, not cut off by a reset connection.
EXPECT_CONTINUE_BYTES = 1 << 20

#: How long to wait for `100 Continue` before sending the body anyway (RFC 9110 10.1.1: a
#: client need not wait indefinitely).
CONTINUE_WAIT_S = 1.0


class RemoteDisconnected(ConnectionResetError):
    """The connection ended before the first byte of an answer (as http.client's of the same
    name): on a kept-alive connection, the server closed it while idle and never read the
    request, so sending it again on a new connection applies nothing twice."""


def _check_header(name: str, value: str) -> None:
    for text in (name, value):
        if "\r" in text or "\n" in text:
            raise ValueError(f"invalid HTTP header {name!r}: it contains a line break")


class Connection:
    """One HTTP/1.1 connection. `reusable` is false once the server has said it will close it,
    or once an exchange failed part-way."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter,
                 host_header: str):
        self._reader = reader
        self._writer = writer
        self._host_header = host_header
        self.reusable = True

    @classmethod
    async def open(cls, endpoint: Endpoint) -> "Connection":
        context = ssl.create_default_context() if endpoint.https else None
        port = endpoint.port or (443 if endpoint.https else 80)
        reader, writer = await asyncio.open_connection(
            endpoint.host, port, ssl=context, limit=_LINE_LIMIT,
            server_hostname=endpoint.host if context else None)
        return cls(reader, writer, endpoint.netloc.rpartition("@")[2])

    def close(self) -> None:
        self.reusable = False
        self._writer.close()

    async def wait_closed(self) -> None:
        try:
            await self._writer.wait_closed()
        except (OSError, ssl.SSLError):
            pass  # already reset: it is closed either way

    async def exchange(self, method: str, target: str, headers: Dict[str, str],
                       body: Optional[bytes]) -> Response:
        """Sends one request and reads its whole answer. Raises RemoteDisconnected when the
        request could not be sent or the connection ended before the answer began."""
        self.reusable = False  # until the answer has been read whole
        expect = body is not None and len(body) >= EXPECT_CONTINUE_BYTES
        head = self._head(method, target, headers, body, expect)
        rest = body or b""
        try:
            status_line = None
            if expect:
                self._writer.write(head)
                await self._writer.drain()
                status_line = await self._continue_or_answer()
            else:
                rest = head + rest
            body_sent = status_line is None
            if body_sent:
                self._writer.write(rest)
                await self._writer.drain()
                status_line = await self._reader.readline()
        except (BrokenPipeError, ConnectionResetError) as e:
            raise RemoteDisconnected(f"connection closed before the answer: {e}") from e
        if not status_line:
            raise RemoteDisconnected("connection closed before the answer")
        status, version = self._parse_status(status_line)
        answer_headers = await self._read_headers()
        while 100 <= status < 200:  # an interim answer: the real one follows
            status, version = self._parse_status(await self._reader.readline())
            answer_headers = await self._read_headers()
        data, until_eof = await self._read_body(method, status, answer_headers)
        connection = answer_headers.get("connection", "").lower()
        if version == "HTTP/1.0":
            keep = "keep-alive" in connection
        else:
            keep = "close" not in connection
        self.reusable = keep and not until_eof and body_sent
        return Response(status, answer_headers, data)

    async def _continue_or_answer(self) -> Optional[bytes]:
        """After headers with `Expect: 100-continue`: None to send the body (the server said
        100 Continue, or said nothing for a while), or the status line of its final answer (a
        413 for a body over its limit, read whole instead of a broken pipe)."""
        try:
            line = await asyncio.wait_for(self._reader.readline(), CONTINUE_WAIT_S)
        except asyncio.TimeoutError:
            return None
        if line and self._parse_status(line)[0] == 100:
            await self._read_headers()
            return None
        return line

    def _head(self, method: str, target: str, headers: Dict[str, str],
              body: Optional[bytes], expect_continue: bool) -> bytes:
        lines = [f"{method} {target} HTTP/1.1", f"Host: {self._host_header}"]
        for name, value in headers.items():
            _check_header(name, value)
            lines.append(f"{name}: {value}")
        if body is not None:
            lines.append(f"Content-Length: {len(body)}")
        if expect_continue:
            lines.append("Expect: 100-continue")
        return ("\r\n".join(lines) + "\r\n\r\n").encode("latin-1")

    @staticmethod
    def _parse_status(line: bytes) -> Tuple[int, str]:
        parts = line.decode("latin-1").split(None, 2)
        if len(parts) < 2 or not parts[0].startswith("HTTP/") or not parts[1].isdigit():
            raise ConnectionError(f"not an HTTP answer: {line[:100]!r}")
        return int(parts[1]), parts[0]

    async def _read_headers(self) -> Dict[str, str]:
        headers: Dict[str, str] = {}
        while True:
            line = await self._reader.readline()
            if not line:
                raise ConnectionError("connection closed in the middle of an answer's headers")
            if line in (b"\r\n", b"\n"):
                return headers
            name, _, value = line.decode("latin-1").partition(":")
            headers[name.strip().lower()] = value.strip()

    async def _read_body(self, method: str, status: int,
                         headers: Dict[str, str]) -> Tuple[bytes, bool]:
        """The body, and whether it ran until the server closed the connection."""
        try:
            if method == "HEAD" or status in (204, 304):
                return b"", False
            if "chunked" in headers.get("transfer-encoding", "").lower():
                return await self._read_chunks(), False
            if "content-length" in headers:
                return await self._reader.readexactly(int(headers["content-length"])), False
            return await self._reader.read(), True
        except asyncio.IncompleteReadError as e:
            raise ConnectionError("connection closed in the middle of an answer's body") from e

    async def _read_chunks(self) -> bytes:
        chunks: List[bytes] = []
        while True:
            size_line = await self._reader.readline()
            size = int(size_line.split(b";", 1)[0].strip() or b"x", 16)
            if size == 0:
                while (await self._reader.readline()) not in (b"\r\n", b"\n", b""):
                    pass  # trailers
                return b"".join(chunks)
            chunks.append(await self._reader.readexactly(size))
            await self._reader.readexactly(2)  # the CRLF after each chunk

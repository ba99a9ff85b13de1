"""A real redis-server for the replica suites: a temporary directory, a free loopback port,
append-only file on with fsync on every write (what a no-loss setup uses), and a tiny RESP
client to look inside or tamper with the stream. Standard library only.
"""

import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time
from typing import List, Optional

REDIS_SERVER = shutil.which("redis-server")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def free_ports(n: int) -> list:
    """n loopback ports free now, all at once (servers that must know each other's ports before
    they start)."""
    sockets = [socket.socket() for _ in range(n)]
    for s in sockets:
        s.bind(("127.0.0.1", 0))
    ports = [s.getsockname()[1] for s in sockets]
    for s in sockets:
        s.close()
    return ports


class RedisProcess:
    """redis-server in its own directory; restart() keeps the directory and port."""

    def __init__(self, config: Optional[List[str]] = None):
        """`config`: redis-server's arguments besides --port and --logfile (a deployment's own,
        e.g. docker/compose.replicas.yml's); by default AOF on, fsync always, in self.dir."""
        self.dir = tempfile.mkdtemp(prefix="strata-redis-")
        self.port = free_port()
        self.config = config if config is not None else [
            "--bind", "127.0.0.1", "--dir", self.dir, "--appendonly", "yes",
            "--appendfsync", "always", "--save", "", "--daemonize", "no"]
        self.process: Optional[subprocess.Popen] = None
        self.start()

    def start(self) -> None:
        self.process = subprocess.Popen(
            [REDIS_SERVER] + self.config
            + ["--port", str(self.port), "--logfile", os.path.join(self.dir, "redis.log")],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            try:
                if self.command("PING") == "PONG":
                    return
            except (OSError, RuntimeError):  # not listening yet, or LOADING its AOF
                pass
            time.sleep(0.02)
        raise RuntimeError("redis-server did not start")

    def kill(self) -> None:
        """SIGKILL: what a crash does (the AOF, fsynced on every write, keeps every entry)."""
        if self.process and self.process.poll() is None:
            self.process.send_signal(signal.SIGKILL)
            self.process.wait()

    def restart(self) -> None:
        self.kill()
        self.start()

    def stop(self) -> None:
        self.kill()
        shutil.rmtree(self.dir, True)

    def url(self, stream: str) -> str:
        return f"redis://127.0.0.1:{self.port}/{stream}"

    # RESP2, enough for the tests.
    def command(self, *args):
        with socket.create_connection(("127.0.0.1", self.port), timeout=5) as s:
            out = b"*%d\r\n" % len(args)
            for a in args:
                a = a if isinstance(a, bytes) else str(a).encode()
                out += b"$%d\r\n%s\r\n" % (len(a), a)
            s.sendall(out)
            return _read(s.makefile("rb"))


def _read(f):
    line = f.readline()
    if not line:
        raise OSError("connection closed")
    kind, rest = line[:1], line[1:-2]
    if kind == b"+":
        return rest.decode()
    if kind == b"-":
        raise RuntimeError(rest.decode())
    if kind == b":":
        return int(rest)
    if kind == b"$":
        n = int(rest)
        if n < 0:
            return None
        data = f.read(n + 2)[:-2]
        return data
    if kind == b"*":
        n = int(rest)
        return None if n < 0 else [_read(f) for _ in range(n)]
    raise OSError("bad RESP reply " + repr(line))

"""Starts a real strata-server on a free loopback port for tests, and stops it.

    with ServerProcess(binary) as server:
        ... server.url ...

The server is started with --port 0 and its log is read until it says which port it got, so
there is no race for a port; then, unless wait_ready=False, /readyz is polled until it answers 200
(a server with --data listens while it recovers its scene, answering 503 meanwhile). Standard
library only.
"""

import os
import re
import signal
import subprocess
import tempfile
import time
import urllib.error
import urllib.request
from typing import Callable, Dict, List, Optional

_LISTENING = re.compile(r"listening on (http://[0-9.]+:([0-9]+))")


class ServerProcess:
    """A strata-server child process. `args` are extra flags (e.g. ["--demo"])."""

    def __init__(self, binary: str, args: Optional[List[str]] = None, timeout: float = 30.0,
                 env: Optional[Dict[str, str]] = None,
                 preexec_fn: Optional[Callable[[], None]] = None, wait_ready: bool = True,
                 port: int = 0, default_flags: bool = True):
        """`env`: variables added to this process's environment (STRATA_TOKEN is not inherited).
        `preexec_fn` runs in the child before exec (resource limits, another user).
        `wait_ready`: return only once /readyz answers 200 (else as soon as it listens).
        `port`: a port chosen beforehand (servers that must know each other's, --peers); 0 lets
        the server pick a free one.
        `default_flags`: False runs exactly `binary` + `args` (no --host, --port, --log-level), for
        a deployment's own flags and environment (tests/server/test_compose_topology.py); the
        server must then log at info level and `port` must be the port it listens on."""
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

    def log(self) -> str:
        """Everything the server has logged so far."""
        with open(self.log_path, encoding="utf-8", errors="replace") as log:
            return log.read()

    def kill(self) -> None:
        """SIGKILL, no grace: what a crash, an OOM kill or `kill -9` does."""
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait()

    def stop(self) -> int:
        """Stops the server (SIGTERM: a graceful shutdown) and returns its exit code."""
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

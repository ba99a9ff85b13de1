"""Crash test: a real strata-server with a data directory, a client streaming edit batches, and
SIGKILL at random moments (during appends, background snapshots and journal truncation), over
and over. After every restart each batch the client saw acknowledged must be there, nothing
unacknowledged may be half there, and the version must be the last acknowledged one, or one more
when a batch was written but its answer was lost. Bounded to about a minute (CTest label crash).
"""

import json
import os
import random
import shutil
import tempfile
import threading
import time
import unittest
import urllib.error
import urllib.request

import durable_scene
from hostile import Server

KILLS = int(os.environ.get("STRATA_CRASH_KILLS", "32"))


class Streamer(threading.Thread):
    """Sends batch n, n+1, ... with If-Match, one at a time, until the server dies."""

    def __init__(self, port: int, first: int):
        super().__init__(daemon=True)
        self.port = port
        self.next = first
        self.acked = first  # the version the last acknowledged batch produced
        self.in_flight = False
        self.error = ""

    def run(self) -> None:
        while True:
            body = json.dumps(durable_scene.batch(self.next)).encode()
            req = urllib.request.Request(
                f"http://127.0.0.1:{self.port}/v1/edits", data=body, method="POST",
                headers={"Content-Type": "application/json", "If-Match": f'"{self.next}"'})
            self.in_flight = True
            try:
                with urllib.request.urlopen(req, timeout=30) as r:
                    answer = json.loads(r.read())
            except urllib.error.HTTPError as e:
                self.error = f"batch {self.next} answered {e.code}: {e.read()[:300]!r}"
                return
            except (urllib.error.URLError, ConnectionError, OSError, ValueError):
                return  # the server is gone; this batch's fate is unknown
            if answer.get("version") != self.next + 1:
                raise AssertionError(f"batch {self.next} answered {answer}")
            self.in_flight = False
            self.acked = self.next + 1
            self.next += 1


class CrashTest(unittest.TestCase):
    def test_sigkill_at_random_moments_loses_no_acknowledged_batch(self):
        data = tempfile.mkdtemp(prefix="strata-crash-")
        rng = random.Random(int(os.environ.get("STRATA_CRASH_SEED", str(int(time.time())))))
        args = ["--data", data, "--fsync", "always", "--snapshot-threshold-kb", "48"]
        acked = 0
        lost_answers = 0
        mid_snapshot = 0
        snapshots_seen = 0
        started = time.monotonic()
        try:
            for kill in range(KILLS):
                server = Server(args)
                try:
                    self.assertTrue(wait_ready(server), server.log())
                    version = server.version()
                    # Every acknowledged batch is there; at most the one in flight more.
                    self.assertIn(version, (acked, acked + 1),
                                  f"kill {kill}: version {version} after {acked} acknowledged\n"
                                  + server.log())
                    lost_answers += version == acked + 1
                    problem = durable_scene.check(server, version)
                    self.assertEqual(problem, "", f"kill {kill}: {problem}\n" + server.log())

                    streamer = Streamer(server.port, version)
                    streamer.start()
                    time.sleep(rng.uniform(0.02, 0.6))
                    snapshots_seen += any(n.startswith("snapshot-") for n in os.listdir(data))
                    server.kill()
                    streamer.join(timeout=30)
                    self.assertFalse(streamer.is_alive())
                    self.assertEqual(streamer.error, "", server.log())
                    acked = streamer.acked
                    mid_snapshot += any(n.endswith(".tmp") for n in os.listdir(data))
                finally:
                    server.kill()
                    server.stop()
            # A last restart after the last kill.
            server = Server(args)
            try:
                self.assertTrue(wait_ready(server), server.log())
                version = server.version()
                self.assertIn(version, (acked, acked + 1))
                self.assertEqual(durable_scene.check(server, version), "")
            finally:
                server.stop()
        finally:
            shutil.rmtree(data, ignore_errors=True)
        print(f"\n{KILLS} kills in {time.monotonic() - started:.1f} s: {acked} batches "
              f"acknowledged, {lost_answers} answers lost after the write, snapshots on disk "
              f"at {snapshots_seen} kills, {mid_snapshot} kills during a snapshot write")
        self.assertGreater(acked, KILLS, "the client should have streamed many batches")
        self.assertGreater(snapshots_seen, 0, "snapshots should have been written")


def wait_ready(server, timeout: float = 30.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{server.port}/readyz", timeout=5) as r:
                if r.status == 200:
                    return True
        except (urllib.error.URLError, ConnectionError, OSError):
            pass
        time.sleep(0.02)
    return False


if __name__ == "__main__":
    unittest.main()

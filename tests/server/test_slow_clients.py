"""The issue's bound, checked against the real server: with 64 hostile slow connections open
(headers trickled a byte a second, bodies stalled, keep-alive connections left idle, connections
that never send a byte), a normal client still gets GET /v1/scene in under a second at the 99th
percentile, and SIGTERM still ends the process in under five seconds. A correctness bound on the
front end's design (no client can hold a worker), not a benchmark: the margin is wide.
"""

import socket
import statistics
import threading
import time
import unittest

from hostile import Conn, Server, exchange, request

TOKEN = "s3cret"
AUTH = ("Authorization", "Bearer " + TOKEN)
HOSTILE = 64


class Attacker(threading.Thread):
    """Keeps one hostile connection open until stopped, reconnecting when the server drops it."""

    def __init__(self, port: int, kind: int, stop: threading.Event):
        super().__init__(daemon=True)
        self.port, self.kind, self.stop_event = port, kind, stop
        self.connections = 0

    def run(self):
        while not self.stop_event.is_set():
            try:
                conn = Conn(self.port, timeout=2)
                self.connections += 1
                self.attack(conn)
            except OSError:
                pass  # dropped by the server (408, idle timeout): come back
            finally:
                try:
                    conn.close()
                except (NameError, UnboundLocalError):
                    pass
            self.stop_event.wait(0.1)

    def attack(self, conn: Conn):
        if self.kind == 0:  # slowloris: headers one byte a second, no token
            conn.send(b"GET /v1/scene HTTP/1.1\r\nHost: a\r\n")
            while not self.stop_event.wait(1.0):
                conn.send(b"X")
        elif self.kind == 1:  # an authenticated body that stalls
            conn.send(b"POST /v1/edits HTTP/1.1\r\nHost: a\r\nAuthorization: Bearer " +
                      TOKEN.encode() + b"\r\nContent-Length: 100000\r\n\r\n{\"edits\": [")
            while not self.stop_event.wait(1.0):
                conn.send(b" ")
        elif self.kind == 2:  # one request, then an idle keep-alive connection
            conn.send(request("GET", "/v1/stats", [AUTH]))
            conn.response()
            while not self.stop_event.wait(0.5):
                pass
            raise OSError
        else:  # connects and never sends a byte
            while not self.stop_event.wait(0.5):
                pass
            raise OSError


class SlowConnections(unittest.TestCase):
    def test_64_slow_connections_leave_the_server_responsive_and_stoppable(self):
        server = Server(["--demo"], {"STRATA_TOKEN": TOKEN})
        stop = threading.Event()
        attackers = [Attacker(server.port, i % 4, stop) for i in range(HOSTILE)]
        try:
            for a in attackers:
                a.start()
            time.sleep(3.0)  # every attacker connected and mid-attack
            rss_before = server.rss_mb()

            # Twelve seconds, so that header deadlines (10 s) and keep-alive timeouts (5 s) cut
            # attackers off and they come back while the normal client is measured.
            latencies = []
            for i in range(200):
                time.sleep(0.06)
                start = time.monotonic()
                if i % 2:
                    r = exchange(server.port, request("GET", "/v1/scene", [AUTH]), timeout=5)
                else:
                    status, _, _ = server.call("GET", "/v1/scene",
                                               headers={"Authorization": "Bearer " + TOKEN},
                                               timeout=5)
                    r = type("R", (), {"status": status})
                latencies.append(time.monotonic() - start)
                self.assertEqual(r.status, 200)
            latencies.sort()
            p99 = latencies[int(0.99 * len(latencies)) - 1]
            print(f"\nGET /v1/scene under {HOSTILE} slow connections: median "
                  f"{statistics.median(latencies) * 1000:.1f} ms, p99 {p99 * 1000:.1f} ms, "
                  f"max {latencies[-1] * 1000:.1f} ms; attacker connections opened: "
                  f"{sum(a.connections for a in attackers)}")
            self.assertLess(p99, 1.0)
            status, _ = server.json("POST", "/v1/edits", {"edits": [{"op": "add_material",
                                                                     "id": "ok"}]},
                                    headers={"Authorization": "Bearer " + TOKEN})
            self.assertEqual(status, 200)
            self.assertLess(server.rss_mb() - rss_before, 64)

            # SIGTERM with every hostile connection still open.
            start = time.monotonic()
            server.signal(15)
            code = server.wait(10)
            took = time.monotonic() - start
            print(f"SIGTERM with {HOSTILE} slow connections open: exited {code} in "
                  f"{took * 1000:.0f} ms")
            self.assertEqual(code, 0)
            self.assertLess(took, 5.0)
        finally:
            stop.set()
            server.stop()
            for a in attackers:
                a.join(5)


if __name__ == "__main__":
    unittest.main()

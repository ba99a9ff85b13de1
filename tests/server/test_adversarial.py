"""The real strata-server against hostile clients, one class of attack per test: each checks the
status the server answers, that it is still alive and answering, that nothing was applied, and,
where a small request could ask for a lot, that its memory stays bounded.

Run: PYTHONPATH=tests/server:tests/python STRATA_SERVER_BINARY=build/server/strata-server \
         python3 -m unittest -v test_adversarial
"""

import gzip
import json
import os
import re
import select
import signal
import socket
import subprocess
import threading
import time
import unittest

from hostile import SERVER, Conn, Server, edits_body, exchange, request

MATERIAL = {"op": "add_material", "id": "m"}


class ServerCase(unittest.TestCase):
    """One server for the class; every test ends by checking it still answers."""

    ARGS = ["--demo"]
    ENV = None

    @classmethod
    def setUpClass(cls):
        cls.server = Server(cls.ARGS, cls.ENV)
        cls.port = cls.server.port

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()

    def tearDown(self):
        self.assertTrue(self.server.alive(), self.server.log()[-3000:])
        self.assertEqual(exchange(self.port, request("GET", "/livez")).status, 200)

    def assertProblem(self, r, status, slug=None):
        self.assertEqual(r.status, status, r.body[:300])
        self.assertEqual(r.headers.get("content-type"), "application/problem+json")
        doc = r.json()
        self.assertEqual(doc["status"], status)
        if slug:
            self.assertEqual(doc["type"], "https://strata.dev/problems/" + slug)
        return doc


class InvalidText(ServerCase):
    """Invalid UTF-8 and CR/LF anywhere in a request: a clear 4xx, never a crash or a 500."""

    def test_invalid_utf8_in_paths_queries_and_headers_is_answered_with_a_4xx(self):
        for target in ["/%ff", "/%c3%28", "/v1/scene/meshes/%ff%fe", "/v1/scene/instances/%ed%a0%80",
                       "/v1/render?format=%ff", "/v1/render?width=%ff%fe", "/v1/scene?x=%ff",
                       "/%ff?%ff=%ff", "/v1/%ff/render"]:
            r = exchange(self.port, request("GET", target))
            self.assertIn(r.status, (400, 404), target)
            self.assertProblem(r, r.status)
        # Raw non-ASCII bytes in the request line, and obs-text in a header value that an error
        # message quotes back.
        self.assertProblem(exchange(self.port, b"GET /\xff\xfe HTTP/1.1\r\nHost: a\r\n\r\n"), 400)
        r = exchange(self.port, request("POST", "/v1/edits", [("If-Match", "\"\xff\xfe\"")],
                                        edits_body(MATERIAL)))
        doc = self.assertProblem(r, 400)
        self.assertIn("If-Match", doc["detail"])
        self.assertEqual(self.server.json("GET", "/v1/scene/materials/m")[0], 404)

    def test_log_records_cannot_be_forged(self):
        exchange(self.port, request("GET", "/x%0d%0a2026-01-01T00:00:00.000%20info%20FORGED"))
        exchange(self.port, b"GET /y HTTP/1.1\r\nHost: a\r\nX: \xc2\x85FORGED2\r\n\r\n")
        r = exchange(self.port, request("POST", "/v1/edits", [],
                                        edits_body({"op": "add_material", "id": "a\nFORGED3"})))
        self.assertProblem(r, 400)
        time.sleep(0.2)
        for line in self.server.log().splitlines():
            self.assertFalse(re.match(r"^\S* *info FORGED", line), line)
            self.assertFalse(line.startswith("FORGED"), line)
        self.assertIn("%0D%0A", self.server.log())  # the attempt is logged, escaped

    def test_overflowing_cameras_and_huge_quaternions_are_refused_and_renders_still_work(self):
        version = self.server.version()
        for edit in [{"op": "set_camera", "eye": [-3e38, -3e38, -3e38], "target": [3e38, 3e38, 3e38]},
                     {"op": "set_camera", "eye": [1e19, 0, 0], "target": [0, 0, 0]},
                     {"op": "set_transform", "instance": "floor",
                      "transform": {"quaternion": [1e19, 1e19, 1e19, 1e19]}},
                     {"op": "set_transform", "instance": "floor",
                      "transform": {"translate": [1e30, 0, 0]}}]:
            status, doc = self.server.json("POST", "/v1/edits", {"edits": [edit]})
            self.assertEqual(status, 422, doc)
            self.assertIn("pointer", doc)
        r = exchange(self.port, request("GET", "/v1/render?width=16&height=16&eye=3e38,0,0"))
        self.assertProblem(r, 422)
        self.assertEqual(self.server.version(), version)
        self.assertEqual(exchange(self.port, request("GET", "/v1/render?width=16&height=16")).status,
                         200)


class Framing(ServerCase):
    """Everything two HTTP parsers could read differently is refused (request smuggling)."""

    def test_ambiguous_or_unsupported_framing_is_refused_and_nothing_is_applied(self):
        body = edits_body(MATERIAL)
        n = str(len(body)).encode()
        cases = [
            (400, b"POST /v1/edits HTTP/1.1\r\nHost: a\r\nContent-Length: " + n +
             b"\r\nContent-Length: 1\r\n\r\n" + body),
            (400, b"POST /v1/edits HTTP/1.1\r\nHost: a\r\nContent-Length: " + n +
             b"\r\nTransfer-Encoding: chunked\r\n\r\n" + body),
            (400, b"POST /v1/edits HTTP/1.1\r\nHost: a\r\nTransfer-Encoding: gzip\r\n\r\n" + body),
            (400, b"POST /v1/edits HTTP/1.1\r\nHost: a\r\nTransfer-Encoding: identity, chunked\r\n\r\n"),
            (400, b"POST /v1/edits HTTP/1.1\r\nHost: a\r\nContent-Length : " + n + b"\r\n\r\n" + body),
            (400, b"POST /v1/edits HTTP/1.1\r\nHost: a\r\nContent-Length: " + n +
             b"\r\nX-Folded: a\r\n b\r\n\r\n" + body),
            (400, b"POST /v1/edits HTTP/1.1\r\nHost: a\r\nno colon here\r\nContent-Length: " + n +
             b"\r\n\r\n" + body),
            (400, b"POST /v1/edits HTTP/1.1\r\nHost: a\r\nX: a\x00b\r\nContent-Length: " + n +
             b"\r\n\r\n" + body),
            (400, b"POST /v1/edits HTTP/1.1\r\nContent-Length: " + n + b"\r\n\r\n" + body),
            (400, b"POST /v1/edits HTTP/1.1\r\nHost: a\r\nContent-Length: -" + n + b"\r\n\r\n" + body),
            (415, b"POST /v1/edits HTTP/1.1\r\nHost: a\r\nContent-Encoding: br\r\nContent-Length: "
             + n + b"\r\n\r\n" + body),
            (417, b"POST /v1/edits HTTP/1.1\r\nHost: a\r\nExpect: 200-ok\r\nContent-Length: " + n +
             b"\r\n\r\n" + body),
            (501, b"BREW /v1/edits HTTP/1.1\r\nHost: a\r\n\r\n"),
            (505, b"POST /v1/edits HTTP/2.0\r\nHost: a\r\n\r\n"),
        ]
        version = self.server.version()
        for status, raw in cases:
            with self.subTest(raw=raw[:90]):
                conn = Conn(self.port)
                conn.send(raw)
                self.assertProblem(conn.response(), status)
                # The connection is closed: whatever followed cannot be read as a new request.
                self.assertTrue(conn.closed_within(5))
                conn.close()
        self.assertEqual(self.server.version(), version)

    def test_expect_100_continue_over_the_cap_gets_413_without_a_100_first(self):
        conn = Conn(self.port)
        conn.send(request("POST", "/v1/edits", [("Expect", "100-continue"),
                                                ("Content-Length", str(1 << 40))]))
        self.assertProblem(conn.response(), 413, "too-large")
        conn.close()
        conn = Conn(self.port)
        body = edits_body({"op": "add_material", "id": "expected"})
        conn.send(request("POST", "/v1/edits", [("Expect", "100-continue"),
                                                ("Content-Length", str(len(body)))]))
        self.assertEqual(conn.response().status, 100)
        conn.send(body)
        self.assertEqual(conn.response().status, 200)
        conn.close()

    def test_pipelined_requests_are_answered_in_order(self):
        version = self.server.version()
        conn = Conn(self.port)
        conn.send(request("POST", "/v1/edits", [], edits_body({"op": "add_material", "id": "p1"})) +
                  request("POST", "/v1/edits", [], edits_body({"op": "add_material", "id": "p2"})) +
                  request("GET", "/v1/scene/materials/p2") +
                  request("GET", "/livez"))
        first, second, scene, live = (conn.response() for _ in range(4))
        conn.close()
        self.assertEqual(first.json()["version"], version + 1)
        self.assertEqual(second.json()["version"], version + 2)
        self.assertEqual(scene.status, 200)
        self.assertEqual(scene.json()["id"], "p2")
        self.assertEqual(live.status, 200)

    def test_repeated_query_parameters_are_400(self):
        for target in ["/v1/render?width=8&width=8", "/v1/render?width=8&height=8&width=9"]:
            doc = self.assertProblem(exchange(self.port, request("GET", target)), 400)
            self.assertIn("more than once", doc["detail"])

    def test_ids_with_slashes_can_be_read_back_and_control_characters_are_refused(self):
        status, doc = self.server.json("POST", "/v1/edits", {"edits": [
            {"op": "add_material", "id": "/World/Looks/red"},
            {"op": "add_mesh", "id": "/World/geo/tri", "positions": [0, 0, 0, 1, 0, 0, 0, 1, 0],
             "indices": [0, 1, 2]}]})
        self.assertEqual(status, 200, doc)
        status, doc = self.server.json("GET", "/v1/scene/materials/%2FWorld%2FLooks%2Fred")
        self.assertEqual((status, doc.get("id")), (200, "/World/Looks/red"))
        status, doc = self.server.json("GET", "/v1/scene/meshes/%2fWorld%2fgeo%2ftri")
        self.assertEqual((status, doc.get("id")), (200, "/World/geo/tri"))
        status, doc = self.server.json("POST", "/v1/edits",
                                       {"edits": [{"op": "add_material", "id": "bell\u0007"}]})
        self.assertEqual(status, 400)
        self.assertEqual(doc["pointer"], "/edits/0/id")

    def test_head_on_render_does_not_render(self):
        renders = self.server.counters()["renders"]
        r = exchange(self.port, request("HEAD", "/v1/render?width=64&height=64"), head=True)
        self.assertEqual(r.status, 405)
        self.assertEqual(r.headers.get("allow"), "GET, POST")
        self.assertEqual(self.server.counters()["renders"], renders)


class Amplification(ServerCase):
    """Small requests that used to cost hundreds of MB: Range, gzip, headers, shapes, churn."""

    ARGS = ["--demo", "--max-scene-triangles", "2000000"]

    def test_range_on_a_frame_is_ignored(self):
        # As many ranges as fit the 8 KiB a header line may have (httplib turned 2,700 of them
        # into a ~1 GB multipart answer).
        ranges = "bytes=" + ",".join(f"{i}-{i}" for i in range(900))
        plain = exchange(self.port, request("GET", "/v1/render?width=64&height=64"))
        rss = self.server.rss_mb()
        r = exchange(self.port, request("GET", "/v1/render?width=64&height=64", [("Range", ranges)]))
        self.assertEqual(r.status, 200)
        self.assertNotIn("content-range", r.headers)
        self.assertEqual(r.body, plain.body)
        self.assertLess(self.server.rss_mb() - rss, 50)

    def test_compressed_bodies_are_refused_before_inflating(self):
        bomb = gzip.compress(b'{"edits": [' + b" " * (64 << 20) + b"]}", 9)
        version, rss = self.server.version(), self.server.rss_mb()
        r = exchange(self.port, request("POST", "/v1/edits", [("Content-Encoding", "gzip")], bomb))
        self.assertProblem(r, 415, "unsupported-encoding")
        self.assertEqual(self.server.version(), version)
        self.assertLess(self.server.rss_mb() - rss, 32)

    def test_too_many_or_too_large_headers_are_431(self):
        many = [(f"X-{i}", "v") for i in range(101)]
        self.assertProblem(exchange(self.port, request("GET", "/v1/scene", many)), 431)
        self.assertProblem(exchange(self.port, request("GET", "/v1/scene", [("X", "v" * 40000)])),
                           431)
        # Millions of headers, streamed: the answer comes after the first 32 KiB.
        rss = self.server.rss_mb()
        conn = Conn(self.port)
        conn.send(b"GET /v1/scene HTTP/1.1\r\nHost: a\r\n")
        answered = None
        try:
            for _ in range(3000):
                conn.send(b"X-A: b\r\n" * 1000)
        except (BrokenPipeError, ConnectionResetError):
            pass
        answered = conn.response()
        self.assertProblem(answered, 431, "headers-too-large")
        conn.close()
        self.assertLess(self.server.rss_mb() - rss, 16)

    def test_the_scene_budget_refuses_a_batch_before_it_is_built(self):
        version = self.server.version()
        status, doc = self.server.json("POST", "/v1/edits", {"edits": [
            {"op": "add_mesh", "id": "big", "shape": {"type": "sphere", "segments": 2048}}]})
        self.assertEqual(status, 413, doc)
        self.assertEqual(doc["pointer"], "/edits/0")
        self.assertIn("max_scene_triangles", doc["detail"])
        self.assertEqual(self.server.version(), version)

    def test_mesh_churn_gives_memory_back(self):
        def scene(n):
            edits = []
            for i in range(n):
                edits.append({"op": "add_mesh", "id": f"c{i}",
                              "shape": {"type": "sphere", "segments": 24}})
                edits.append({"op": "add_instance", "id": f"ci{i}", "mesh": f"c{i}"})
            return edits

        peaks = []
        for _ in range(4):
            self.assertEqual(self.server.json("POST", "/v1/edits", {"edits": scene(1500)})[0], 200)
            self.assertEqual(self.server.call("POST", "/v1/commit")[0], 200)
            peaks.append(self.server.rss_mb())
            remove = [{"op": "remove_instance", "instance": f"ci{i}"} for i in range(1500)]
            remove += [{"op": "remove_mesh", "mesh": f"c{i}"} for i in range(1500)]
            self.assertEqual(self.server.json("POST", "/v1/edits", {"edits": remove})[0], 200)
            self.assertEqual(self.server.call("POST", "/v1/commit")[0], 200)
            memory = self.server.json("GET", "/v1/stats")[1]["memory_bytes"]
            self.assertGreaterEqual(memory["tlas"], 0)
            self.assertGreaterEqual(memory["blas"], 0)
        # Each cycle peaks about as high as the first, not higher and higher.
        self.assertLess(max(peaks), peaks[0] * 1.3 + 32, peaks)


class SlowClients(ServerCase):
    """Clients that trickle, stall or idle hold no worker and are cut off on time."""

    ARGS = ["--demo", "--header-timeout", "1", "--read-timeout", "2", "--keep-alive-timeout", "1",
            "--max-connections-per-client", "24", "--threads", "2"]

    def test_trickled_headers_and_bodies_are_cut_off_with_408_while_others_are_served(self):
        slow = []
        for i in range(12):  # many more than --threads
            conn = Conn(self.port)
            if i % 2:
                conn.send(b"GET /v1/scene HTTP/1.1\r\nHost: a\r\nX-Slow: ")
            else:
                conn.send(request("POST", "/v1/edits", [("Content-Length", "1000")]) + b'{"edits"')
            slow.append(conn)
        start = time.monotonic()
        for _ in range(10):
            self.assertEqual(exchange(self.port, request("GET", "/v1/scene")).status, 200)
        self.assertLess(time.monotonic() - start, 5)
        for conn in slow:
            r = conn.response()
            self.assertEqual(r.status, 408)
            self.assertTrue(conn.closed_within(5))
            conn.close()
        self.assertLess(time.monotonic() - start, 5)

    def test_one_byte_at_a_time_does_not_extend_the_deadline(self):
        conn = Conn(self.port)
        start = time.monotonic()
        for b in b"GET /v1/scene HTTP/1.1\r\nHost: a\r\nX-Very-Long-Header: " + b"a" * 100:
            conn.send(bytes([b]))
            if select.select([conn.sock], [], [], 0.05)[0]:
                break  # the server has answered
        self.assertEqual(conn.response().status, 408)
        self.assertLess(time.monotonic() - start, 2.5)
        conn.close()

    def test_idle_connections_are_closed_after_the_keep_alive_timeout(self):
        conn = Conn(self.port)
        conn.send(request("GET", "/v1/scene"))
        self.assertEqual(conn.response().status, 200)
        self.assertTrue(conn.closed_within(3))
        conn.close()
        silent = Conn(self.port)  # never sends a byte
        self.assertTrue(silent.closed_within(3))
        silent.close()

    def test_blank_lines_between_requests_neither_start_one_nor_keep_the_connection(self):
        conn = Conn(self.port)
        conn.send(request("GET", "/v1/scene") + b"\r\n")
        self.assertEqual(conn.response().status, 200)
        start = time.monotonic()
        try:
            for _ in range(10):  # CRLFs every 0.3 s for 3 s: the 1 s idle timeout still holds
                conn.send(b"\r\n")
                if select.select([conn.sock], [], [], 0.3)[0]:
                    break
        except (BrokenPipeError, ConnectionResetError):
            pass
        conn.sock.settimeout(3)
        rest = b""
        while chunk := conn.sock.recv(4096):
            rest += chunk
        self.assertEqual(rest, b"")  # closed without an answer: blank lines are no request
        self.assertLess(time.monotonic() - start, 2.5)
        conn.close()

    def test_beyond_the_per_client_limit_only_health_checks_are_answered(self):
        held = [Conn(self.port) for _ in range(24)]
        for conn in held:  # make sure each is accepted before the next test connection
            conn.send(b"GET")
        time.sleep(0.2)
        over = exchange(self.port, request("GET", "/v1/scene"))
        self.assertProblem(over, 429, "too-many-connections")
        self.assertEqual(exchange(self.port, request("GET", "/readyz")).status, 200)
        for conn in held:
            conn.close()
        time.sleep(0.2)
        self.assertEqual(exchange(self.port, request("GET", "/v1/scene")).status, 200)


class TokenAndDeadlines(ServerCase):
    """With a token, a render deadline and a shutdown grace."""

    ARGS = ["--demo", "--render-timeout", "2"]
    ENV = {"STRATA_TOKEN": "s3cret"}
    AUTH = ("Authorization", "Bearer s3cret")

    def tearDown(self):
        self.assertTrue(self.server.alive(), self.server.log()[-3000:])

    def test_unauthenticated_requests_are_refused_before_their_body_is_read(self):
        conn = Conn(self.port)
        conn.send(request("POST", "/v1/edits", [("Content-Length", str(200 << 20))]))
        self.assertProblem(conn.response(), 401, "unauthorized")
        self.assertTrue(conn.closed_within(5))
        conn.close()

    def test_a_render_past_its_deadline_is_stopped_with_a_clear_problem(self):
        start = time.monotonic()
        r = exchange(self.port, request("GET", "/v1/render?width=640&height=360&spp=4096",
                                        [self.AUTH]), timeout=30)
        doc = self.assertProblem(r, 503, "deadline-exceeded")
        self.assertIn("--render-timeout", doc["detail"])
        self.assertLess(time.monotonic() - start, 10)
        r = exchange(self.port, request("GET", "/v1/scene", [self.AUTH]))
        self.assertEqual(r.status, 200)

    def test_a_client_that_leaves_cancels_its_render(self):
        conn = Conn(self.port)
        conn.send(request("GET", "/v1/render?width=640&height=360&spp=4000", [self.AUTH]))
        time.sleep(0.5)
        conn.close()  # the client gives up
        # The engine is free again long before the render would have finished (the deadline is
        # 2 s here, the render ~1 minute): a commit, serialised with renders, goes through.
        start = time.monotonic()
        r = exchange(self.port, request("POST", "/v1/commit", [self.AUTH]), timeout=30)
        self.assertEqual(r.status, 200)
        self.assertLess(time.monotonic() - start, 2)
        metrics = exchange(self.port, request("GET", "/metrics", [self.AUTH])).body.decode()
        gone = re.search(r"^strata_http_clients_gone_total (\d+)", metrics, re.M)
        self.assertGreaterEqual(int(gone.group(1)), 1)


class Lifecycle(unittest.TestCase):
    """Signals, start-up refusals and the drain, each with a server of its own."""

    def test_sighup_is_logged_and_ignored(self):
        server = Server()
        try:
            server.signal(signal.SIGHUP)
            time.sleep(0.3)
            self.assertTrue(server.alive())
            self.assertEqual(exchange(server.port, request("GET", "/livez")).status, 200)
            self.assertIn("SIGHUP", server.log())
        finally:
            self.assertEqual(server.stop(), 0)

    def test_a_second_server_on_a_taken_port_fails_with_a_clear_error(self):
        first = Server()
        try:
            second = subprocess.run([SERVER, "--port", str(first.port)], capture_output=True,
                                    text=True, timeout=30)
            self.assertNotEqual(second.returncode, 0)
            self.assertIn("in use", second.stderr)
            self.assertEqual(exchange(first.port, request("GET", "/livez")).status, 200)
        finally:
            first.stop()

    def test_bad_hosts_and_tokens_are_refused_at_start_up(self):
        def run(args, env=None):
            full = dict(os.environ)
            full.pop("STRATA_TOKEN", None)
            full.update(env or {})
            return subprocess.run([SERVER, "--port", "0"] + args, capture_output=True, text=True,
                                  timeout=10, env=full)
        r = run(["--host", "not-a-host"])
        self.assertEqual(r.returncode, 2)
        self.assertIn("not an IP address or a name", r.stderr)
        r = run([], {"STRATA_TOKEN": ""})
        self.assertEqual(r.returncode, 2)
        self.assertIn("set but empty", r.stderr)
        r = run(["--token-file", "/dev/zero"])
        self.assertEqual(r.returncode, 2)
        self.assertIn("regular file", r.stderr)

    def test_while_draining_readyz_is_503_and_a_second_sigterm_exits_at_once(self):
        server = Server(["--demo", "--shutdown-grace", "30"])
        try:
            render = Conn(server.port, timeout=60)
            render.send(request("GET", "/v1/render?width=640&height=360&spp=4000"))
            time.sleep(0.5)
            server.signal(signal.SIGTERM)
            time.sleep(0.3)
            ready = exchange(server.port, request("GET", "/readyz"))
            self.assertEqual(ready.status, 503)
            self.assertEqual(exchange(server.port, request("GET", "/livez")).status, 200)
            self.assertEqual(exchange(server.port, request("GET", "/v1/scene")).status, 503)
            start = time.monotonic()
            server.signal(signal.SIGTERM)
            self.assertEqual(server.wait(5), 128 + signal.SIGTERM)
            self.assertLess(time.monotonic() - start, 2)
            render.close()
        finally:
            server.stop()

    def test_sigterm_stops_a_long_render_after_the_grace(self):
        server = Server(["--demo", "--shutdown-grace", "1"])
        try:
            render = Conn(server.port, timeout=60)
            render.send(request("GET", "/v1/render?width=640&height=360&spp=4000"))
            time.sleep(0.5)
            start = time.monotonic()
            server.signal(signal.SIGTERM)
            r = render.response()
            self.assertEqual(r.status, 503)
            self.assertEqual(server.wait(10), 0)
            self.assertLess(time.monotonic() - start, 5)
            render.close()
        finally:
            server.stop()


if __name__ == "__main__":
    unittest.main()

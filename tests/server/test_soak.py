"""A bounded soak (about 40 s): editors, mesh churn, renderers (some impatient), readers and slow
clients against one real server at once. No well-behaved request may get a 5xx or lose its
connection, and resident memory must stay bounded: each churn cycle peaks about where the first
did, and clearing the scene gives the memory back.
"""

import random
import threading
import time
import unittest

from hostile import Conn, Server, exchange, request

DURATION = 35.0


class Worker(threading.Thread):
    """Runs `step` until stopped, recording every status and any failure."""

    def __init__(self, name, step, stop):
        super().__init__(daemon=True, name=name)
        self.step, self.stop_event = step, stop
        self.statuses, self.errors = {}, []

    def run(self):
        rng = random.Random(hash(self.name))
        while not self.stop_event.is_set():
            try:
                for status in self.step(rng):
                    self.statuses[status] = self.statuses.get(status, 0) + 1
            except Exception as e:  # pylint: disable=broad-except
                self.errors.append(f"{self.name}: {e!r}")
                self.stop_event.wait(0.2)


class Soak(unittest.TestCase):
    def test_mixed_load_gives_no_5xx_and_bounded_memory(self):
        server = Server(["--demo", "--render-timeout", "20"])
        stop = threading.Event()
        rss = []

        def edit(edits):
            return server.call("POST", "/v1/edits", {"edits": edits})[0]

        def editor(tag):
            counter = [0]

            def step(rng):
                counter[0] += 1
                n = counter[0]
                yield edit([{"op": "add_mesh", "id": f"{tag}{n}",
                             "shape": {"type": "sphere", "segments": rng.choice([8, 16, 32])}},
                            {"op": "add_instance", "id": f"{tag}i{n}", "mesh": f"{tag}{n}",
                             "transform": {"translate": [rng.uniform(-5, 5), 0,
                                                         rng.uniform(-5, 5)]}}])
                yield edit([{"op": "set_transform", "instance": f"{tag}i{n}",
                             "transform": {"rotate_deg": [0, rng.uniform(0, 360), 0]}}])
                if n > 3:
                    yield edit([{"op": "remove_instance", "instance": f"{tag}i{n - 3}"},
                                {"op": "remove_mesh", "mesh": f"{tag}{n - 3}"}])
            return step

        def churn(rng):
            # Many meshes in and out: the pattern that used to grow RSS cycle after cycle.
            adds = []
            for i in range(400):
                adds += [{"op": "add_mesh", "id": f"churn{i}",
                          "shape": {"type": "sphere", "segments": 24}},
                         {"op": "add_instance", "id": f"churni{i}", "mesh": f"churn{i}",
                          "transform": {"translate": [i % 20, 5, i // 20]}}]
            yield edit(adds)
            yield server.call("POST", "/v1/commit")[0]
            removes = [{"op": "remove_instance", "instance": f"churni{i}"} for i in range(400)]
            removes += [{"op": "remove_mesh", "mesh": f"churn{i}"} for i in range(400)]
            yield edit(removes)
            yield server.call("POST", "/v1/commit")[0]

        def renderer(rng):
            size = rng.choice([32, 64, 96])
            yield server.call("GET", f"/v1/render?width={size}&height={size}&spp="
                                     f"{rng.choice([1, 2, 4])}", timeout=60)[0]
            yield server.call("POST", "/v1/render",
                              {"width": 48, "height": 32, "format": "exr", "aovs": ["depth"],
                               "camera": {"eye": [rng.uniform(-9, 9), 3, 9]}}, timeout=60)[0]

        def impatient(rng):
            # A long render whose client gives up: the server must stop it, not queue behind it.
            conn = Conn(server.port)
            conn.send(request("GET", "/v1/render?width=320&height=180&spp=512"))
            time.sleep(rng.uniform(0.05, 0.3))
            conn.close()
            return []

        def reader(rng):
            for path in ["/v1/scene", "/v1/stats", "/metrics", "/v1/plan", "/readyz"]:
                yield server.call("GET", path)[0]

        def slow(rng):
            # Hostile clients are not measured: they only have to be there.
            conn = Conn(server.port, timeout=15)
            kind = rng.randrange(3)
            try:
                if kind == 0:
                    conn.send(b"GET /v1/scene HTTP/1.1\r\nHost: a\r\n")
                    for _ in range(20):
                        if stop.wait(0.5):
                            break
                        conn.send(b"X")
                elif kind == 1:
                    conn.send(request("POST", "/v1/edits", [("Content-Length", "50000")]) + b"{")
                    stop.wait(rng.uniform(1, 5))
                else:
                    stop.wait(rng.uniform(1, 5))
            except OSError:
                pass
            finally:
                conn.close()
            return []

        workers = [Worker("editor-a", editor("a"), stop), Worker("editor-b", editor("b"), stop),
                   Worker("churn", churn, stop), Worker("renderer-1", renderer, stop),
                   Worker("renderer-2", renderer, stop), Worker("impatient", impatient, stop),
                   Worker("reader", reader, stop)]
        slow_clients = [Worker(f"slow-{i}", slow, stop) for i in range(8)]
        try:
            for w in workers + slow_clients:
                w.start()
            start = time.monotonic()
            while time.monotonic() - start < DURATION:
                rss.append((time.monotonic() - start, server.rss_mb()))
                time.sleep(0.5)
            stop.set()
            for w in workers + slow_clients:
                w.join(60)

            statuses = {}
            for w in workers:
                for status, n in w.statuses.items():
                    statuses[status] = statuses.get(status, 0) + n
            errors = [e for w in workers for e in w.errors]
            print(f"\nsoak: {sum(statuses.values())} requests, statuses {sorted(statuses.items())}")
            self.assertEqual(errors, [])
            self.assertEqual({s: n for s, n in statuses.items() if s >= 500}, {})
            self.assertGreater(statuses.get(200, 0), 100)

            # Memory: the churn peaks repeat (no growth cycle after cycle), and a cleared scene
            # gives the memory back.
            early = max(r for t, r in rss if t < DURATION / 3)
            late = max(r for t, r in rss if t >= 2 * DURATION / 3)
            self.assertEqual(server.call("POST", "/v1/edits", {"edits": [{"op": "clear"}]})[0], 200)
            self.assertEqual(server.call("POST", "/v1/commit")[0], 200)
            time.sleep(0.5)
            cleared = server.rss_mb()
            print(f"soak: RSS max {early:.0f} MB in the first third, {late:.0f} MB in the last "
                  f"third, {cleared:.0f} MB after clear")
            self.assertLess(late, early * 1.25 + 48)
            self.assertLess(cleared, early)
            self.assertEqual(exchange(server.port, request("GET", "/livez")).status, 200)
            self.assertEqual(server.stop(), 0)
        finally:
            stop.set()
            server.stop()


if __name__ == "__main__":
    unittest.main()

"""Replicas following one edit log in Redis Streams (issue 16), with a real redis-server (AOF on,
fsync always) and real strata-server processes: convergence, one winner per version under
If-Match races, a replica SIGKILLed and restarted, Redis SIGKILLed mid-stream, a poisoned entry,
read-your-writes with min_version, a replica joining from a snapshot after trimming, and replicas
that hold a scene jumping to the snapshot over entries trimmed while they were stopped.
Skipped, saying so, only where redis-server is not installed (scripts/install-deps.sh installs it).
"""

import json
import socket
import shutil
import signal
import struct
import tempfile
import threading
import time
import unittest
import uuid

import durable_scene
from journal_bytes import clears, crc32c, log_entry
from hostile import Server
from redis_fixture import REDIS_SERVER, RedisProcess, free_ports

RENDER = "/v1/render?width=64&height=48&spp=2"
# Frames across replicas: odd sizes, a camera override that sees every instance.
SPLIT_VIEW = "width=83&height=61&spp=2&eye=3.5,4,13&target=3.5,0.5,0"
SPLIT_RENDERS = [
    f"/v1/render?{SPLIT_VIEW}",
    f"/v1/render?{SPLIT_VIEW}&format=exr&aovs=albedo,depth,instance_id,mesh_id",
    f"/v1/render?{SPLIT_VIEW.replace('spp=2', 'spp=1')}&filter=atrous&exposure=0.5",
]
# Filtered from 2 samples on, the filter reads each pixel's measured noise, which bands do not
# carry: the coordinator renders such a frame whole and says so.
SPLIT_WHOLE_RENDER = f"/v1/render?{SPLIT_VIEW}&filter=atrous&exposure=0.5"


@unittest.skipIf(REDIS_SERVER is None,
                 "redis-server is not installed (scripts/install-deps.sh installs it)")
class Replicas(unittest.TestCase):
    def setUp(self):
        self.redis = RedisProcess()
        self.addCleanup(self.redis.stop)
        self.stream = "strata-" + uuid.uuid4().hex[:8]

    def replica(self, *extra, port=0):
        s = Server(["--log", self.redis.url(self.stream), "--threads", "8"] + list(extra),
                   port=port)
        self.addCleanup(s.stop)
        return s

    def peered_replicas(self, n=3, *extra):
        """n replicas, each started with the other n-1 as --peers."""
        ports = free_ports(n)
        urls = [f"http://127.0.0.1:{p}" for p in ports]
        return [self.replica("--peers", ",".join(u for u in urls if u != urls[i]), *extra,
                             port=ports[i]) for i in range(n)]

    def replicas(self, n=3, *extra):
        return [self.replica(*extra) for _ in range(n)]

    def at(self, server, version, path="/v1/scene"):
        sep = "&" if "?" in path else "?"
        return server.call("GET", f"{path}{sep}min_version={version}")

    def assert_converged(self, servers, version):
        scenes, frames = [], []
        for s in servers:
            status, _, body = self.at(s, version)
            self.assertEqual(status, 200, body)
            scenes.append(json.loads(body))
            status, _, frame = self.at(s, version, RENDER)
            self.assertEqual(status, 200, frame[:300])
            frames.append(frame)
        for scene in scenes:
            self.assertEqual(scene["version"], version)
            self.assertEqual(scene, scenes[0])
        for frame in frames:
            self.assertEqual(frame, frames[0], "frames differ between replicas")

    def append_entry(self, record, version):
        """Appends `record` to the log as the entry of `version`, as a writer would."""
        self.redis.command("XADD", self.stream, f"{version}-0", "v", str(version), "t", "0",
                           "r", record)
        self.redis.command("SET", self.stream + ":version", str(version))

    def stopped_detail(self, server):
        """Waits (10 s at most) for `server` to stop following the log; its /readyz detail."""
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and server.call("GET", "/readyz")[0] == 200:
            time.sleep(0.05)
        status, _, body = server.call("GET", "/readyz")
        self.assertEqual(status, 503)
        return json.loads(body)["detail"]

    def stream_batches(self, servers, first, count):
        for n in range(first, first + count):
            s = servers[n % len(servers)]
            status, answer = s.json("POST", "/v1/edits", durable_scene.batch(n))
            self.assertEqual(status, 200, answer)
            self.assertEqual(answer["version"], n + 1)
        return first + count

    def test_round_robin_batches_converge_to_one_version_and_identical_frames(self):
        servers = self.replicas()
        self.stream_batches(servers, 0, 24)
        self.assert_converged(servers, 24)
        for s in servers:
            self.assertEqual(durable_scene.check(s, 24), "")
        self.assertEqual(self.redis.command("XLEN", self.stream), 24)

    def test_undo_and_redo_on_any_replica_take_back_the_newest_batch_of_the_log(self):
        a, b = self.replicas(2)

        def instances(server, version):
            status, _, body = self.at(server, version, "/v1/scene/instances?limit=1000")
            self.assertEqual(status, 200, body)
            items = json.loads(body)["items"]
            for i in items:
                del i["version"]
            return sorted(items, key=lambda i: i["id"])

        states = {}
        for n in range(6):
            self.stream_batches([a, b], n, 1)
            states[n + 1] = instances(a, n + 1)
        # b undoes what a wrote last (version 6), a then undoes version 5: both follow one log,
        # so both hold the same stacks.
        status, answer = b.json("POST", "/v1/undo", None)
        self.assertEqual((status, answer.get("undone")), (200, 6), answer)
        status, answer = a.json("POST", "/v1/undo", None)
        self.assertEqual((status, answer.get("undone")), (200, 5), answer)
        status, answer = b.json("POST", "/v1/redo", None)
        self.assertEqual((status, answer.get("redone"), answer.get("version")), (200, 5, 9),
                         answer)
        for s in (a, b):
            self.assertEqual(instances(s, 9), states[5])
        self.assert_converged([a, b], 9)
        histories = [self.at(s, 9, "/v1/history?limit=4")[2] for s in (a, b)]
        entries = [[(e["version"], e["kind"], e.get("target")) for e in json.loads(h)["entries"]]
                   for h in histories]
        self.assertEqual(entries[0], [(9, "redo", 5), (8, "undo", 5), (7, "undo", 6),
                                      (6, "edit", None)])
        self.assertEqual(entries[0], entries[1])
        # The times are the writers': every replica shows the same ones.
        times = [[e["time"] for e in json.loads(h)["entries"]] for h in histories]
        self.assertEqual(times[0], times[1])

    def test_a_batch_that_depends_on_a_write_just_made_on_another_replica_is_accepted(self):
        a, b = self.replicas(2)
        for n in range(0, 40, 4):
            # Batch n adds mesh-n on a; batch n+1 instances it on b, which may not have applied
            # batch n yet: b must catch up with the log before refusing it.
            self.stream_batches([a], n, 1)
            self.stream_batches([b], n + 1, 3)
        self.assert_converged([a, b], 40)

    def test_concurrent_if_match_writers_on_different_replicas_get_one_winner_per_version(self):
        servers = self.replicas()
        for version in range(8):
            results = [None] * len(servers)
            barrier = threading.Barrier(len(servers))

            def write(k):
                barrier.wait()
                body = {"edits": [{"op": "add_material", "id": f"w{k}-v{version}"}]}
                results[k] = servers[k].json("POST", "/v1/edits", body,
                                             headers={"If-Match": f'"{version}"'})

            threads = [threading.Thread(target=write, args=(k,)) for k in range(len(servers))]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            statuses = sorted(r[0] for r in results)
            self.assertEqual(statuses, [200] + [412] * (len(servers) - 1), results)
            winner = next(r[1] for r in results if r[0] == 200)
            self.assertEqual(winner["version"], version + 1)
        self.assert_converged(servers, 8)
        status, materials = servers[0].json("GET", "/v1/scene/materials?min_version=8")
        self.assertEqual(status, 200)
        self.assertEqual(len(materials["items"]), 8, materials)

    def test_a_replica_killed_and_restarted_catches_up(self):
        servers = self.replicas()
        n = self.stream_batches(servers, 0, 10)
        servers[2].kill()
        n = self.stream_batches(servers[:2], n, 10)
        servers[2] = self.replica()
        n = self.stream_batches(servers, n, 4)
        self.assert_converged(servers, n)
        self.assertEqual(durable_scene.check(servers[2], n), "")

    def test_redis_restarted_mid_stream_loses_no_acknowledged_batch(self):
        servers = self.replicas()
        acked, refused, stop = [], [], threading.Event()

        def writer():
            k = 0
            while not stop.is_set():
                body = {"edits": [{"op": "add_material", "id": f"m{k}"}]}
                try:
                    status, answer = servers[k % 3].json("POST", "/v1/edits", body)
                except OSError:
                    status, answer = 0, {}
                (acked if status == 200 else refused).append((k, status, answer))
                k += 1

        t = threading.Thread(target=writer, daemon=True)
        t.start()
        self.addCleanup(stop.set)
        time.sleep(0.8)
        self.redis.kill()
        time.sleep(0.5)
        # Redis is down: writes are refused with a problem, renders of the applied version work.
        status, headers, body = servers[0].call("POST", "/v1/edits",
                                                {"edits": [{"op": "add_material", "id": "x"}]})
        self.assertEqual(status, 503, body)
        self.assertIn("problem+json", headers.get("Content-Type", ""))
        self.assertEqual(servers[1].call("GET", RENDER)[0], 200)
        self.redis.start()
        time.sleep(1.0)
        stop.set()
        t.join()
        self.assertGreater(len(acked), 5)
        self.assertTrue(any(r[1] == 503 for r in refused), refused[:5])
        head = int(self.redis.command("GET", self.stream + ":version"))
        self.assertGreaterEqual(head, max(a[2]["version"] for a in acked))
        self.assert_converged(servers, head)
        for s in servers:
            status, listing = s.json("GET", "/v1/scene/materials?limit=10000")
            have = {m["id"] for m in listing["items"]}
            missing = [k for k, _, _ in acked if f"m{k}" not in have]
            self.assertEqual(missing, [], "acknowledged batches lost")

    def test_a_poisoned_entry_stops_the_replicas_loudly(self):
        servers = self.replicas(2)
        n = self.stream_batches(servers, 0, 3)
        # An entry no Strata server wrote: a bad checksum.
        self.append_entry(b"\x04\x00\x00\x00\xde\xad\xbe\xef" + (n + 1).to_bytes(8, "little")
                          + b"\x00\x00\x00\x00", n + 1)
        for s in servers:
            self.assertIn("poisoned", self.stopped_detail(s))
            self.assertIn("strata_replica_stopped 1", s.call("GET", "/metrics")[2].decode())
            self.assertIn("replica stopped", s.log())
            # Reads of the last applied version still work; writes are refused.
            self.assertEqual(durable_scene.check(s, n), "")
            status, _ = s.json("POST", "/v1/edits", durable_scene.batch(n))
            self.assertEqual(status, 503)

    def test_a_replica_started_before_redis_waits_then_joins(self):
        self.redis.kill()
        s = Server(["--log", self.redis.url(self.stream)], wait_ready=False)
        self.addCleanup(s.stop)
        time.sleep(0.5)
        status, _, body = s.call("GET", "/readyz")
        self.assertEqual(status, 503)
        self.assertIn("Redis unreachable", json.loads(body)["detail"])
        status, _, body = s.call("POST", "/v1/edits", durable_scene.batch(0))
        self.assertEqual(status, 503, body)
        self.assertIn("edit log", json.loads(body)["detail"])
        self.assertEqual(s.call("GET", "/v1/scene")[0], 200)  # reads of version 0 work
        self.redis.start()
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and s.call("GET", "/readyz")[0] != 200:
            time.sleep(0.05)
        self.assertEqual(s.call("GET", "/readyz")[0], 200)
        self.assertEqual(self.stream_batches([s], 0, 2), 2)

    def test_the_demo_scene_is_appended_once_to_an_empty_log(self):
        servers = self.replicas(2, "--demo")
        self.assert_converged(servers, 1)
        self.assertEqual(self.redis.command("XLEN", self.stream), 1)
        self.assertIn("--demo ignored: the edit log holds a scene already", servers[1].log())

    def test_an_entry_that_does_not_apply_stops_the_replicas_loudly(self):
        servers = self.replicas(2)
        n = self.stream_batches(servers, 0, 2)
        self.assertEqual(crc32c(b"123456789"), 0xE3069283)
        # Checksum and encoding are fine (one remove_instance, kind tag 9), but the instance does
        # not exist: applying it would fail on every replica.
        payload = (1).to_bytes(4, "little") + bytes([9]) + (4).to_bytes(4, "little") + b"nope"
        self.append_entry(log_entry(payload, n + 1), n + 1)
        for s in servers:
            detail = self.stopped_detail(s)
            self.assertIn(f"does not apply at version {n}", detail)
            self.assertIn("nope", detail)
            self.assertEqual(durable_scene.check(s, n), "")

    def test_an_entry_whose_id_is_not_utf8_stops_the_replicas_loudly_and_they_keep_serving(self):
        servers = self.replicas(2)
        n = self.stream_batches(servers, 0, 2)
        # A well-formed add_light (kind tag 17) whose id is not UTF-8: before the engine held
        # every way in to the id rule, every replica applied it and then aborted writing JSON.
        light = struct.pack("<B3f3f3f5f", 0, 0, 3, 0, 0, -1, 0, 1, 1, 1, 10, 30, 25, 1, 1)
        payload = ((1).to_bytes(4, "little") + bytes([17]) + (2).to_bytes(4, "little") + b"m\xff"
                   + light)
        self.append_entry(log_entry(payload, n + 1), n + 1)
        for s in servers:
            detail = self.stopped_detail(s)
            self.assertIn(f"does not apply at version {n}", detail)
            self.assertIn("light id is not valid UTF-8", detail)
            # The process lives and serves the last version it applied.
            self.assertEqual(durable_scene.check(s, n), "")
            self.assertEqual(s.call("GET", RENDER)[0], 200)
            self.assertIsNone(s.process.poll())

    def assert_reset_refuses_writes_and_stops(self, reset, reason):
        """Two replicas at version 3; `reset()` rewrites the log under them. Writes answer 503
        within the write deadline naming `reason`, /readyz reports it, reads go on, and SIGTERM
        ends the process within the grace period."""
        servers = self.replicas(2, "--log-write-timeout-ms", "1500", "--shutdown-grace", "1")
        n = self.stream_batches(servers, 0, 3)
        reset()
        a, b = servers
        # Eight writers at once (as many as the workers): each is answered within the deadline,
        # and a read between them is not held up.
        answers = []

        def write(k):
            started = time.monotonic()
            status, answer = a.json("POST", "/v1/edits", durable_scene.batch(n + k))
            answers.append((status, answer, time.monotonic() - started))

        writers = [threading.Thread(target=write, args=(k,)) for k in range(8)]
        for t in writers:
            t.start()
        started = time.monotonic()
        self.assertEqual(a.call("GET", "/v1/scene")[0], 200)
        self.assertLess(time.monotonic() - started, 1.5)
        for t in writers:
            t.join()
        for status, answer, seconds in answers:
            self.assertEqual(status, 503, answer)
            self.assertIn(reason, answer["detail"])
            self.assertLess(seconds, 3.0)
        for s in servers:
            self.assertIn(reason, self.stopped_detail(s))
            self.assertEqual(durable_scene.check(s, n), "")
            self.assertEqual(s.json("POST", "/v1/edits", durable_scene.batch(n))[0], 503)
        # SIGTERM ends a stopped replica within its grace (1 s) plus the watchdog's 2 s.
        started = time.monotonic()
        b.signal(signal.SIGTERM)
        self.assertIsNotNone(b.wait(4.0), "SIGTERM did not end the replica")
        self.assertLess(time.monotonic() - started, 4.0)

    def test_a_flushed_redis_stops_the_replicas_and_writes_answer_503_in_time(self):
        self.assert_reset_refuses_writes_and_stops(
            lambda: self.redis.command("FLUSHALL"), "behind this replica's version 3")

    def test_a_version_key_set_back_stops_the_replicas(self):
        self.assert_reset_refuses_writes_and_stops(
            lambda: self.redis.command("SET", self.stream + ":version", "1"),
            "behind this replica's version 3")

    def test_an_emptied_stream_stops_the_replicas(self):
        def empty():
            self.redis.command("XTRIM", self.stream, "MAXLEN", "0")
        servers = self.replicas(2)
        n = self.stream_batches(servers, 0, 3)
        empty()
        for s in servers:
            detail = self.stopped_detail(s)
            self.assertIn("the edit log was rewritten", detail)
            self.assertIn("the stream was emptied", detail)
            self.assertEqual(durable_scene.check(s, n), "")
        status, answer = servers[0].json("POST", "/v1/edits", durable_scene.batch(n))
        self.assertEqual(status, 503)
        self.assertIn("stopped following the edit log", answer["detail"])

    def test_reads_waiting_for_a_far_version_hold_no_worker(self):
        # Two workers; sixteen clients loop on reads of a version that never comes. Before,
        # each held a worker for the whole wait and normal reads queued behind them.
        s = Server(["--log", self.redis.url(self.stream), "--threads", "2",
                    "--min-version-wait-ms", "3000", "--max-waiting-reads-per-client", "32"])
        self.addCleanup(s.stop)
        n = self.stream_batches([s], 0, 1)
        stop = threading.Event()
        waited = []

        def waiter():
            while not stop.is_set():
                status, _, body = s.call("GET", f"/v1/scene?min_version={n + 1000}")
                waited.append(status)

        loops = [threading.Thread(target=waiter) for _ in range(16)]
        for t in loops:
            t.start()
        time.sleep(0.3)
        try:
            for _ in range(10):
                started = time.monotonic()
                self.assertEqual(s.call("GET", "/v1/scene")[0], 200)
                self.assertEqual(s.call("GET", RENDER)[0], 200)
                self.assertLess(time.monotonic() - started, 1.0)
            metrics = s.call("GET", "/metrics")[2].decode()
            waiting = [line for line in metrics.splitlines()
                       if line.startswith("strata_http_reads_waiting ")]
            self.assertGreaterEqual(float(waiting[0].split()[1]), 12, waiting)
            # A waiting read is answered as soon as its version arrives (written elsewhere).
            got = []
            reader = threading.Thread(
                target=lambda: got.append(s.call("GET", f"/v1/scene?min_version={n + 1}")))
            reader.start()
            time.sleep(0.2)
            self.assertEqual(s.json("POST", "/v1/edits", durable_scene.batch(n))[0], 200)
            reader.join(2.0)
            self.assertEqual(got[0][0], 200)
            self.assertEqual(json.loads(got[0][2])["version"], n + 1)
        finally:
            stop.set()
            for t in loops:
                t.join()
        self.assertEqual(set(waited), {503})

    def test_waiting_reads_are_capped_per_client(self):
        s = self.replica("--min-version-wait-ms", "2000", "--max-waiting-reads-per-client", "3")
        results = []

        def wait_far():
            results.append(s.call("GET", "/v1/scene?min_version=99"))

        held = [threading.Thread(target=wait_far) for _ in range(3)]
        for t in held:
            t.start()
        time.sleep(0.3)
        status, headers, body = s.call("GET", "/v1/scene?min_version=99")
        self.assertEqual(status, 503)
        self.assertIn("too many reads are waiting", json.loads(body)["detail"])
        self.assertEqual(headers.get("Retry-After"), "1")
        self.assertEqual(s.call("GET", "/v1/scene")[0], 200)
        for t in held:
            t.join()
        self.assertEqual([r[0] for r in results], [503, 503, 503])
        for r in results:
            self.assertIn("behind min_version 99", json.loads(r[2])["detail"])
        self.assertIn("strata_http_waits_refused_total 1", s.call("GET", "/metrics")[2].decode())

    def test_an_entry_of_more_edits_than_a_batch_may_hold_stops_the_replicas_before_decoding(self):
        servers = self.replicas(2, "--max-batch-edits", "1000")
        n = self.stream_batches(servers, 0, 2)
        # 5 MB of one-byte clears: 5M edits, 1.2 GB once decoded.
        self.append_entry(log_entry(clears(5_000_000), n + 1), n + 1)
        for s in servers:
            detail = self.stopped_detail(s)
            self.assertIn("holds 5000000 edits, more than a batch may hold", detail)
            self.assertEqual(durable_scene.check(s, n), "")
            self.assertLess(s.rss_mb(), 400)

    def test_min_version_waits_for_the_replica_and_names_the_lag_when_it_cannot(self):
        a, b = self.replicas(2, "--min-version-wait-ms", "400")
        status, answer = a.json("POST", "/v1/edits", durable_scene.batch(0))
        self.assertEqual(status, 200)
        status, _, body = b.call("GET", "/v1/scene", headers={"X-Strata-Min-Version": "1"})
        self.assertEqual(status, 200)
        self.assertEqual(json.loads(body)["version"], 1)
        status, headers, body = b.call("GET", "/v1/render?width=8&height=8&min_version=5")
        self.assertEqual(status, 503)
        self.assertIn("behind min_version 5", json.loads(body)["detail"])
        self.assertEqual(b.call("GET", "/v1/scene?min_version=x")[0], 400)
        status, _, body = b.call("GET", "/readyz")
        self.assertEqual(status, 200)
        ready = json.loads(body)["replica"]
        self.assertEqual(ready["applied_version"], 1)
        self.assertEqual(ready["lag_entries"], 0)
        metrics = b.call("GET", "/metrics")[2].decode()
        self.assertIn("strata_replica_applied_version 1", metrics)
        self.assertIn("strata_replica_lag_seconds 0", metrics)

    def test_min_version_without_a_log_waits_for_this_servers_own_writes(self):
        s = Server(["--min-version-wait-ms", "300"])
        self.addCleanup(s.stop)
        status, _, body = s.call("GET", "/v1/scene?min_version=1")
        self.assertEqual(status, 503)
        self.assertIn("behind min_version 1", json.loads(body)["detail"])
        done = []
        reader = threading.Thread(
            target=lambda: done.append(s.call("GET", "/v1/scene?min_version=1")[0]))
        reader.start()
        time.sleep(0.05)
        self.assertEqual(s.json("POST", "/v1/edits", durable_scene.batch(0))[0], 200)
        reader.join()
        self.assertEqual(done, [200])

    def test_a_replica_joining_after_trimming_loads_the_snapshot_and_follows(self):
        servers = self.replicas(2, "--log-snapshot-every", "5")
        n = self.stream_batches(servers, 0, 23)
        snap = self.stored_snapshot_at_least(20)
        # Trimmed below the snapshot the newest replaced (at least 15): the log is shorter.
        first = self.redis.command("XRANGE", self.stream, "-", "+", "COUNT", "1")[0][0]
        self.assertGreater(int(first.split(b"-")[0]), 10)
        self.assertLess(self.redis.command("XLEN", self.stream), 13)
        data = tempfile.mkdtemp(prefix="strata-replica-")
        self.addCleanup(shutil.rmtree, data, True)
        late = self.replica("--log-snapshot-every", "5", "--data", data)
        self.assertIn(f"loaded the snapshot of version {snap}", late.log())
        servers.append(late)
        n = self.stream_batches(servers, n, 3)
        self.assert_converged(servers, n)
        self.assertEqual(durable_scene.check(late, n), "")
        # Its directory holds the snapshot it joined from and what followed: it restarts alone.
        late.stop()
        alone = Server(["--data", data])
        self.addCleanup(alone.stop)
        self.assertEqual(durable_scene.check(alone, n), "")

    def stored_snapshot_at_least(self, version):
        """Waits (up to 10 s) until Redis holds a snapshot of at least `version`; returns its."""
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            snap = self.redis.command("HGET", self.stream + ":snapshot", "version")
            if snap is not None and int(snap) >= version:
                break
            time.sleep(0.05)
        snap = int(self.redis.command("HGET", self.stream + ":snapshot", "version"))
        self.assertGreaterEqual(snap, version)
        return snap

    def trim_past(self, writer, n, behind):
        """Streams batches through `writer` until a stored snapshot is at least 20 and the log no
        longer holds the entry after version `behind`; returns the version reached."""
        n = self.stream_batches([writer], n, 23 - n)
        snap = self.stored_snapshot_at_least(20)
        first = self.redis.command("XRANGE", self.stream, "-", "+", "COUNT", "1")[0][0]
        self.assertGreater(int(first.split(b"-")[0]), behind + 1, "the gap should be real")
        return n, snap

    def metric(self, server, name):
        _, _, text = server.call("GET", "/metrics")
        for line in text.decode().splitlines():
            if line.startswith(name + " "):
                return float(line.split()[1])
        self.fail(f"{name} missing from /metrics")

    def test_a_replica_restarted_on_its_data_directory_after_trimming_jumps_to_the_snapshot(self):
        data = tempfile.mkdtemp(prefix="strata-replica-")
        self.addCleanup(shutil.rmtree, data, True)
        a = self.replica("--log-snapshot-every", "5")
        b = self.replica("--log-snapshot-every", "5", "--data", data)
        n = self.stream_batches([a, b], 0, 7)
        self.assertEqual(self.at(b, n)[0], 200)
        b.kill()
        n, snap = self.trim_past(a, n, 7)
        # Restarted on its directory, B recovers version 7, finds the entries after it trimmed
        # and replaces its scene with the snapshot instead of stopping.
        b = self.replica("--log-snapshot-every", "5", "--data", data)
        self.assertEqual(self.at(b, n)[0], 200)
        log = b.log()
        self.assertIn("recovered version 7", log)
        self.assertIn(f"loaded the snapshot of version {snap}", log)
        self.assertIn("in place of version 7", log)
        self.assertEqual(self.metric(b, "strata_replica_snapshot_jumps_total"), 1)
        self.assertEqual(self.metric(b, "strata_replica_stopped"), 0)
        n = self.stream_batches([a, b], n, 3)
        self.assertEqual(self.metric(b, "strata_durable_last_snapshot_version"), snap)
        self.assert_converged([a, b], n)
        self.assertEqual(durable_scene.check(b, n), "")
        # The directory now holds the snapshot and what followed: alone, without the log, it
        # recovers version n, not version 7 followed by a gap.
        b.stop()
        alone = Server(["--data", data])
        self.addCleanup(alone.stop)
        self.assertIn(f"recovered version {n} (snapshot {snap}", alone.log())
        self.assertEqual(durable_scene.check(alone, n), "")
        self.assertEqual(self.at(alone, n, RENDER)[2], self.at(a, n, RENDER)[2])

    def test_a_replica_paused_while_the_log_was_trimmed_jumps_to_the_snapshot_when_resumed(self):
        a = self.replica("--log-snapshot-every", "5")
        b = self.replica("--log-snapshot-every", "5")
        n = self.stream_batches([a, b], 0, 7)
        self.assertEqual(self.at(b, n)[0], 200)
        b.signal(signal.SIGSTOP)
        self.addCleanup(b.signal, signal.SIGCONT)
        n, snap = self.trim_past(a, n, 8)  # the entry it may have had queued, at most
        b.signal(signal.SIGCONT)
        self.assertEqual(self.at(b, n)[0], 200)
        n = self.stream_batches([a, b], n, 3)
        self.assert_converged([a, b], n)
        self.assertEqual(durable_scene.check(b, n), "")
        self.assertIn(f"loaded the snapshot of version {snap}", b.log())
        self.assertEqual(self.metric(b, "strata_replica_snapshot_jumps_total"), 1)
        self.assertEqual(self.metric(a, "strata_replica_snapshot_jumps_total"), 0)

    def assert_split_equals_single(self, coordinator, path, split, version, used_peers):
        single = coordinator.call("GET", f"{path}&min_version={version}")
        self.assertEqual(single[0], 200, single[2][:300])
        status, headers, frame = coordinator.call("GET",
                                                  f"{path}&split={split}&min_version={version}")
        self.assertEqual(status, 200, frame[:300])
        self.assertEqual(headers["ETag"], f'"{version}"')
        self.assertEqual(headers["Content-Type"], single[1]["Content-Type"])
        bands = headers["X-Strata-Split"]
        self.assertTrue(bands.startswith(f"{split} bands at version {version}: local"), bands)
        if used_peers:
            self.assertNotIn("local (", bands)
        self.assertTrue(frame == single[2], f"split={split} {path} differs from one render: "
                        f"{len(frame)} vs {len(single[2])} bytes; {bands}")
        return bands

    def test_a_split_render_is_the_bytes_of_a_single_render(self):
        servers = self.peered_replicas(3)
        n = self.stream_batches(servers, 0, 7)
        self.assert_converged(servers, n)
        for split in (2, 3):
            for path in SPLIT_RENDERS:
                self.assert_split_equals_single(servers[split % 3], path, split, n, True)
            single = servers[0].call("GET", f"{SPLIT_WHOLE_RENDER}&min_version={n}")
            status, headers, frame = servers[0].call(
                "GET", f"{SPLIT_WHOLE_RENDER}&split={split}&min_version={n}")
            self.assertEqual(status, 200, frame[:300])
            self.assertEqual(frame, single[2])
            self.assertTrue(headers["X-Strata-Split"].startswith(
                f"1 band at version {n}: local (not split: a filtered frame"), headers)
        # A POST body splits too; more bands than processes, or a band with split, are 422.
        status, headers, frame = servers[0].call(
            "POST", "/v1/render", {"width": 40, "height": 30, "split": 3, "camera": {"eye": [3, 2, 9]}})
        self.assertEqual(status, 200, frame[:300])
        self.assertEqual(frame, servers[0].call(
            "POST", "/v1/render", {"width": 40, "height": 30, "camera": {"eye": [3, 2, 9]}})[2])
        status, _, body = servers[0].call("GET", f"{SPLIT_RENDERS[0]}&split=4")
        self.assertEqual(status, 422, body)
        self.assertEqual(json.loads(body)["pointer"], "/split")
        self.assertIn("needs 3 peers", json.loads(body)["detail"])
        status, _, body = servers[0].call("GET", f"{SPLIT_RENDERS[0]}&split=2&band=0,8")
        self.assertEqual(status, 422, body)
        self.assertEqual(json.loads(body)["pointer"], "/split")

    def test_a_split_render_with_a_peer_down_renders_its_band_locally(self):
        servers = self.peered_replicas(3, "--peer-timeout-ms", "3000")
        n = self.stream_batches(servers, 0, 5)
        self.assert_converged(servers, n)
        down = servers[2].url
        servers[2].kill()
        for path in SPLIT_RENDERS[:2]:
            bands = self.assert_split_equals_single(servers[0], path, 3, n, False)
            self.assertIn(f"local ({down}:", bands)
            self.assertIn(servers[1].url, bands)
        # The survivors keep converging, and keep splitting.
        n = self.stream_batches(servers[:2], n, 2)
        self.assert_split_equals_single(servers[1], SPLIT_RENDERS[0], 2, n, True)


class SplitWithoutLog(unittest.TestCase):
    """Split renders need no shared log: any peers holding the scene at the frame's version do,
    and a peer at another version has its band rendered by the coordinator."""

    def test_peers_at_the_same_version_serve_bands_and_one_at_another_does_not(self):
        ports = free_ports(2)
        peer = Server(port=ports[1])
        self.addCleanup(peer.stop)
        coordinator = Server(["--peers", peer.url], port=ports[0])
        self.addCleanup(coordinator.stop)
        for n in range(5):
            for s in (coordinator, peer):
                self.assertEqual(s.json("POST", "/v1/edits", durable_scene.batch(n))[0], 200)
        path = f"/v1/render?{SPLIT_VIEW}&format=exr&aovs=instance_id"
        single = coordinator.call("GET", path)[2]
        status, headers, frame = coordinator.call("GET", path + "&split=2")
        self.assertEqual(status, 200, frame[:300])
        self.assertEqual(headers["X-Strata-Split"], f"2 bands at version 5: local, {peer.url}")
        self.assertEqual(frame, single)
        # The peer moves ahead: its band is rendered here, and the frame is still version 5's.
        self.assertEqual(peer.json("POST", "/v1/edits", durable_scene.batch(5))[0], 200)
        status, headers, frame = coordinator.call("GET", path + "&split=2")
        self.assertEqual(status, 200, frame[:300])
        self.assertEqual(headers["X-Strata-Split"],
                         f"2 bands at version 5: local, local ({peer.url}: at version 6, not 5)")
        self.assertEqual(frame, single)
        # Without --peers a split is a 422 naming it.
        status, _, body = peer.call("GET", path + "&split=2")
        self.assertEqual(status, 422, body)
        self.assertEqual(json.loads(body)["pointer"], "/split")

    def test_a_peer_that_never_answers_costs_the_peer_timeout_and_no_more_than_the_deadline(self):
        # A listening socket that accepts (in the kernel's backlog) and never answers.
        silent = socket.socket()
        silent.bind(("127.0.0.1", 0))
        silent.listen(8)
        self.addCleanup(silent.close)
        url = f"http://127.0.0.1:{silent.getsockname()[1]}"
        coordinator = Server(["--peers", url, "--peer-timeout-ms", "300"])
        self.addCleanup(coordinator.stop)
        self.assertEqual(coordinator.json("POST", "/v1/edits", durable_scene.batch(0))[0], 200)
        path = f"/v1/render?{SPLIT_VIEW}"
        single = coordinator.call("GET", path)[2]
        status, headers, frame = coordinator.call("GET", path + "&split=2")
        self.assertEqual(status, 200, frame[:300])
        self.assertTrue(headers["X-Strata-Split"].startswith(
            f"2 bands at version 1: local, local ({url}: "), headers["X-Strata-Split"])
        self.assertEqual(frame, single)
        # The render's deadline bounds the wait for a peer, whatever --peer-timeout-ms says.
        patient = Server(["--peers", url, "--peer-timeout-ms", "60000", "--render-timeout", "1"])
        self.addCleanup(patient.stop)
        t0 = time.monotonic()
        status, _, body = patient.call("GET", path + "&split=2")
        self.assertEqual(status, 503, body)
        self.assertIn("deadline-exceeded", json.loads(body)["type"])
        self.assertLess(time.monotonic() - t0, 20)
        self.assertEqual(patient.call("GET", "/readyz")[0], 200)


if __name__ == "__main__":
    unittest.main()

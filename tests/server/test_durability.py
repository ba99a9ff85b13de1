"""Durability at the process level: real strata-server processes on data directories that are
torn, damaged, empty, missing, read-only, full or already in use. Each case has a documented
outcome (protocol/README.md, "Durability") and a clear message; none crashes the server.
Snapshot export and import through HTTP and the strata CLI are here too.
"""

import base64
import glob
import json
import os
import resource
import shutil
import struct
import subprocess
import tempfile
import time
import unittest
import urllib.request

import durable_scene
from hostile import SERVER, Server

CLI = os.environ.get("STRATA_CLI_BINARY", "build/clients/cli/strata")
HEADER = 32  # segment header bytes


def run_server(args, timeout=30.0):
    """Runs a server that is expected to refuse to start: (exit code, log)."""
    p = subprocess.run([SERVER, "--host", "127.0.0.1", "--port", "0"] + args,
                       capture_output=True, text=True, timeout=timeout)
    return p.returncode, p.stdout + p.stderr


def stream(server, first, count):
    for n in range(first, first + count):
        status, answer = server.json("POST", "/v1/edits", durable_scene.batch(n))
        assert status == 200, (status, answer)
    return first + count


def segments(data):
    return sorted(glob.glob(os.path.join(data, "journal-*.log")))


def record_offsets(path):
    """Start offsets of the records in a segment (the format of engine/durable/journal_format.h)."""
    with open(path, "rb") as f:
        raw = f.read()
    offsets, pos = [], HEADER
    while pos + 16 <= len(raw):
        length = int.from_bytes(raw[pos:pos + 4], "little")
        offsets.append(pos)
        pos += 16 + length
    return offsets


class DataDirectory(unittest.TestCase):
    def setUp(self):
        self.data = tempfile.mkdtemp(prefix="strata-durable-")
        self.addCleanup(shutil.rmtree, self.data, True)

    def server(self, *extra, **kw):
        s = Server(["--data", self.data] + list(extra), **kw)
        self.addCleanup(s.stop)
        return s

    def fill(self, count):
        s = self.server()
        stream(s, 0, count)
        s.stop()

    def test_a_restart_brings_back_the_same_scene(self):
        s = self.server()
        stream(s, 0, 12)
        before = s.json("GET", "/v1/scene")[1]
        s.kill()
        s = self.server()
        self.assertEqual(s.json("GET", "/v1/scene")[1], before)
        self.assertEqual(durable_scene.check(s, 12), "")
        stats = s.json("GET", "/v1/stats")[1]["durability"]
        self.assertEqual(stats["recovered_version"], 12)
        self.assertEqual(stats["fsync"], "always")
        self.assertGreaterEqual(stats["recovery_seconds"], 0)
        metrics = s.call("GET", "/metrics")[2].decode()
        self.assertIn("strata_durable_journal_bytes ", metrics)
        self.assertIn("strata_durable_fsync_duration_seconds_bucket", metrics)

    def test_demo_reset_brings_the_demo_back_over_a_recovered_scene_as_the_next_version(self):
        def instance_ids(server):
            page = server.json("GET", "/v1/scene/instances?limit=10000")[1]
            return sorted(i["id"] for i in page["items"])
        s = self.server("--demo")
        demo = instance_ids(s)
        self.assertTrue(demo)
        self.assertEqual(s.json("POST", "/v1/edits", {"edits": [{"op": "clear"}]})[0], 200)
        cleared = s.version()
        s.stop()
        # --demo leaves a recovered scene alone (the user's work), and says how to reset it.
        s = self.server("--demo")
        self.assertEqual((s.version(), instance_ids(s)), (cleared, []))
        self.assertIn("--demo-reset replaces it", s.log())
        s.stop()
        s = self.server("--demo-reset")
        self.assertEqual(s.version(), cleared + 1)
        self.assertEqual(instance_ids(s), demo)
        s.kill()
        # The reset is one journaled version like any other.
        s = self.server()
        self.assertEqual((s.version(), instance_ids(s)), (cleared + 1, demo))

    def test_an_imported_asset_is_journaled_and_survives_a_kill(self):
        s = self.server()
        ply = (b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
               b"property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
               b"end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n")
        status, _, body = s.call("POST", "/v1/assets?format=ply&prefix=quad", ply,
                                 {"Content-Type": "application/ply"})
        self.assertEqual(status, 200, body)
        before = s.json("GET", "/v1/scene/meshes/quad.mesh0")[1]
        s.kill()
        s = self.server()
        self.assertEqual(s.version(), 1)
        self.assertEqual(s.json("GET", "/v1/scene/meshes/quad.mesh0")[1], before)
        self.assertEqual(s.json("GET", "/v1/scene/instances/quad.node0")[0], 200)

    def test_bulk_instance_edits_survive_a_kill(self):
        s = self.server()
        rows = b"".join(struct.pack("<12f", 1, 0, 0, i % 100, 0, 1, 0, 0, 0, 0, 1, i // 100)
                        for i in range(5000))
        edits = [{"op": "add_mesh", "id": "pebble", "shape": {"type": "box", "size": 0.3}},
                 {"op": "add_instances", "ids": {"prefix": "p", "count": 5000}, "mesh": "pebble",
                  "transforms_b64": base64.b64encode(rows).decode()}]
        self.assertEqual(s.json("POST", "/v1/edits", {"edits": edits})[0], 200)
        move = {"op": "update_instances", "ids": ["p7", "p4321"],
                "transforms": [1, 0, 0, 0, 0, 1, 0, 5, 0, 0, 1, 0] * 2}
        self.assertEqual(s.json("POST", "/v1/edits", {"edits": [move]})[0], 200)
        before = s.json("GET", "/v1/scene/instances/p4321")[1]
        s.kill()
        s = self.server()
        self.assertEqual(s.version(), 2)
        self.assertEqual(s.json("GET", "/v1/scene")[1]["counts"]["instances"], 5000)
        self.assertEqual(s.json("GET", "/v1/scene/instances/p4321")[1], before)
        self.assertEqual(s.json("GET", "/v1/scene/instances/p4320")[1]["transform"][3], 20)
        # The journal holds the bulk edit as it came: the packed rows, not 5000 edits.
        journal = sum(os.path.getsize(f) for f in segments(self.data))
        self.assertLess(journal, len(rows) + 4096)

    def test_undo_and_redo_survive_kills(self):
        def state(server):
            meshes = server.json("GET", "/v1/scene/meshes?limit=10000")[1]["items"]
            instances = server.json("GET", "/v1/scene/instances?limit=10000")[1]["items"]
            for i in instances:
                del i["version"]  # the version it was read at
            return (sorted(m["id"] for m in meshes),
                    sorted(instances, key=lambda i: i["id"]))

        def step(server, op, version, target):
            status, answer = server.json("POST", "/v1/" + op, None)
            self.assertEqual(status, 200, answer)
            key = "undone" if op == "undo" else "redone"
            self.assertEqual((answer["version"], answer[key]), (version, target))

        s = self.server()
        states = {}
        for n in range(6):
            stream(s, n, 1)
            states[n + 1] = state(s)
        step(s, "undo", 7, 6)
        self.assertEqual(state(s), states[5])
        s.kill()
        # The stacks come back from the journal: the next undo takes back v5, not the undo.
        s = self.server()
        self.assertEqual(state(s), states[5])
        step(s, "undo", 8, 5)
        self.assertEqual(state(s), states[4])
        step(s, "redo", 9, 5)
        self.assertEqual(state(s), states[5])
        s.kill()
        s = self.server()
        step(s, "redo", 10, 6)
        self.assertEqual(state(s), states[6])
        status, answer = s.json("POST", "/v1/redo", None)
        self.assertEqual(status, 409, answer)
        self.assertTrue(answer["type"].endswith("/nothing-to-undo"), answer)
        history = s.json("GET", "/v1/history?limit=5")[1]
        self.assertEqual([(e["version"], e["kind"], e.get("target")) for e in history["entries"]],
                         [(10, "redo", 6), (9, "redo", 5), (8, "undo", 5), (7, "undo", 6),
                          (6, "edit", None)])
        self.assertEqual(history["undo"], {"depth": 6, "next": 10})

    def test_past_versions_read_and_render_as_they_were(self):
        s = self.server()
        stream(s, 0, 4)
        frame = "/v1/render?width=48&height=32&spp=2"
        status, headers, live_png = s.call("GET", frame)
        self.assertEqual((status, headers["ETag"]), (200, '"4"'))
        scene4 = s.json("GET", "/v1/scene")[1]
        live_snapshot = s.call("GET", "/v1/scene/snapshot")[2]
        stream(s, 4, 3)
        self.assertEqual(s.version(), 7)

        status, headers, past_png = s.call("GET", frame + "&at_version=4")
        self.assertEqual((status, headers["ETag"]), (200, '"4"'), past_png[:200])
        self.assertEqual(past_png, live_png, "the frame rendered live at version 4")
        status, _, posted = s.call("POST", "/v1/render?at_version=4",
                                   {"width": 48, "height": 32, "spp": 2})
        self.assertEqual((status, posted), (200, live_png))
        self.assertEqual(s.json("GET", "/v1/scene?at_version=4")[1], scene4)
        self.assertEqual(s.call("GET", "/v1/scene/instances/inst-2?at_version=4")[0], 200)
        self.assertEqual(s.call("GET", "/v1/scene/instances/inst-6?at_version=4")[0], 404)
        listed = s.json("GET", "/v1/scene/instances?limit=100&at_version=4")[1]
        self.assertEqual(sorted(i["id"] for i in listed["items"]),
                         ["inst-0", "inst-1", "inst-2", "inst-3"])
        self.assertEqual(s.json("GET", "/v1/scene/tree?at_version=4")[1]["version"], 4)
        picked = s.json("GET", "/v1/pick?x=24&y=16&width=48&height=32&at_version=4")[1]
        self.assertEqual(picked["version"], 4)
        self.assertEqual(s.call("GET", "/v1/scene/snapshot?at_version=4")[2], live_snapshot)
        path = os.path.join(self.data, "..", os.path.basename(self.data) + "-v4.strata")
        self.addCleanup(lambda: os.path.exists(path) and os.remove(path))
        save = subprocess.run([CLI, "--server", s.url, "snapshot", "save", "--version", "4", path],
                              capture_output=True, text=True)
        self.assertEqual(save.returncode, 0, save.stderr)
        with open(path, "rb") as f:
            self.assertEqual(f.read(), live_snapshot)

        # What does not exist, or is not a version, is said so; the live scene never moved.
        status, answer = s.json("GET", "/v1/scene?at_version=99")
        self.assertEqual((status, answer.get("pointer")), (404, "/at_version"), answer)
        self.assertIn("does not exist yet", answer["detail"])
        self.assertEqual(s.json("GET", "/v1/scene?at_version=x")[0], 400)
        self.assertEqual(s.version(), 7)
        self.assertEqual(durable_scene.check(s, 7), "")
        # A snapshot moves the history it reaches forward: what it covers is gone.
        s.stop()
        s = self.server("--snapshot-threshold-kb", "1")
        stream(s, 7, 3)
        first_segment = os.path.join(self.data, "journal-%020d.log" % 0)
        deadline = time.monotonic() + 30
        while os.path.exists(first_segment):  # a snapshot's clean-up removes what it covers
            self.assertLess(time.monotonic(), deadline, "no snapshot was written")
            time.sleep(0.05)
        status, answer = s.json("GET", "/v1/scene?at_version=2")
        self.assertEqual(status, 404, answer)
        self.assertIn("older than the data directory keeps", answer["detail"])

    def test_without_a_data_directory_past_versions_are_404(self):
        s = Server([])
        self.addCleanup(s.stop)
        stream(s, 0, 2)
        status, answer = s.json("GET", "/v1/scene?at_version=1")
        self.assertEqual(status, 404, answer)
        self.assertIn("without --data", answer["detail"])
        self.assertEqual(s.json("GET", "/v1/scene?at_version=2")[0], 200, "the live version")

    def test_a_torn_last_record_is_truncated_and_logged(self):
        self.fill(6)
        seg = segments(self.data)[-1]
        os.truncate(seg, os.path.getsize(seg) - 7)
        s = self.server()
        self.assertEqual(s.version(), 5)
        self.assertEqual(durable_scene.check(s, 5), "")
        self.assertIn("torn last record", s.log())
        self.assertEqual(s.json("GET", "/v1/stats")[1]["durability"]["torn_records_truncated"], 1)

    def test_a_flipped_byte_in_the_middle_refuses_to_start_naming_file_and_offset(self):
        self.fill(6)
        seg = segments(self.data)[-1]
        at = record_offsets(seg)[2]
        with open(seg, "r+b") as f:
            f.seek(at + 20)
            b = f.read(1)
            f.seek(at + 20)
            f.write(bytes([b[0] ^ 0x20]))
        code, log = run_server(["--data", self.data])
        self.assertEqual(code, 1, log)
        self.assertIn(seg, log)
        self.assertIn(f"offset {at}", log)
        self.assertIn("--recover-truncate", log)
        s = self.server("--recover-truncate")
        self.assertEqual(s.version(), 2)
        self.assertEqual(durable_scene.check(s, 2), "")
        self.assertIn("truncated", s.log())

    def test_an_empty_journal_starts_an_empty_scene(self):
        open(os.path.join(self.data, "journal-%020d.log" % 0), "wb").close()
        s = self.server()
        self.assertEqual(s.version(), 0)
        stream(s, 0, 2)
        s.kill()
        self.assertEqual(self.server().version(), 2)

    def test_a_snapshot_without_a_journal_is_loaded(self):
        source = Server([])
        self.addCleanup(source.stop)
        stream(source, 0, 9)
        status, headers, snap = source.call("GET", "/v1/scene/snapshot")
        self.assertEqual(status, 200)
        self.assertEqual(headers["ETag"], '"9"')
        with open(os.path.join(self.data, "snapshot-%020d.snap" % 9), "wb") as f:
            f.write(snap)
        s = self.server()
        self.assertEqual(s.version(), 9)
        self.assertEqual(durable_scene.check(s, 9), "")

    def test_a_missing_directory_is_created(self):
        nested = os.path.join(self.data, "a", "b")
        s = Server(["--data", nested])
        self.addCleanup(s.stop)
        stream(s, 0, 1)
        self.assertTrue(segments(nested))

    def test_a_read_only_directory_refuses_to_start_with_a_clear_message(self):
        os.chmod(self.data, 0o555)
        self.addCleanup(os.chmod, self.data, 0o755)
        drop = None
        if os.geteuid() == 0:  # root writes anywhere: run the server as nobody
            def drop():
                os.setgid(65534)
                os.setuid(65534)
        p = subprocess.run([SERVER, "--port", "0", "--data", self.data], capture_output=True,
                           text=True, timeout=30, preexec_fn=drop)
        log = p.stdout + p.stderr
        self.assertEqual(p.returncode, 1, log)
        self.assertIn("cannot create the lock file", log)
        self.assertIn("Permission denied", log)

    def test_a_full_disk_refuses_the_batch_and_keeps_the_server_alive(self):
        limit = 256 * 1024

        def small_files():
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

        s = self.server(preexec_fn=small_files)
        n, refused = 0, None
        while n < 200:
            status, answer = s.json("POST", "/v1/edits", durable_scene.batch(n))
            if status != 200:
                refused = (status, answer)
                break
            n += 1
        self.assertIsNotNone(refused, "the journal should have hit the file size limit")
        self.assertEqual(refused[0], 503, refused)
        self.assertIn("File too large", refused[1]["detail"])
        self.assertTrue(s.alive())
        self.assertEqual(s.version(), n, "a refused batch changes nothing")
        self.assertEqual(durable_scene.check(s, n), "")
        s.kill()
        s = self.server()
        self.assertEqual(s.version(), n)
        self.assertEqual(durable_scene.check(s, n), "")

    def test_a_snapshot_the_disk_cannot_hold_keeps_the_journal_and_is_retried(self):
        # Files up to 256 KiB: journal segments stay under it (each snapshot attempt starts a new
        # one), snapshots of the growing scene soon do not.
        limit = 256 * 1024

        def small_files():  # a soft limit: the test lifts it later without privileges
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))

        s = self.server("--snapshot-threshold-kb", "32", preexec_fn=small_files)

        def durability():
            return s.json("GET", "/v1/stats")[1]["durability"]

        n = stream(s, 0, 120)  # every batch acknowledged: the journal is unaffected
        deadline = time.monotonic() + 20
        while durability()["snapshot_failures"] == 0:
            self.assertLess(time.monotonic(), deadline, "a snapshot should have failed")
            time.sleep(0.05)
        stats = durability()
        self.assertIn("File too large", stats["last_snapshot_error"])
        self.assertIn("the journal keeps every record", stats["last_snapshot_error"])
        self.assertIn("File too large", s.log())
        self.assertFalse(stats["failed"], "a failed snapshot does not stop the journal")
        self.assertEqual(glob.glob(os.path.join(self.data, "*.tmp")), [])
        # Retried without any new edit.
        failures = stats["snapshot_failures"]
        while durability()["snapshot_failures"] == failures:
            self.assertLess(time.monotonic(), deadline + 20, "the snapshot should be retried")
            time.sleep(0.05)
        self.assertTrue(s.alive())
        n = stream(s, n, 5)
        self.assertEqual(durable_scene.check(s, n), "")
        # Room again: the next retry succeeds, and replaces the journal it kept.
        written = durability()["snapshots_written"]
        resource.prlimit(s.pid, resource.RLIMIT_FSIZE,
                         (resource.RLIM_INFINITY, resource.RLIM_INFINITY))
        while durability()["snapshots_written"] == written:
            self.assertLess(time.monotonic(), deadline + 120, "the retry should succeed")
            time.sleep(0.05)
        self.assertNotIn("last_snapshot_error", durability())
        s.kill()
        s = self.server()
        self.assertEqual(s.version(), n)
        self.assertEqual(durable_scene.check(s, n), "")

    def test_two_servers_cannot_share_a_directory(self):
        self.server()
        code, log = run_server(["--data", self.data])
        self.assertEqual(code, 1, log)
        self.assertIn("in use by another strata-server", log)

    def test_snapshots_replace_the_journal_and_survive_restarts(self):
        s = self.server("--snapshot-threshold-kb", "16")
        stream(s, 0, 40)
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            if s.json("GET", "/v1/stats")[1]["durability"]["snapshots_written"] > 0:
                break
            time.sleep(0.05)
        stats = s.json("GET", "/v1/stats")[1]["durability"]
        self.assertGreater(stats["snapshots_written"], 0)
        self.assertGreater(stats["last_snapshot_bytes"], 0)
        self.assertGreater(stats["last_snapshot_unix_ms"], 0)
        s.kill()
        self.assertTrue(glob.glob(os.path.join(self.data, "snapshot-*.snap")))
        s = self.server()
        self.assertEqual(durable_scene.check(s, 40), "")
        self.assertIn("loaded snapshot", s.log())

    def test_undo_reaches_past_snapshots_after_a_kill(self):
        s = self.server("--snapshot-threshold-kb", "16")
        stream(s, 0, 40)
        deadline = time.monotonic() + 10
        while s.json("GET", "/v1/stats")[1]["durability"]["snapshots_written"] == 0:
            self.assertLess(time.monotonic(), deadline, "no snapshot was written")
            time.sleep(0.05)
        stream(s, 40, 1)  # one batch in the journal after the snapshot
        before = s.json("GET", "/v1/history?limit=100")[1]
        self.assertEqual(before["undo"]["depth"], 41)
        s.kill()
        s = self.server()
        self.assertIn("restored the history saved with the snapshot", s.log())
        after = s.json("GET", "/v1/history?limit=100")[1]
        self.assertEqual(after["undo"], before["undo"])
        self.assertEqual([e["version"] for e in after["entries"]],
                         [e["version"] for e in before["entries"]])
        # Every batch can be taken back, those before the snapshot too.
        for n in range(41):
            status, answer = s.json("POST", "/v1/undo", None)
            self.assertEqual(status, 200, answer)
            self.assertEqual(answer["undone"], 41 - n)
        status, answer = s.json("POST", "/v1/undo", None)
        self.assertEqual(status, 409, answer)
        self.assertEqual(s.json("GET", "/v1/scene")[1]["counts"]["instances"], 0)

    def test_the_server_listens_while_it_recovers_and_answers_503_until_built(self):
        # A journal long enough that replaying it takes a while: 300k instances in 15 batches.
        s = self.server()
        status, _ = s.json("POST", "/v1/edits", {"edits": [
            {"op": "add_mesh", "id": "m", "shape": {"type": "box"}}]})
        self.assertEqual(status, 200)
        per = 20000
        for b in range(15):
            edits = [{"op": "add_instance", "id": f"i{b * per + k}", "mesh": "m",
                      "transform": {"translate": [k % 1000, b, k // 1000]}} for k in range(per)]
            status, answer = s.json("POST", "/v1/edits", {"edits": edits})
            self.assertEqual(status, 200, answer)
        s.kill()

        s = self.server(wait_ready=False)
        details, refused = [], None
        deadline = time.monotonic() + 120
        while True:
            self.assertLess(time.monotonic(), deadline)
            self.assertEqual(s.call("GET", "/livez")[0], 200, "alive from the first moment")
            status, _, body = s.call("GET", "/readyz")
            if status == 200:
                break
            self.assertEqual(status, 503, body)
            details.append(json.loads(body)["detail"])
            if refused is None:
                refused = s.call("GET", "/v1/scene")
            time.sleep(0.01)
        self.assertTrue(any("replaying the journal" in d for d in details), details)
        self.assertTrue(any("%" in d and "records" in d for d in details), details)
        self.assertTrue(any("being built" in d for d in details), details)
        # Everything else waits for the scene, with a hint when to come back.
        self.assertIsNotNone(refused)
        self.assertEqual(refused[0], 503)
        self.assertEqual(refused[1].get("Retry-After"), "1")
        self.assertIn(b"starting", refused[2])
        self.assertEqual(s.version(), 16)
        self.assertEqual(s.json("GET", "/v1/scene")[1]["counts"]["instances"], 300000)
        self.assertGreater(s.json("GET", "/v1/stats")[1]["durability"]["rebuild_seconds"], 0)


class SnapshotExport(unittest.TestCase):
    def test_a_scene_moves_between_servers_through_http_and_the_cli(self):
        a, b = Server([]), Server([])
        self.addCleanup(a.stop)
        self.addCleanup(b.stop)
        stream(a, 0, 11)
        stream(b, 0, 3)
        path = os.path.join(tempfile.mkdtemp(prefix="strata-snap-"), "scene.strata")
        self.addCleanup(shutil.rmtree, os.path.dirname(path), True)
        save = subprocess.run([CLI, "--server", a.url, "snapshot", "save", path],
                              capture_output=True, text=True)
        self.assertEqual(save.returncode, 0, save.stderr)
        self.assertIn("saved version 11", save.stdout)
        load = subprocess.run([CLI, "--server", b.url, "snapshot", "load", path],
                              capture_output=True, text=True)
        self.assertEqual(load.returncode, 0, load.stderr)
        self.assertEqual(b.version(), 4, "loading is one new version")
        scene_a, scene_b = a.json("GET", "/v1/scene")[1], b.json("GET", "/v1/scene")[1]
        scene_a.pop("version"), scene_b.pop("version")
        self.assertEqual(scene_a, scene_b)
        self.assertEqual(durable_scene.check(a, 11), "")
        # The same hits: identical frames.
        frame = {"width": 64, "height": 48, "spp": 1}
        self.assertEqual(a.call("POST", "/v1/render", frame)[2], b.call("POST", "/v1/render",
                                                                           frame)[2])

    def test_a_damaged_snapshot_is_refused_and_changes_nothing(self):
        s = Server([])
        self.addCleanup(s.stop)
        stream(s, 0, 3)
        snap = s.call("GET", "/v1/scene/snapshot")[2]
        bad = bytearray(snap)
        bad[len(bad) // 2] ^= 1
        status, _, body = s.call("POST", "/v1/scene/snapshot", bytes(bad),
                                 {"Content-Type": "application/vnd.strata.snapshot"})
        self.assertEqual(status, 400, body)
        self.assertIn(b"checksum", body)
        self.assertEqual(s.version(), 3)
        status, _, body = s.call("POST", "/v1/scene/snapshot", snap, {"If-Match": '"2"'})
        self.assertEqual(status, 412, body)
        self.assertEqual(s.version(), 3)


if __name__ == "__main__":
    unittest.main()

"""Undo, redo and the history (POST /v1/undo, POST /v1/redo, GET /v1/history) through the
blocking client against a real strata-server: each undo and redo is a new version whose scene is
the one before (after) the batch it takes back (applies again), the history lists every version
with its kind, target, message, ops and whether it is on the undo stack, pages by cursor, and the
problems are typed: NothingToUndoError (409) on an empty stack, VersionMismatchError (412) on a
stale If-Match. Each test starts its own server, so its history starts empty at version 0."""

import datetime
import json
import os
import re
import socket
import subprocess
import tempfile
import time
import unittest
import urllib.parse

from strata_client import (BadRequestError, Client, History, HistoryEntry, HistoryStack,
                           NotFoundError, NothingToUndoError, ProblemError, UndoResult,
                           VersionMismatchError)
from strata_process import ServerProcess
from test_client import SERVER

BALL = [
    {"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 16}},
    {"op": "add_instance", "id": "b0", "mesh": "ball"},
]
SECOND = [{"op": "add_instance", "id": "b1", "mesh": "ball",
           "transform": {"translate": [2, 0, 0]}}]
MOVE = [{"op": "set_transform", "instance": "b0", "transform": {"translate": [0, 3, 0]}}]


class FrameStream:
    """GET /v1/stream read over a raw socket (an endless body no HTTP client here reads): the
    answer's head, then each part's JPEG with the version and sample count of its comment."""

    SEPARATOR = b"\r\n--strata-frame\r\nContent-Type: image/jpeg\r\n\r\n"

    def __init__(self, url, query):
        parts = urllib.parse.urlsplit(url)
        self.sock = socket.create_connection((parts.hostname, parts.port), timeout=10)
        self.sock.sendall(f"GET /v1/stream?{query} HTTP/1.1\r\nHost: x\r\n\r\n".encode())
        self.data = b""
        self.read_until(lambda: b"\r\n\r\n" in self.data, 10)
        head, _, self.data = self.data.partition(b"\r\n\r\n")
        self.status = int(head.split(b" ")[1]) if head else 0
        self.headers = head.decode("latin-1")

    def close(self):
        self.sock.close()

    def read_until(self, done, timeout):
        end = time.monotonic() + timeout
        while not done() and time.monotonic() < end:
            self.sock.settimeout(max(end - time.monotonic(), 0.01))
            try:
                got = self.sock.recv(65536)
            except socket.timeout:
                break
            if not got:
                break
            self.data += got
        return done()

    def problem(self):
        """The problem document of a refused stream."""
        length = int(re.search(r"Content-Length: (\d+)", self.headers, re.I).group(1))
        self.read_until(lambda: len(self.data) >= length, 10)
        return json.loads(self.data[:length])

    def next(self, timeout=10):
        """(version, samples, jpeg) of the next whole part, or None when none came in time."""
        start = self.data.find(b"\xff\xd8")
        if start < 0 and not self.read_until(lambda: b"\xff\xd8" in self.data, timeout):
            return None
        start = self.data.find(b"\xff\xd8")
        if not self.read_until(lambda: self.data.find(self.SEPARATOR, start) >= 0, timeout):
            return None
        end = self.data.find(self.SEPARATOR, start)
        jpeg, self.data = self.data[start:end], self.data[end + len(self.SEPARATOR):]
        comment = re.search(rb"strata version=(\d+) samples=(\d+)", jpeg)
        return int(comment.group(1)), int(comment.group(2)), jpeg

    def converged(self, samples, timeout=20):
        """The first part with `samples` samples (parts before it are skipped)."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            part = self.next(end - time.monotonic())
            if part is None or part[1] >= samples:
                return part
        return None


class UndoHistoryTest(unittest.TestCase):

    def setUp(self):
        self.server = ServerProcess(SERVER)
        self.client = Client(self.server.url)

    def tearDown(self):
        self.client.close()
        self.server.stop()

    def instance_ids(self):
        return sorted(i["id"] for i in self.client.instances())

    def b0_y(self):
        return self.client.scene("instances", "b0")["transform"][7]

    def three_batches(self):
        """Versions 1 (BALL, with a message), 2 (SECOND) and 3 (MOVE)."""
        versions = (self.client.edit(BALL, message="a ball"), self.client.edit(SECOND),
                    self.client.edit(MOVE))
        self.assertEqual(versions, (1, 2, 3))
        self.assertEqual(self.b0_y(), 3)
        return versions

    def test_undo_and_redo_are_new_versions_that_take_batches_back_and_apply_them_again(self):
        _, second, move = self.three_batches()
        undone = self.client.undo()
        self.assertIsInstance(undone, UndoResult)
        self.assertEqual((undone.version, undone.target, undone.undone, undone.applied),
                         (4, move, move, 1))
        self.assertIsNone(undone.redone)
        self.assertEqual(undone, {"version": 4, "undone": move, "applied": 1})
        self.assertEqual(self.b0_y(), 0)
        self.assertEqual(self.instance_ids(), ["b0", "b1"])

        undone = self.client.undo()
        self.assertEqual((undone.version, undone.target), (5, second))
        self.assertEqual(self.instance_ids(), ["b0"])
        self.assertEqual(self.client.scene()["version"], 5)
        with self.assertRaises(ProblemError) as caught:
            self.client.scene("instances", "b1")
        self.assertEqual(caught.exception.status, 404)

        redone = self.client.redo()
        self.assertEqual((redone.version, redone.target, redone.redone), (6, second, second))
        self.assertIsNone(redone.undone)
        self.assertEqual(self.instance_ids(), ["b0", "b1"])
        self.assertEqual(self.client.scene("instances", "b1")["transform"][3], 2)
        self.assertEqual(self.b0_y(), 0)  # the move stays taken back: next on the redo stack

        # What the history says now, newest first.
        history = self.client.history()
        self.assertIsInstance(history, History)
        self.assertEqual((history.version, history.oldest, history.next_cursor), (6, 1, None))
        self.assertIsInstance(history.undo, HistoryStack)
        self.assertEqual((history.undo.depth, history.undo.next), (2, 6))
        self.assertEqual((history.redo.depth, history.redo.next), (1, move))
        self.assertGreater(history.held_bytes, 0)
        entries = history.entries
        self.assertTrue(all(isinstance(e, HistoryEntry) for e in entries))
        self.assertEqual([(e.version, e.kind, e.target, e.undoable) for e in entries],
                         [(6, "redo", second, True), (5, "undo", second, False),
                          (4, "undo", move, False), (3, "edit", None, False),
                          (2, "edit", None, False), (1, "edit", None, True)])
        self.assertEqual([e.message for e in entries], [None] * 5 + ["a ball"])
        self.assertNotIn("message", entries[0])  # absent members stay absent in the dict view
        self.assertNotIn("target", entries[-1])
        self.assertEqual(entries[-1].ops, {"add_mesh": 1, "add_instance": 1})
        self.assertEqual(entries[-1].edits, 2)
        self.assertEqual(entries[-2].ops, {"add_instance": 1})
        self.assertEqual(entries[1].ops, {"remove_instance": 1})
        self.assertEqual(entries[0].ops, {"add_instance": 1})
        self.assertEqual(history["entries"][0]["kind"], "redo")
        for entry in entries:
            self.assertEqual(entry.datetime.tzinfo, datetime.timezone.utc)
            self.assertTrue(entry.time.endswith("Z"), entry.time)
        now = datetime.datetime.now(datetime.timezone.utc)
        self.assertLess(abs((now - entries[0].datetime).total_seconds()), 120)
        self.assertLessEqual(entries[-1].datetime, entries[0].datetime)

        # The rest of the stacks: undo takes back the redo, then the first batch; then nothing.
        self.assertEqual(self.client.undo().target, 6)
        self.assertEqual(self.instance_ids(), ["b0"])
        self.assertEqual(self.client.undo().target, 1)
        self.assertEqual(self.instance_ids(), [])
        self.assertEqual(self.client.scene()["counts"]["meshes"], 0)
        with self.assertRaises(NothingToUndoError) as caught:
            self.client.undo()
        p = caught.exception
        self.assertEqual((p.status, p.problem_type, p.current_version), (409, "nothing-to-undo", 8))
        self.assertEqual(self.client.scene()["version"], 8)  # nothing applied
        self.assertEqual(self.client.history(limit=1).undo.depth, 0)

    def test_a_new_edit_empties_the_redo_stack(self):
        self.three_batches()
        self.client.undo()
        self.client.undo()
        self.assertEqual(self.client.history(limit=1).redo.depth, 2)
        self.assertEqual(self.client.edit([{"op": "update_instance", "instance": "b0",
                                            "visible": False}]), 6)
        history = self.client.history(limit=1)
        self.assertEqual((history.redo.depth, history.redo.next), (0, None))
        with self.assertRaises(NothingToUndoError) as caught:
            self.client.redo()
        self.assertEqual(caught.exception.current_version, 6)
        self.assertEqual(self.instance_ids(), ["b0"])
        # Nothing redone yet on a fresh server either.
        with ServerProcess(SERVER) as fresh, Client(fresh.url) as client:
            with self.assertRaises(NothingToUndoError):
                client.redo()
            with self.assertRaises(NothingToUndoError):
                client.undo()

    def test_if_match_undoes_only_the_version_it_names(self):
        self.three_batches()
        with self.assertRaises(VersionMismatchError) as caught:
            self.client.undo(if_match=2)
        self.assertEqual(caught.exception.current_version, 3)
        self.assertEqual(self.b0_y(), 3)  # nothing applied
        self.assertEqual(self.client.undo(if_match=3).version, 4)
        with self.assertRaises(VersionMismatchError) as caught:
            self.client.redo(if_match=3)
        self.assertEqual(caught.exception.current_version, 4)
        self.assertEqual(self.client.redo(if_match='"4"').target, 3)
        self.assertEqual(self.b0_y(), 3)
        self.assertEqual(self.client.undo(if_match="*").target, 5)

    def test_history_pages_by_cursor_and_the_iterator_follows_them(self):
        self.three_batches()
        self.client.undo()
        self.client.undo()
        self.client.redo()
        self.client.edit([], message="empty, but kept")  # version 7
        first = self.client.history(limit=2)
        self.assertEqual([e.version for e in first.entries], [7, 6])
        self.assertEqual(first.entries[0].message, "empty, but kept")
        self.assertEqual((first.entries[0].edits, first.entries[0].ops), (0, {}))
        self.assertIsNotNone(first.next_cursor)
        pages = [first.entries]
        cursor = first.next_cursor
        while cursor is not None:
            page = self.client.history(limit=2, cursor=cursor)
            self.assertEqual(page.version, 7)
            pages.append(page.entries)
            cursor = page.next_cursor
        self.assertEqual([[e.version for e in p] for p in pages], [[7, 6], [5, 4], [3, 2], [1]])
        everything = list(self.client.history_entries(page_size=3))
        self.assertEqual([e.version for e in everything], [7, 6, 5, 4, 3, 2, 1])
        self.assertEqual(everything, self.client.history(limit=1000).entries)
        # A version made after a page was read does not shift the next page.
        self.client.edit(MOVE)
        self.assertEqual([e.version for e in self.client.history(2, first.next_cursor).entries],
                         [5, 4])
        for query in ({"limit": 0}, {"limit": 1001}, {"cursor": "x"}, {"cursor": "0"}):
            with self.subTest(query=query), self.assertRaises(BadRequestError):
                self.client.history(**query)

    def test_a_message_is_text_of_at_most_1024_bytes(self):
        self.client.edit(BALL, message="ü" * 512)  # 1024 bytes of UTF-8
        self.assertEqual(self.client.history().entries[0].message, "ü" * 512)
        for message in ("x" * 1025, "ü" * 513, "two\nlines", "tab\there", "\x7f", "\u2028"):
            with self.subTest(message=message[:12]):
                with self.assertRaises(ProblemError) as caught:
                    self.client.edit(MOVE, message=message)
                self.assertIn(caught.exception.status, (400, 422))
                self.assertIn("message", caught.exception.detail)
        self.assertEqual(self.client.scene()["version"], 1)  # nothing applied
        self.client.edit(MOVE, message="")
        self.assertNotIn("message", self.client.history(limit=1).entries[0])


class PastVersionTest(unittest.TestCase):
    """at_version through the client: the scene and frames as they were, from --data."""

    def setUp(self):
        self.data = tempfile.TemporaryDirectory(prefix="strata-past-")
        self.server = ServerProcess(SERVER, ["--data", self.data.name])
        self.client = Client(self.server.url)

    def tearDown(self):
        self.client.close()
        self.server.stop()
        self.data.cleanup()

    def test_scene_and_frames_at_a_past_version(self):
        self.client.edit(BALL)
        frame = self.client.render(48, 32, spp=1)
        self.client.edit(MOVE)
        self.assertEqual(self.client.scene("instances", "b0")["transform"][7], 3)
        self.assertEqual(self.client.scene("instances", "b0", at_version=1)["transform"][7], 0)
        self.assertEqual(self.client.scene(at_version=1)["version"], 1)
        self.assertEqual(self.client.render(48, 32, spp=1, at_version=1), frame)
        self.assertEqual(self.client.last_render.version, 1)
        with self.assertRaises(NotFoundError):
            self.client.scene(at_version=9)
        with self.assertRaises(ValueError):
            self.client.scene(at_version=-1)

    def test_the_scene_and_a_frame_as_they_were_at_a_time(self):
        self.client.edit(BALL)
        frame = self.client.render(48, 32, spp=1)
        time.sleep(0.05)
        then = datetime.datetime.now(datetime.timezone.utc)
        time.sleep(0.05)
        self.client.edit(MOVE)
        self.assertEqual(self.client.scene(at_version=then)["version"], 1)
        self.assertEqual(self.client.render(48, 32, spp=1, at_version=then), frame)
        self.assertEqual(self.client.last_render.version, 1)
        self.assertEqual(self.client.scene(at_version=datetime.datetime.now(
            datetime.timezone.utc))["version"], 2)
        with self.assertRaises(NotFoundError) as caught:
            self.client.scene(at_version=then - datetime.timedelta(hours=1))
        self.assertIn("oldest version the history lists, 1", caught.exception.detail)
        with self.assertRaises(ValueError):
            self.client.scene(at_version=datetime.datetime.now())  # no time zone
        cli = os.environ.get("STRATA_CLI_BINARY")
        if cli:
            with tempfile.TemporaryDirectory() as d:
                past, live = os.path.join(d, "past.strata"), os.path.join(d, "v1.strata")
                stamp = then.isoformat(timespec="milliseconds").replace("+00:00", "Z")
                for args, path in ((["--at-time", stamp], past), (["--version", "1"], live)):
                    done = subprocess.run([cli, "--server", self.server.url, "snapshot", "save",
                                           *args, path], capture_output=True, text=True)
                    self.assertEqual(done.returncode, 0, done.stderr)
                with open(past, "rb") as a, open(live, "rb") as b:
                    self.assertEqual(a.read(), b.read())
        status = self.server_call("/v1/scene?at_time=yesterday")
        self.assertEqual(status, 400)
        status = self.server_call("/v1/scene?at_time=2026-01-01T00:00:00Z&at_version=1")
        self.assertEqual(status, 400)

    def server_call(self, target):
        import urllib.error
        import urllib.request
        try:
            with urllib.request.urlopen(self.server.url + target) as r:
                return r.status
        except urllib.error.HTTPError as e:
            return e.code

    def stream(self, query):
        stream = FrameStream(self.server.url, query)
        self.addCleanup(stream.close)
        return stream

    def test_a_frame_stream_shows_a_past_version_and_stays_there(self):
        view = "width=48&height=32&max_samples=2&fps=30"
        self.client.edit(BALL)
        live = self.stream(view)
        self.assertEqual(live.status, 200, live.headers)
        version, samples, live_v1 = live.converged(2)
        self.assertEqual((version, samples), (1, 2))
        live.close()
        self.client.edit(MOVE)
        # The stream at version 1 shows the frames the live stream showed then, byte for byte,
        # and stops at max_samples though the scene moves on.
        past = self.stream(view + "&at_version=1")
        self.assertEqual(past.status, 200, past.headers)
        self.assertEqual(past.converged(2), (1, 2, live_v1))
        self.client.edit(SECOND)
        self.assertIsNone(past.next(timeout=0.6))
        # A stream at the live version stays at it too: an edit sends it no new frame.
        now = self.stream(view + "&at_version=3")
        self.assertEqual(now.converged(2)[:2], (3, 2))
        self.client.edit([{"op": "remove_instance", "instance": "b1"}])
        self.assertIsNone(now.next(timeout=0.6))
        # A live stream opened beside them shows the newest version.
        self.assertEqual(self.stream(view).converged(2)[:2], (4, 2))
        # at_time names the version made then: a viewer of it shares version 1's view.
        stamp = urllib.parse.quote(self.client.history(limit=4).entries[-1].time)
        self.assertEqual(self.stream(f"{view}&at_time={stamp}").converged(2), (1, 2, live_v1))

    def test_past_version_streams_are_refused_with_a_problem_naming_why(self):
        self.client.edit(BALL)
        for query, status, pointer in (("at_version=7", 404, "/at_version"),
                                       ("at_version=one", 400, "/at_version"),
                                       ("at_version=1&at_time=2026-01-01T00:00:00Z", 400,
                                        "/at_time"),
                                       ("at_version=1&highlight=nobody", 404, "/highlight")):
            with self.subTest(query=query):
                refused = self.stream("width=16&height=16&" + query)
                self.assertEqual(refused.status, status, refused.headers)
                self.assertEqual(refused.problem().get("pointer"), pointer)
        # Streams hold at most four past versions at once; a fifth waits (503, Retry-After),
        # while more viewers of a held version share it.
        for _ in range(4):
            self.client.edit(MOVE)
        held = [self.stream(f"width=16&height=16&max_samples=1&at_version={v}")
                for v in range(1, 5)]
        for stream in held:
            self.assertIsNotNone(stream.next(), stream.headers)
        refused = self.stream("width=16&height=16&at_version=5")
        self.assertEqual(refused.status, 503, refused.headers)
        self.assertIn("Retry-After", refused.headers)
        self.assertIn("past versions", refused.problem()["detail"])
        self.assertEqual(self.stream("width=24&height=16&at_version=2").status, 200)
        held[0].close()
        # Once a stream lets its version go, another version may be streamed.
        deadline = time.monotonic() + 10
        while True:
            again = self.stream("width=16&height=16&at_version=5")
            if again.status == 200 or time.monotonic() > deadline:
                break
            time.sleep(0.05)
        self.assertEqual(again.status, 200, again.headers)
        self.assertEqual(again.next()[0], 5)

    def test_assets_at_a_past_version(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "tri.obj")
            with open(path, "w") as f:
                f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
            made = self.client.import_asset(path, prefix="kit")
        self.client.delete_asset("kit")
        self.assertEqual(self.client.assets(), [])
        past = self.client.assets(at_version=made.version)
        self.assertEqual([(a.id, a.file, a.counts.meshes) for a in past], [("kit", "tri.obj", 1)])
        self.assertEqual(self.client.asset("kit", at_version=made.version).meshes, ["kit.mesh0"])
        with self.assertRaises(NotFoundError):
            self.client.asset("kit")


if __name__ == "__main__":
    unittest.main()

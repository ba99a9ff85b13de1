"""The asyncio client against a real strata-server: every method with the blocking client's
typed results and problems, concurrent requests on a few kept-alive connections, reconnection
after the server closes an idle one, large bodies after 100 Continue, tokens."""

import asyncio
import os
import socket
import tempfile
import time
import unittest
from unittest import mock

from strata_client import (AsyncClient, Client, Frame, History, Hit, ImportResult, NotFoundError,
                           NothingToUndoError, Page, ProblemError, RebuildReport, TooLargeError,
                           UnauthorizedError, UndoResult, UnprocessableError,
                           VersionMismatchError)
from strata_client import _aio_http
from strata_process import ServerProcess
from test_client import SCENE, SERVER
from test_typed_results import body_limit_batches, write_quad_obj


class AsyncClientTest(unittest.IsolatedAsyncioTestCase):
    @classmethod
    def setUpClass(cls):
        # A short keep-alive timeout, so a test can wait for the server to close an idle
        # connection.
        cls.server = ServerProcess(SERVER, ["--keep-alive-timeout", "1"])

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()

    async def asyncSetUp(self):
        self.client = AsyncClient(self.server.url)
        await self.client.edit([{"op": "clear"}])
        self.version = await self.client.edit(SCENE)

    async def asyncTearDown(self):
        await self.client.close()

    async def test_edit_commit_and_plan_answer_typed_reports(self):
        plan = await self.client.plan()
        self.assertIsInstance(plan, RebuildReport)
        self.assertTrue(plan.planned)
        report = await self.client.commit()
        self.assertIsInstance(report, RebuildReport)
        self.assertEqual((report.version, report.tlas.action), (self.version, "update"))
        self.assertEqual([(e.mesh, e.primitives) for e in report.rebuilt], [("ball", 224)])
        self.assertEqual(report["blas_rebuilds"], 1)
        self.assertEqual(await self.client.edit([], if_match=self.version), self.version + 1)

    async def test_render_frame_render_and_render_array(self):
        frame = await self.client.render_frame(48, 32)
        self.assertIsInstance(frame, Frame)
        self.assertTrue(frame.image.startswith(b"\x89PNG\r\n\x1a\n"))
        self.assertEqual((frame.info.version, frame.info.samples), (self.version, 1))
        self.assertEqual(frame.info.report.rebuilt[0].mesh, "ball")
        self.assertIs(self.client.last_render, frame.info)
        png = await self.client.render(48, 32, camera={"eye": [0, 5, 0.1]})
        self.assertTrue(png.startswith(b"\x89PNG"))
        self.assertTrue(self.client.last_render.rebuild.startswith(f"v{self.version} tlas=none"))
        image = await self.client.render_array(48, 32)
        self.assertEqual(image.shape, (32, 48, 3))
        centre = image[16, 24].astype(int)
        self.assertGreater(centre[0], centre[2])  # the red ball
        with self.assertRaises(ValueError):
            await self.client.render_array(8, 8, fmt="exr")
        arrays = await self.client.render_arrays(48, 32, aovs=["instance_id"])
        self.assertEqual(arrays.client_id("instance_id", arrays["instance_id"][16, 24]), "b0")

    async def test_it_answers_what_the_blocking_client_answers(self):
        with Client(self.server.url) as blocking:
            self.assertEqual(await self.client.scene("instances", "b0"),
                             blocking.scene("instances", "b0"))
            self.assertEqual(await self.client.scene(), blocking.scene())
            self.assertEqual(await self.client.pick(32, 32, 64, 64), blocking.pick(32, 32, 64, 64))
            self.assertEqual(await self.client.tree(depth=2), blocking.tree(depth=2))
        stats = await self.client.stats()
        self.assertEqual(stats["version"], self.version)

    async def test_listings_follow_cursors_as_async_iterators(self):
        await self.client.edit(
            [{"op": "add_group", "id": "row"}]
            + [{"op": "add_instance", "id": f"r{i}", "mesh": "ball", "parent": "row",
                "visible": i % 2 == 0} for i in range(7)]
            + [{"op": "add_light", "id": "lamp", "type": "point", "position": [0, 4, 0]}])
        ids = [i["id"] async for i in self.client.instances(page_size=2, parent="row")]
        self.assertEqual(ids, [f"r{i}" for i in range(7)])
        hidden = [i["id"] async for i in self.client.instances(page_size=3, visible=False)]
        self.assertEqual(hidden, ["r1", "r3", "r5"])
        self.assertEqual([g["id"] async for g in self.client.groups(parent="")], ["row"])
        kids = [k["kind"] async for k in self.client.children("row", page_size=3)]
        self.assertEqual(kids, ["instance"] * 7)
        self.assertEqual([m["id"] async for m in self.client.meshes()], ["ball"])
        self.assertEqual([m["id"] async for m in self.client.materials()], ["red"])
        self.assertEqual([t async for t in self.client.textures()], [])
        self.assertEqual([l["id"] async for l in self.client.lights()], ["lamp"])
        page = await self.client.page("instances", limit=4)
        self.assertIsInstance(page, Page)
        self.assertEqual((len(page.items), page.version), (4, self.version + 1))
        with self.assertRaises(NotFoundError):
            [i async for i in self.client.instances(mesh="nope")]

    async def test_picks_are_typed_hits(self):
        hit = await self.client.pick(32, 32, 64, 64)
        self.assertIsInstance(hit, Hit)
        self.assertEqual((hit.instance, hit.mesh), ("b0", "ball"))
        hits = await self.client.pick_many([(32, 32), (0, 0)], 64, 64,
                                           camera={"target": [0, 0, 20]})
        self.assertEqual(hits, [None, None])

    async def test_import_asset_uploads_a_model(self):
        with tempfile.TemporaryDirectory() as d:
            answer = await self.client.import_asset(write_quad_obj(d), parent=None)
            self.assertIsInstance(answer, ImportResult)
            self.assertEqual((answer.meshes, answer.version), (["quad.mesh0"], self.version + 1))
            with open(os.path.join(d, "bad.obj"), "w") as f:
                f.write("mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
            with self.assertRaises(FileNotFoundError):
                await self.client.import_asset(os.path.join(d, "bad.obj"))

    async def test_assets_are_listed_reimported_and_deleted(self):
        with tempfile.TemporaryDirectory() as d:
            path = write_quad_obj(d)
            await self.client.import_asset(path, prefix="kit")
            self.assertEqual([a.id for a in await self.client.assets()], ["kit"])
            self.assertEqual((await self.client.asset("kit")).instances, ["kit.node0"])
            again = await self.client.reimport_asset("kit", path)
            self.assertEqual(again.kept.meshes, ["kit.mesh0"])
        gone = await self.client.delete_asset("kit")
        self.assertEqual(gone.removed["instances"], ["kit.node0"])
        self.assertEqual(await self.client.assets(), [])

    async def test_problems_are_typed_exceptions(self):
        with self.assertRaises(UnprocessableError) as caught:
            await self.client.edit([{"op": "set_camera", "fov_y_deg": 30},
                                    {"op": "remove_instance", "instance": "nope"}])
        p = caught.exception
        self.assertEqual((p.status, p.problem_type, p.edit_index, p.pointer),
                         (422, "unknown-id", 1, "/edits/1/instance"))
        self.assertIn("unknown instance 'nope'", p.problem.detail)
        with self.assertRaises(VersionMismatchError) as caught:
            await self.client.edit([], if_match=self.version - 1)
        self.assertEqual(caught.exception.current_version, self.version)
        with self.assertRaises(ProblemError) as caught:
            await self.client.scene("materials", "nope/../x")
        self.assertIsInstance(caught.exception, NotFoundError)
        with self.assertRaises(ValueError):
            await self.client.scene("cameras", "main")
        # A problem leaves the connection usable.
        self.assertEqual(await self.client.edit([]), self.version + 1)

    async def test_undo_redo_and_history_answer_what_the_blocking_client_answers(self):
        added = await self.client.edit([{"op": "add_instance", "id": "b1", "mesh": "ball"}],
                                       message="b1")
        undone = await self.client.undo(if_match=added)
        self.assertIsInstance(undone, UndoResult)
        self.assertEqual((undone.version, undone.target, undone.applied), (added + 1, added, 1))
        with self.assertRaises(NotFoundError):
            await self.client.scene("instances", "b1")
        redone = await self.client.redo()
        self.assertEqual((redone.version, redone.target), (added + 2, added))
        self.assertEqual((await self.client.scene("instances", "b1"))["mesh"], "ball")
        history = await self.client.history(limit=3)
        self.assertIsInstance(history, History)
        self.assertEqual([(e.kind, e.target, e.message, e.undoable) for e in history.entries],
                         [("redo", added, None, True), ("undo", added, None, False),
                          ("edit", None, "b1", False)])
        self.assertEqual(history.next_cursor, str(added))
        with Client(self.server.url) as blocking:
            self.assertEqual(history, blocking.history(limit=3))
        versions = [e.version async for e in self.client.history_entries(page_size=2)]
        self.assertEqual(versions[:4], [added + 2, added + 1, added, self.version])
        self.assertEqual(versions, sorted(set(versions), reverse=True))
        with self.assertRaises(NothingToUndoError):
            await self.client.redo()
        with self.assertRaises(VersionMismatchError) as caught:
            await self.client.undo(if_match=added)
        self.assertEqual(caught.exception.current_version, added + 2)

    async def test_concurrent_requests_share_a_few_kept_alive_connections(self):
        async with AsyncClient(self.server.url, max_connections=3) as client:
            versions = await asyncio.gather(*(client.edit([]) for _ in range(12)))
            self.assertEqual(sorted(versions), list(range(self.version + 1, self.version + 13)))
            self.assertLessEqual(len(client._idle), 3)
            hits = await asyncio.gather(*(client.pick(32, 32, 64, 64) for _ in range(9)))
            self.assertEqual({h.instance for h in hits}, {"b0"})
            idle = list(client._idle)
            for _ in range(4):  # one at a time: one connection, again and again
                await client.plan()
                self.assertEqual(client._idle[-1:], idle[-1:])
        self.assertEqual(client._idle, [])

    async def test_a_connection_the_server_closed_while_idle_is_reopened(self):
        await self.client.stats()
        (conn,) = self.client._idle
        await asyncio.sleep(1.6)  # past the server's --keep-alive-timeout 1
        self.assertEqual(await self.client.edit([]), self.version + 1)  # sent exactly once
        self.assertEqual(await self.client.edit([]), self.version + 2)
        self.assertIsNot(self.client._idle[0], conn)

    async def test_an_unreachable_server_raises_a_connection_error(self):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        with self.assertRaises(ConnectionError):
            await AsyncClient(f"http://127.0.0.1:{port}", timeout=5).stats()
        for url in ("localhost:7070", "ftp://host", "http://host/v1"):
            with self.assertRaises(ValueError):
                AsyncClient(url)


class AsyncBodyLimitTest(unittest.IsolatedAsyncioTestCase):
    async def test_a_large_body_waits_for_100_continue_and_one_over_the_limit_gets_413(self):
        fits, too_big = body_limit_batches()
        with ServerProcess(SERVER, ["--max-body-mb", "2"]) as server:
            async with AsyncClient(server.url) as client:
                await client.stats()
                with self.assertRaises(TooLargeError) as caught:
                    await client.edit(too_big)
                self.assertIn("--max-body-mb", caught.exception.detail)
                # Only the server's 100 Continue can send the body before this wait is over.
                with mock.patch.object(_aio_http, "CONTINUE_WAIT_S", 120):
                    started = time.monotonic()
                    self.assertEqual(await client.edit(fits), 1)
                    self.assertLess(time.monotonic() - started, 60)
                self.assertEqual(len(client._idle), 1)


class AsyncTokenTest(unittest.IsolatedAsyncioTestCase):
    async def test_the_bearer_token_is_sent(self):
        with tempfile.NamedTemporaryFile("w", suffix=".token", delete=False) as f:
            f.write("s3cret\n")
        try:
            with ServerProcess(SERVER, ["--token-file", f.name]) as server:
                async with AsyncClient(server.url) as anonymous:
                    with self.assertRaises(UnauthorizedError):
                        await anonymous.stats()
                async with AsyncClient(server.url, token="s3cret") as client:
                    self.assertEqual((await client.stats())["version"], 0)
        finally:
            os.unlink(f.name)


if __name__ == "__main__":
    unittest.main()

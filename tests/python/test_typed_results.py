"""Typed results and typed problems of the blocking client against a real strata-server:
reports, render info, hits, pages and import answers are dataclasses that still read as the dicts
version 0.1 returned; each problem status raises its ProblemError subclass."""

import json
import os
import tempfile
import unittest

from strata_client import (Asset, AssetCounts, AssetDeleteResult, BadRequestError, BlasEntry,
                           Client, CommitPhases, Compaction, Frame, Hit, ImportResult, KeptIds,
                           ReimportResult, MemoryBytes, NotFoundError, Page, Problem, ProblemError,
                           RebuildReport, RenderInfo, TlasMerge, TlasReport, TooLargeError,
                           UnprocessableError, VersionMismatchError)
from strata_process import ServerProcess
from test_client import SCENE, SERVER, SceneTestCase


def write_quad_obj(folder: str) -> str:
    """A one-quad OBJ in `folder`; returns its path."""
    path = os.path.join(folder, "quad.obj")
    with open(path, "w") as f:
        f.write("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    return path


class TypedResultsTest(SceneTestCase):

    def test_a_commit_answers_a_typed_report_that_is_still_its_json(self):
        report = self.client.commit()
        self.assertIsInstance(report, RebuildReport)
        self.assertEqual((report.version, report.planned), (self.version, False))
        self.assertIsInstance(report.tlas, TlasReport)
        self.assertEqual((report.tlas.action, report.tlas.instances), ("update", 1))
        self.assertIsInstance(report.tlas.merge, TlasMerge)
        self.assertFalse(report.tlas.merge.swapped)
        self.assertIs(report.tlas.static_array, False)  # one instance: an instance geometry
        self.assertIs(report.tlas.dynamic_array, True)  # no motion keys: an instance array
        self.assertEqual(len(report.rebuilt), 1)
        entry = report.rebuilt[0]
        self.assertIsInstance(entry, BlasEntry)
        self.assertEqual((entry.mesh, entry.reason, entry.primitives), ("ball", "added", 224))
        self.assertGreaterEqual(entry.ms, 0)
        self.assertIsInstance(report.memory_bytes, MemoryBytes)
        self.assertGreater(report.memory_bytes.blas, 0)
        self.assertEqual(entry.bytes, report.memory_bytes.blas)
        self.assertIsNone(entry.uncompacted_bytes)
        self.assertIsInstance(report.memory_bytes.compaction, Compaction)
        self.assertEqual(report.memory_bytes.compaction.meshes, 0)
        self.assertIsInstance(report.phases, CommitPhases)
        self.assertGreaterEqual(report.ms, report.phases.blas_ms)
        # The dict view is the same objects: what 0.1 code reads keeps working.
        self.assertIs(report["tlas"], report.tlas)
        self.assertEqual(report["rebuilt"][0]["mesh"], "ball")
        self.assertIsInstance(report, dict)
        self.assertEqual(json.loads(json.dumps(report)), report)

    def test_a_compacted_mesh_reports_its_size_before_and_after(self):
        self.client.commit()
        self.client.edit([{"op": "add_mesh", "id": "gem", "build": {"compact": True},
                           "shape": {"type": "sphere", "segments": 48}}])
        report = self.client.commit()
        entry = report.rebuilt[0]
        self.assertEqual(entry.mesh, "gem")
        self.assertLess(entry.bytes, entry.uncompacted_bytes)
        compaction = report.memory_bytes.compaction
        self.assertEqual((compaction.meshes, compaction.uncompacted_bytes, compaction.bytes),
                         (1, entry.uncompacted_bytes, entry.bytes))
        self.assertEqual(compaction.saved_bytes, entry.uncompacted_bytes - entry.bytes)
        self.assertTrue(self.client.scene("meshes", "gem")["build"]["compact"])
        stats = self.client.stats()["memory_bytes"]["compaction"]
        self.assertEqual(stats["per_mesh"], [{"mesh": "gem", "bytes": entry.bytes,
                                              "uncompacted_bytes": entry.uncompacted_bytes}])

    def test_a_plan_leaves_out_what_only_a_commit_measures(self):
        plan = self.client.plan()
        self.assertTrue(plan.planned)
        self.assertIsNone(plan.ms)
        self.assertIsNone(plan.phases)
        self.assertIsNone(plan.tlas.merge)
        self.assertNotIn("ms", plan)  # absent members stay absent in the dict view
        self.assertEqual([(e.mesh, e.ms) for e in plan.rebuilt], [("ball", None)])

    def test_render_frame_answers_the_image_and_its_render_info(self):
        frame = self.client.render_frame(32, 16)
        self.assertIsInstance(frame, Frame)
        self.assertTrue(frame.image.startswith(b"\x89PNG\r\n\x1a\n"))
        info = frame.info
        self.assertIsInstance(info, RenderInfo)
        self.assertIs(self.client.last_render, info)
        self.assertEqual((info.version, info.content_type, info.samples),
                         (self.version, "image/png", 1))
        self.assertIsNone(info.split)
        self.assertIsInstance(info.report, RebuildReport)
        self.assertEqual(info.report.rebuilt[0].mesh, "ball")
        self.assertTrue(info.rebuild.startswith(f"v{self.version} tlas=update(1) rebuilds=1"))
        self.assertEqual(self.client.render(8, 8, spp=2), self.client.render_frame(8, 8,
                                                                                   spp=2).image)

    def test_a_pick_answers_typed_hits(self):
        hit = self.client.pick(32, 32, 64, 64)
        self.assertIsInstance(hit, Hit)
        self.assertEqual((hit.instance, hit.mesh, hit.group_path), ("b0", "ball", []))
        self.assertAlmostEqual(hit.distance, 3.03, delta=0.1)
        self.assertEqual(len(hit.position), 3)
        self.assertEqual(hit["instance"], "b0")
        hits = self.client.pick_many([(32, 32), (0, 0)], 64, 64,
                                     camera={"eye": [0, 0.5, 8], "target": [0, 0, 0]})
        self.assertIsInstance(hits[0], Hit)
        self.assertIsNone(hits[1])
        self.assertGreater(hits[0].distance, hit.distance)

    def test_a_page_has_its_items_cursor_and_version(self):
        self.client.edit([{"op": "add_group", "id": "row"}] + [
            {"op": "add_instance", "id": f"r{i}", "mesh": "ball", "parent": "row"}
            for i in range(5)])
        first = self.client.page("instances", limit=2, parent="row")
        self.assertIsInstance(first, Page)
        self.assertEqual([i["id"] for i in first.items], ["r0", "r1"])
        self.assertEqual(first.version, self.version + 1)
        self.assertIsNotNone(first.next_cursor)
        second = self.client.page("instances", 2, first.next_cursor, parent="row")
        self.assertEqual([i["id"] for i in second.items], ["r2", "r3"])
        kids = self.client.page("children", group="row", limit=10)
        self.assertEqual(len(kids.items), 5)
        self.assertIsNone(kids.next_cursor)
        self.assertEqual(self.client.page("meshes").items[0]["id"], "ball")
        with self.assertRaises(ValueError):
            self.client.page("cameras")
        with self.assertRaises(ValueError):
            self.client.page("children")

    def test_an_import_answers_a_typed_result(self):
        with tempfile.TemporaryDirectory() as d:
            answer = self.client.import_asset(write_quad_obj(d), prefix="q")
        self.assertIsInstance(answer, ImportResult)
        self.assertEqual((answer.version, answer.format), (self.version + 1, "obj"))
        self.assertEqual((answer.meshes, answer.instances, answer.groups),
                         (["q.mesh0"], ["q.node0"], ["q"]))
        self.assertIsNone(answer.model)
        self.assertEqual(answer["meshes"], ["q.mesh0"])

    def test_assets_are_listed_reimported_in_place_and_deleted_as_units(self):
        with tempfile.TemporaryDirectory() as d:
            path = write_quad_obj(d)
            made = self.client.import_asset(path, prefix="kit")
            self.assertEqual(made.bounds, {"min": [0, 0, 0], "max": [1, 1, 0]})
            listed = self.client.assets()
            self.assertEqual([a.id for a in listed], ["kit"])
            self.assertIsInstance(listed[0], Asset)
            self.assertIsInstance(listed[0].counts, AssetCounts)
            self.assertEqual((listed[0].file, listed[0].counts.meshes), ("quad.obj", 1))
            self.assertEqual(self.client.asset("kit").meshes, ["kit.mesh0"])
            self.client.commit()

            same = self.client.reimport_asset("kit", path)
            self.assertIsInstance(same, ReimportResult)
            self.assertIsInstance(same.kept, KeptIds)
            self.assertTrue(same.replaced)
            self.assertEqual((same.kept.meshes, same.removed), (["kit.mesh0"], []))
            self.assertEqual(self.client.commit().blas_rebuilds, 0)
            with open(path, "w") as f:
                f.write("v 0 0 0\nv 2 0 0\nv 2 2 0\nf 1 2 3\n")
            changed = self.client.reimport_asset("kit", path, if_match=same.version)
            self.assertEqual(changed.kept.meshes, [])
            self.assertEqual(self.client.commit().blas_rebuilds, 1)
        gone = self.client.delete_asset("kit")
        self.assertIsInstance(gone, AssetDeleteResult)
        self.assertEqual(gone.removed["meshes"], ["kit.mesh0"])
        self.assertEqual(self.client.assets(), [])
        with self.assertRaises(NotFoundError):
            self.client.asset("kit")
        with self.assertRaises(NotFoundError):
            self.client.delete_asset("kit")


class TypedProblemsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.server = ServerProcess(SERVER)
        cls.client = Client(cls.server.url)
        cls.client.edit(SCENE)

    @classmethod
    def tearDownClass(cls):
        cls.client.close()
        cls.server.stop()

    def assert_problem(self, call, cls, status, problem_type, pointer=None):
        with self.assertRaises(cls) as caught:
            call()
        p = caught.exception
        self.assertIsInstance(p, ProblemError)  # `except ProblemError` still catches them all
        self.assertEqual((p.status, p.problem_type, p.pointer), (status, problem_type, pointer))
        self.assertIsInstance(p.problem, Problem)
        self.assertEqual(p.problem.type, "https://strata.dev/problems/" + problem_type)
        self.assertEqual((p.problem.status, p.problem.title, p.problem.pointer),
                         (status, p.title, pointer))
        return p

    def test_each_status_raises_its_own_class(self):
        p = self.assert_problem(
            lambda: self.client.edit([{"op": "remove_instance", "instance": "nope"}]),
            UnprocessableError, 422, "unknown-id", "/edits/0/instance")
        self.assertEqual(p.problem.edit_index, 0)
        self.assert_problem(lambda: self.client.edit([{"op": "add_mesh", "id": "m",
                                                       "postions": []}]),
                            BadRequestError, 400, "invalid-request", "/edits/0/postions")
        self.assert_problem(lambda: self.client.scene("meshes", "nope"), NotFoundError, 404,
                            "not-found")
        self.assert_problem(lambda: self.client.render(65536, 65536), TooLargeError, 413,
                            "too-large", "/width")

    def test_a_version_mismatch_names_the_current_version(self):
        version = self.client.edit([])
        p = self.assert_problem(lambda: self.client.edit([], if_match=version - 1),
                                VersionMismatchError, 412, "version-mismatch")
        self.assertEqual(p.current_version, version)
        self.assertEqual(p.headers["etag"], f'"{version}"')
        self.assertEqual(self.client.edit([], if_match=p.current_version), version + 1)

    def test_a_problems_own_members_are_its_extensions(self):
        with tempfile.NamedTemporaryFile("w", suffix=".ply", delete=False) as f:
            f.write("ply\nformat ascii 1.0\nelement vertex 1\n")
        try:
            p = self.assert_problem(lambda: self.client.import_asset(f.name), UnprocessableError,
                                    422, "invalid-asset")
        finally:
            os.unlink(f.name)
        self.assertEqual(p.problem.extensions["file"], os.path.basename(f.name))
        self.assertEqual(p.problem.extensions["element"], "header")
        self.assertNotIn("title", p.problem.extensions)


def body_limit_batches():
    """For a server with --max-body-mb 2: a batch of about 1.2 MB it takes and one of about 3 MB
    it refuses with 413."""
    def mesh(id, copies):
        return [{"op": "add_mesh", "id": id, "positions": [0, 0, 0, 1, 0, 0, 0, 1, 0] * copies,
                 "indices": [0, 1, 2]}]
    return mesh("fits", 45_000), mesh("too-big", 110_000)


class BodyLimitTest(unittest.TestCase):
    def test_a_body_over_the_limit_is_a_413_problem_not_a_broken_pipe(self):
        fits, too_big = body_limit_batches()
        with ServerProcess(SERVER, ["--max-body-mb", "2"]) as server, \
                Client(server.url) as client:
            client.stats()
            with self.assertRaises(TooLargeError) as caught:
                client.edit(too_big)
            self.assertIn("--max-body-mb", caught.exception.detail)
            self.assertEqual(client.edit(fits), 1)


class ResultParsingTest(unittest.TestCase):
    """How results read answers from a newer or a broken server (no server needed)."""

    REPORT = {"version": 3, "planned": True, "blas_rebuilds": 0, "blas_refits": 0,
              "tlas": {"action": "none", "instances": 0, "strategy": "incremental"},
              "rebuilt": [], "refit": [], "released": [], "primitives_built": 0,
              "primitives_refit": 0, "world_transforms": 0, "instances_changed": 0,
              "memory_bytes": {"blas": 0, "tlas": 0}}

    def test_members_a_newer_server_adds_are_kept(self):
        doc = dict(self.REPORT, shiny_new_member=[1, 2])
        doc["tlas"] = dict(doc["tlas"], also_new=True)
        report = RebuildReport.from_json(doc)
        self.assertEqual(report["shiny_new_member"], [1, 2])
        self.assertTrue(report.tlas["also_new"])
        self.assertEqual(report, doc)

    def test_a_missing_member_is_a_value_error(self):
        doc = dict(self.REPORT)
        del doc["tlas"]
        with self.assertRaises(ValueError):
            RebuildReport.from_json(doc)

    def test_a_result_made_in_code_is_its_dict_too(self):
        hit = Hit("i", "m", 2.0, 7, [0, 0, 0], [0, 0, 1])
        self.assertEqual(hit["primitive"], 7)
        self.assertEqual(Hit.from_json(json.loads(json.dumps(hit))), hit)

    def test_an_answer_that_is_not_a_problem_document_still_raises_by_status(self):
        from strata_client.errors import problem_error
        p = problem_error(404, {}, b"<html>gone</html>")
        self.assertIsInstance(p, NotFoundError)
        self.assertEqual((p.title, p.body, p.problem.type), ("HTTP 404", "<html>gone</html>",
                                                              "about:blank"))
        self.assertIs(type(problem_error(502, {}, b"")), ProblemError)


if __name__ == "__main__":
    unittest.main()

"""The Python client against a real strata-server: every method, problem documents as
ProblemError, If-Match, keep-alive and reconnection, bearer tokens, and numpy frames."""

import json
import os
import socket
import tempfile
import unittest

from strata_client import Client, ProblemError
from strata_process import ServerProcess

SERVER = os.environ.get("STRATA_SERVER_BINARY", "build/server/strata-server")

SCENE = [
    {"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 16}},
    {"op": "add_material", "id": "red", "base_color": [0.9, 0.1, 0.1]},
    {"op": "add_instance", "id": "b0", "mesh": "ball", "material": "red"},
    {"op": "set_camera", "eye": [0, 0.5, 4], "target": [0, 0, 0]},
]


class ServerTestCase(unittest.TestCase):
    """One server and one client for the class."""

    @classmethod
    def setUpClass(cls):
        cls.server = ServerProcess(SERVER)
        cls.client = Client(cls.server.url)

    @classmethod
    def tearDownClass(cls):
        cls.client.close()
        cls.server.stop()


class SceneTestCase(unittest.TestCase):
    """One server for the class; each test starts from SCENE with a fresh blocking client."""

    @classmethod
    def setUpClass(cls):
        cls.server = ServerProcess(SERVER)

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()

    def setUp(self):
        self.client = Client(self.server.url)
        self.client.edit([{"op": "clear"}])
        self.version = self.client.edit(SCENE)

    def tearDown(self):
        self.client.close()


class ClientTest(SceneTestCase):

    def test_edit_returns_the_new_version_and_commit_the_report(self):
        report = self.client.commit()
        self.assertEqual(report["version"], self.version)
        self.assertEqual(report["tlas"]["action"], "update")
        self.assertEqual([e["mesh"] for e in report["rebuilt"]], ["ball"])
        self.assertEqual(report["primitives_built"], 224)
        moved = self.client.edit([{"op": "set_transform", "instance": "b0",
                                   "transform": {"translate": [0, 1, 0]}}])
        self.assertEqual(moved, self.version + 1)
        plan = self.client.plan()
        self.assertTrue(plan["planned"])
        self.assertEqual(plan["tlas"]["action"], "update")
        self.assertEqual(plan["rebuilt"], [])
        self.assertEqual(self.client.commit()["blas_rebuilds"], 0)

    def test_an_invalid_edit_raises_a_problem_with_its_index_and_pointer(self):
        with self.assertRaises(ProblemError) as caught:
            self.client.edit([{"op": "set_camera", "fov_y_deg": 30},
                              {"op": "remove_instance", "instance": "nope"}])
        p = caught.exception
        self.assertEqual(p.status, 422)
        self.assertEqual(p.title, "Unknown id")
        self.assertEqual(p.edit_index, 1)
        self.assertEqual(p.pointer, "/edits/1/instance")
        self.assertEqual(p.type, "https://strata.dev/problems/unknown-id")
        self.assertIn("unknown instance 'nope'", p.detail)
        self.assertIn("422 Unknown id: edit 1", str(p))
        # Atomic: the valid first edit was not applied either.
        self.assertEqual(self.client.scene()["version"], self.version)

    def test_a_schema_error_is_a_400_problem(self):
        with self.assertRaises(ProblemError) as caught:
            self.client.edit([{"op": "add_mesh", "id": "m", "postions": []}])
        self.assertEqual(caught.exception.status, 400)
        self.assertEqual(caught.exception.pointer, "/edits/0/postions")
        self.assertEqual(caught.exception.edit_index, 0)

    def test_if_match_applies_only_at_that_version(self):
        v = self.client.edit([], if_match=self.version)
        self.assertEqual(v, self.version + 1)
        with self.assertRaises(ProblemError) as caught:
            self.client.edit([], if_match=self.version)
        self.assertEqual(caught.exception.status, 412)
        self.assertEqual(caught.exception.etag, f'"{self.version + 1}"')
        self.assertEqual(self.client.edit([], if_match="*"), self.version + 2)

    def test_render_returns_the_image_and_what_its_commit_did(self):
        png = self.client.render(64, 32)
        self.assertTrue(png.startswith(b"\x89PNG\r\n\x1a\n"))
        info = self.client.last_render
        self.assertEqual(info.version, self.version)
        self.assertEqual(info.content_type, "image/png")
        self.assertTrue(info.rebuild.startswith(f"v{self.version} tlas=update(1) rebuilds=1"),
                        info.rebuild)
        self.assertEqual(info.report["version"], self.version)
        self.assertEqual(info.report["blas_rebuilds"], 1)
        self.assertEqual(info.report["tlas"]["action"], "update")
        self.assertEqual(len(info.report["rebuilt"]), 1)
        self.client.render(16, 16, camera={"eye": [0, 5, 0.1]}, exposure=1)
        self.assertTrue(self.client.last_render.rebuild.startswith(
            f"v{self.version} tlas=none(1) rebuilds=0 refits=0"))

    def test_render_problems_carry_their_pointer(self):
        with self.assertRaises(ProblemError) as caught:
            self.client.render(65536, 65536)
        self.assertEqual(caught.exception.status, 413)
        self.assertEqual(caught.exception.pointer, "/width")
        with self.assertRaises(ProblemError) as caught:
            self.client.render(8, 8, widht=3)
        self.assertEqual(caught.exception.status, 400)

    def test_render_array_is_a_numpy_image_of_the_frame(self):
        import numpy as np
        frame = self.client.render_array(48, 32)
        self.assertEqual(frame.shape, (32, 48, 3))
        self.assertEqual(frame.dtype, np.uint8)
        # The red ball sits in the middle of a sky-coloured frame.
        centre, corner = frame[16, 24].astype(int), frame[0, 0].astype(int)
        self.assertGreater(centre[0], centre[2])
        self.assertGreater(corner[2], corner[0])
        with self.assertRaises(ValueError):
            self.client.render_array(8, 8, fmt="exr")
        linear = self.client.render_array(48, 32, fmt="npz")
        self.assertEqual((linear.shape, linear.dtype), ((32, 48, 3), np.float32))
        self.assertGreater(linear[16, 24, 0], linear[16, 24, 2])

    def test_render_arrays_gives_the_aovs_and_the_client_ids_behind_ids(self):
        import numpy as np
        from strata_client import MISS, FrameArrays
        frame = self.client.render_arrays(48, 32, aovs=["depth", "instance_id", "mesh_id"])
        self.assertIsInstance(frame, FrameArrays)
        self.assertEqual(frame.info.version, self.version)
        self.assertEqual(frame["depth"].shape, (32, 48))
        self.assertEqual(frame["instance_id"].dtype, np.uint32)
        self.assertIn("beauty", frame)
        self.assertEqual(frame.client_id("instance_id", frame["instance_id"][16, 24]), "b0")
        self.assertEqual(frame.client_id("mesh_id", frame["mesh_id"][16, 24]), "ball")
        self.assertIsNone(frame.client_id("instance_id", MISS))
        ids = frame.client_ids("instance_id")
        self.assertEqual(ids.shape, (32, 48))
        self.assertEqual(ids[16, 24], "b0")
        self.assertIsNone(ids[0, 0])
        self.assertEqual(set(ids.flatten().tolist()), {"b0", None})

    def test_stats_and_scene(self):
        self.client.commit()
        stats = self.client.stats()
        self.assertEqual(stats["version"], self.version)
        self.assertEqual(stats["last_report"]["version"], self.version)
        self.assertGreater(stats["counters"]["commits"], 0)
        scene = self.client.scene()
        self.assertEqual(scene["counts"]["instances"], 1)
        self.assertEqual(self.client.scene("instances", "b0")["material"], "red")
        self.assertEqual(self.client.scene("meshes", "ball")["triangles"], 224)
        with self.assertRaises(ProblemError) as caught:
            self.client.scene("materials", "nope/../x")
        self.assertEqual(caught.exception.status, 404)
        with self.assertRaises(ValueError):
            self.client.scene("cameras", "main")

    def test_instances_follows_cursors_through_every_page(self):
        self.client.edit([{"op": "add_instance", "id": f"/World/b{i}", "mesh": "ball",
                           "visible": i % 3 != 0} for i in range(25)])
        listed = list(self.client.instances(page_size=4))
        self.assertEqual(len(listed), 26)
        self.assertEqual(len({item["id"] for item in listed}), 26)
        self.assertEqual(listed[0], self.client.scene("instances", listed[0]["id"]))
        hidden = [item["id"] for item in self.client.instances(page_size=3, visible=False)]
        self.assertEqual(sorted(hidden), sorted(f"/World/b{i}" for i in range(0, 25, 3)))
        self.assertEqual(len(list(self.client.instances(mesh="ball"))), 26)
        with self.assertRaises(ProblemError) as caught:
            list(self.client.instances(mesh="nope"))
        self.assertEqual(caught.exception.status, 404)
        self.assertEqual([m["id"] for m in self.client.meshes()], ["ball"])
        self.assertEqual([m["id"] for m in self.client.materials(page_size=1)], ["red"])

    def test_pick_names_the_instance_under_a_pixel(self):
        hit = self.client.pick(32, 32, 64, 64)
        self.assertIsNotNone(hit)
        self.assertEqual(hit["instance"], "b0")
        self.assertEqual(hit["mesh"], "ball")
        self.assertAlmostEqual(hit["distance"], 3.03, delta=0.1)
        self.assertIsNone(self.client.pick(0, 0, 64, 64))
        hits = self.client.pick_many([(32, 32), (0, 0)], 64, 64,
                                     camera={"target": [0, 0, 20]})
        self.assertEqual(hits, [None, None])
        with self.assertRaises(ProblemError) as caught:
            self.client.pick(64, 0, 64, 64)
        self.assertEqual(caught.exception.status, 422)
        self.assertEqual(caught.exception.pointer, "/pixels/0")

    def test_import_asset_uploads_a_model_and_answers_its_ids(self):
        spot = os.path.join(os.environ["STRATA_MODELS_DIR"], "spot.obj")
        self.assertTrue(os.path.exists(spot), spot + " missing")
        answer = self.client.import_asset(spot, prefix="cow")
        self.assertEqual(answer["version"], self.version + 1)
        self.assertEqual(answer["meshes"], ["cow.mesh0"])
        self.assertEqual(answer["instances"], ["cow.node0"])
        self.assertEqual(answer["groups"], ["cow"])
        self.assertEqual(self.client.scene("instances", "cow.node0")["parent"], "cow")
        self.assertEqual(self.client.scene("meshes", "cow.mesh0")["triangles"], 5856)
        with tempfile.NamedTemporaryFile("w", suffix=".ply", delete=False) as f:
            f.write("ply\nformat ascii 1.0\nelement vertex 1\n")
        try:
            with self.assertRaises(ProblemError) as caught:
                self.client.import_asset(f.name)
        finally:
            os.unlink(f.name)
        p = caught.exception
        self.assertEqual(p.status, 422)
        self.assertEqual(p.title, "Invalid asset")
        self.assertEqual(p.body["file"], os.path.basename(f.name))
        self.assertEqual(p.body["element"], "header")
        self.assertEqual(self.client.stats()["version"], self.version + 1)

    def test_import_asset_packs_an_obj_with_its_mtl_and_image(self):
        png = os.path.join(os.path.dirname(__file__), "..", "assets", "data", "bunny.png")
        with tempfile.TemporaryDirectory() as d:
            os.makedirs(os.path.join(d, "models"))
            os.makedirs(os.path.join(d, "materials", "tex"))
            with open(os.path.join(d, "models", "quad.obj"), "w") as f:
                f.write("mtllib ../materials/quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl painted\nf 1/1 2/2 3/3 4/4\n")
            with open(os.path.join(d, "materials", "quad.mtl"), "w") as f:
                f.write("newmtl painted\nKd 0.8 0.4 0.2\nmap_Kd tex/p.png\n")
            with open(png, "rb") as src, open(os.path.join(d, "materials", "tex", "p.png"),
                                              "wb") as dst:
                dst.write(src.read())
            answer = self.client.import_asset(os.path.join(d, "models", "quad.obj"))
        self.assertEqual(answer["model"], "models/quad.obj")
        self.assertEqual(answer["textures"], ["quad.texture0"])
        self.assertEqual(self.client.scene("materials", "quad.material0")["base_color_texture"],
                         "quad.texture0")

    def test_import_asset_packs_a_gltf_directory(self):
        gltf = os.path.join(os.environ.get("STRATA_ASSIMP_MODELS_DIR", "/usr/share/assimp/models"),
                            "glTF2", "BoxTextured-glTF", "BoxTextured.gltf")
        if not os.path.exists(gltf):
            self.skipTest(gltf + " missing")
        answer = self.client.import_asset(gltf)
        self.assertEqual(answer["format"], "gltf")
        self.assertEqual(answer["model"], "BoxTextured.gltf")
        self.assertEqual(answer["textures"], ["BoxTextured.texture0"])
        self.assertEqual(self.client.scene("textures", "BoxTextured.texture0")["format"], "png")

    def test_frame_aims_a_render_at_a_group_far_out_of_view(self):
        self.client.edit([
            {"op": "add_group", "id": "far", "transform": {"translate": [400, 0, 0]}},
            {"op": "add_instance", "id": "far-ball", "mesh": "ball", "parent": "far"}])
        group = self.client.scene("groups", "far")
        self.assertEqual([round(v) for v in group["bounds"]["min"]], [399, -1, -1])
        plain = self.client.render_arrays(48, 32, aovs=["instance_id"])
        self.assertNotIn("far-ball", set(plain.client_ids("instance_id").flatten().tolist()))
        framed = self.client.render_arrays(48, 32, aovs=["instance_id"], frame={"group": "far"})
        self.assertEqual(framed.client_id("instance_id", framed["instance_id"][16, 24]),
                         "far-ball")
        # The whole ball is in the frame: no edge pixel shows it.
        ids = framed.client_ids("instance_id")
        for edge in (ids[0, :], ids[-1, :], ids[:, 0], ids[:, -1]):
            self.assertNotIn("far-ball", set(edge.tolist()))
        with self.assertRaises(ProblemError) as caught:
            self.client.render_frame(16, 16, frame={"instance": "nowhere"})
        self.assertEqual((caught.exception.status, caught.exception.pointer),
                         (422, "/frame/instance"))

    def test_import_asset_decodes_a_draco_compressed_gltf(self):
        gltf = os.path.join(os.environ.get("STRATA_ASSIMP_MODELS_DIR", "/usr/share/assimp/models"),
                            "glTF2", "draco", "2CylinderEngine.gltf")
        if not os.path.exists(gltf):
            self.skipTest(gltf + " missing")
        answer = self.client.import_asset(gltf, prefix="engine")
        self.assertEqual(len(answer["meshes"]), 34)
        self.assertEqual(answer["warnings"], ["1 cameras not imported"])  # nothing of Draco
        self.assertEqual(answer["bounds"], self.client.scene("groups", "engine")["bounds"])
        # Every primitive's triangles, as its indices accessor declares them.
        with open(gltf) as f:
            doc = json.load(f)
        declared = sum(doc["accessors"][p["indices"]]["count"] // 3
                       for m in doc["meshes"] for p in m["primitives"])
        meshes = [self.client.scene("meshes", m) for m in answer["meshes"]]
        self.assertEqual(sum(m["triangles"] for m in meshes), declared)
        self.assertTrue(all(m["normals"] for m in meshes))

    def test_import_asset_refuses_a_missing_side_file_before_sending(self):
        with tempfile.TemporaryDirectory() as d:
            obj = os.path.join(d, "quad.obj")
            with open(obj, "w") as f:
                f.write("mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
            with self.assertRaises(FileNotFoundError) as caught:
                self.client.import_asset(obj)
        self.assertIn("quad.obj (mtllib) names 'gone.mtl'", str(caught.exception))
        self.assertEqual(self.client.stats()["version"], self.version)
        with tempfile.TemporaryDirectory() as d:
            os.makedirs(os.path.join(d, "models"))
            with open(os.path.join(d, "secret.txt"), "w") as f:
                f.write("password")
            obj = os.path.join(d, "models", "quad.obj")
            with open(obj, "w") as f:
                f.write("mtllib ../secret.txt\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
            with self.assertRaises(ValueError) as refused:
                self.client.import_asset(obj)
        self.assertIn("outside the model's folder only .mtl", str(refused.exception))
        self.assertEqual(self.client.stats()["version"], self.version)

    def test_groups_children_tree_and_group_path(self):
        self.client.edit([
            {"op": "add_group", "id": "car"},
            {"op": "add_group", "id": "wheels", "parent": "car"},
            {"op": "update_instance", "instance": "b0", "parent": "wheels"},
            {"op": "add_instance", "id": "spare", "mesh": "ball", "parent": "car",
             "transform": {"translate": [0, 50, 0]}},
        ])
        self.assertEqual([g["id"] for g in self.client.groups(page_size=1)], ["car", "wheels"])
        self.assertEqual([g["id"] for g in self.client.groups(parent="")], ["car"])
        self.assertEqual([i["id"] for i in self.client.instances(parent="wheels")], ["b0"])
        self.assertEqual([i["id"] for i in self.client.instances(parent="")], [])
        kids = list(self.client.children("car", page_size=1))
        self.assertEqual([(k["kind"], k["id"]) for k in kids],
                         [("group", "wheels"), ("instance", "spare")])
        tree = self.client.tree(depth=2)
        self.assertEqual(tree["groups"][0]["id"], "car")
        self.assertEqual(tree["groups"][0]["groups"][0]["instances"][0]["id"], "b0")
        self.assertFalse(tree["truncated"])
        self.assertTrue(self.client.tree(depth=2, max_nodes=2)["truncated"])
        self.assertEqual(self.client.pick(32, 32, 64, 64)["group_path"], ["car", "wheels"])
        # Moving the car moves b0 out of the view.
        self.client.edit([{"op": "set_transform", "group": "car",
                           "transform": {"translate": [100, 0, 0]}}])
        self.assertIsNone(self.client.pick(32, 32, 64, 64))
        b0 = self.client.scene("instances", "b0")
        self.assertEqual(b0["parent"], "wheels")
        self.assertEqual(b0["world_transform"][3], 100)
        self.assertEqual(self.client.scene("groups", "wheels")["children"]["instances"], 1)
        with self.assertRaises(ProblemError) as caught:
            self.client.edit([{"op": "update_group", "group": "car", "parent": "wheels"}])
        self.assertEqual(caught.exception.status, 422)
        self.assertIn("'car' > 'wheels' > 'car'", caught.exception.detail)
        with self.assertRaises(ProblemError) as caught:
            self.client.edit([{"op": "remove_group", "group": "car"}])
        self.assertEqual(caught.exception.status, 422)
        self.client.edit([{"op": "remove_group", "group": "car", "recursive": True}])
        self.assertEqual(list(self.client.groups()), [])
        self.assertEqual(self.client.scene()["counts"]["instances"], 0)

    def test_lights_are_listed_edited_and_refused_with_the_field_named(self):
        self.client.edit([
            {"op": "add_light", "id": "lamp", "type": "spot", "position": [0, 4, 0],
             "intensity": 40, "angle_deg": 35},
            {"op": "add_light", "id": "panel", "type": "rect", "direction": [0, 0, 1],
             "width": 2, "height": 1},
        ])
        self.assertEqual([l["id"] for l in self.client.lights(page_size=1)], ["lamp", "panel"])
        self.assertEqual(self.client.scene()["counts"]["lights"], 2)
        self.client.edit([{"op": "update_light", "light": "lamp", "color": [1, 0.5, 0.25]}])
        lamp = self.client.scene("lights", "lamp")
        self.assertEqual((lamp["type"], lamp["color"], lamp["angle_deg"]),
                         ("spot", [1, 0.5, 0.25], 35))
        before = self.client.stats()["version"]
        with self.assertRaises(ProblemError) as caught:
            self.client.edit([{"op": "remove_light", "light": "panel"},
                              {"op": "update_light", "light": "lamp", "inner_angle_deg": 50}])
        self.assertEqual(caught.exception.status, 422)
        self.assertEqual(caught.exception.pointer, "/edits/1/inner_angle_deg")
        self.assertEqual(self.client.stats()["version"], before)
        self.assertEqual(len(list(self.client.lights())), 2)
        self.client.edit([{"op": "remove_light", "light": "panel"}])
        self.assertEqual([l["id"] for l in self.client.lights()], ["lamp"])

    def test_one_connection_is_kept_alive_across_requests(self):
        self.client.stats()
        sock = self.client._conn.sock
        for _ in range(5):
            self.client.plan()
            self.client.commit()
        self.assertIs(self.client._conn.sock, sock)

    def test_a_dropped_connection_is_reopened(self):
        self.client.stats()
        self.client._conn.sock.shutdown(socket.SHUT_RDWR)  # as if the server had closed it
        self.assertEqual(self.client.stats()["version"], self.version)
        # Edits are safe to resend: the server never saw the first attempt.
        self.client._conn.sock.shutdown(socket.SHUT_RDWR)
        self.assertEqual(self.client.edit([]), self.version + 1)
        self.assertEqual(self.client.edit([]), self.version + 2)

    def test_a_context_manager_closes_the_connection(self):
        with Client(self.server.url) as c:
            c.stats()
            self.assertIsNotNone(c._conn)
        self.assertIsNone(c._conn)

    def test_bad_urls_are_refused(self):
        for url in ("localhost:7070", "ftp://host", "http://host/v1", "http://"):
            with self.assertRaises(ValueError):
                Client(url)

    def test_an_unreachable_server_raises_a_connection_error(self):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        with self.assertRaises(ConnectionError):
            Client(f"http://127.0.0.1:{port}", timeout=5).stats()


class TokenTest(unittest.TestCase):
    def test_the_bearer_token_is_sent(self):
        with tempfile.NamedTemporaryFile("w", suffix=".token", delete=False) as f:
            f.write("s3cret\n")
        try:
            with ServerProcess(SERVER, ["--token-file", f.name]) as server:
                with self.assertRaises(ProblemError) as caught:
                    Client(server.url).stats()
                self.assertEqual(caught.exception.status, 401)
                self.assertEqual(caught.exception.title, "Unauthorized")
                with Client(server.url, token="s3cret") as c:
                    self.assertEqual(c.stats()["version"], 0)
        finally:
            os.unlink(f.name)


if __name__ == "__main__":
    unittest.main()

"""Frames as numpy arrays (`format=npz`) from a real strata-server, read by numpy.load alone: the
arrays and their shapes and types, the ID manifest resolving instance ids to client ids, linear
values, and the refusals. (tests/engine/npz_test.cpp compares the arrays with the EXR frame.)"""

import io
import json
import os
import unittest
import urllib.error
import urllib.request
import zipfile

import numpy

from strata_process import ServerProcess

SERVER = os.environ.get("STRATA_SERVER_BINARY", "build/server/strata-server")

SCENE = [
    {"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 16}},
    {"op": "add_mesh", "id": "floor", "shape": {"type": "plane"}},
    {"op": "add_material", "id": "red", "base_color": [0.9, 0.1, 0.1]},
    {"op": "add_instance", "id": "b0", "mesh": "ball", "material": "red"},
    {"op": "add_instance", "id": "kugel-ü", "mesh": "ball",
     "transform": [1, 0, 0, 1.5, 0, 1, 0, 0, 0, 0, 1, 0]},
    {"op": "set_camera", "eye": [0.75, 0.5, 5], "target": [0.75, 0, 0]},
]


class NpzFrames(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.server = ServerProcess(SERVER)
        cls.call("POST", "/v1/edits", json.dumps({"edits": SCENE}).encode())

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()

    @classmethod
    def call(cls, method, path, body=None):
        req = urllib.request.Request(cls.server.url + path, data=body, method=method,
                                     headers={"Content-Type": "application/json"} if body else {})
        try:
            with urllib.request.urlopen(req, timeout=30) as r:
                return r.status, dict(r.headers), r.read()
        except urllib.error.HTTPError as e:
            return e.code, dict(e.headers), e.read()

    def frame(self, query):
        status, headers, body = self.call("GET", "/v1/render?" + query)
        self.assertEqual(status, 200, body[:300])
        self.assertEqual(headers["Content-Type"], "application/x-npz")
        self.assertTrue(zipfile.is_zipfile(io.BytesIO(body)))
        self.assertIsNone(zipfile.ZipFile(io.BytesIO(body)).testzip())  # every CRC holds
        return numpy.load(io.BytesIO(body), allow_pickle=False)

    def test_every_aov_is_an_array_of_its_shape_and_type(self):
        f = self.frame("width=40&height=30&format=npz&aovs=albedo,normal,depth,position,"
                       "instance_id,primitive_id,mesh_id,user_id")
        expected = {
            "beauty": ((30, 40, 3), numpy.float32), "albedo": ((30, 40, 3), numpy.float32),
            "normal": ((30, 40, 3), numpy.float32), "position": ((30, 40, 3), numpy.float32),
            "depth": ((30, 40), numpy.float32), "instance_id": ((30, 40), numpy.uint32),
            "primitive_id": ((30, 40), numpy.uint32), "mesh_id": ((30, 40), numpy.uint32),
            "user_id": ((30, 40), numpy.uint32),
        }
        for name, (shape, dtype) in expected.items():
            self.assertEqual(f[name].shape, shape, name)
            self.assertEqual(f[name].dtype, dtype, name)
        self.assertEqual(sorted(f.files), sorted(list(expected) + [
            "instance_id.ids", "instance_id.names", "mesh_id.ids", "mesh_id.names"]))
        # The sky: no hit, infinite depth; the centre of the left ball: a hit, near depth.
        self.assertEqual(f["instance_id"][0, 0], 0xFFFFFFFF)
        self.assertTrue(numpy.isinf(f["depth"][0, 0]))
        self.assertTrue(numpy.all(numpy.isfinite(f["beauty"])))

    def test_the_manifest_names_every_instance_and_mesh_in_the_frame(self):
        f = self.frame("width=64&height=32&format=npz&aovs=instance_id,mesh_id")
        instances = dict(zip(f["instance_id.ids"].tolist(), f["instance_id.names"].tolist()))
        meshes = dict(zip(f["mesh_id.ids"].tolist(), f["mesh_id.names"].tolist()))
        seen = {instances[v] for v in numpy.unique(f["instance_id"]).tolist() if v != 0xFFFFFFFF}
        self.assertEqual(seen, {"b0", "kugel-ü"})
        self.assertEqual({meshes[v] for v in numpy.unique(f["mesh_id"]).tolist()
                          if v != 0xFFFFFFFF}, {"ball"})
        self.assertEqual(f["instance_id.names"].dtype.kind, "U")

    def test_the_arrays_are_linear_and_the_same_for_the_same_frame(self):
        query = "width=32&height=24&spp=2&aovs=depth,instance_id&format=npz"
        f = self.frame(query)
        # Same version, camera and spp: the same frame, to the bit.
        again = self.frame(query)
        for name in ("beauty", "depth", "instance_id"):
            numpy.testing.assert_array_equal(f[name], again[name])
        # Linear like the EXR: exposure does not change the arrays (it does change a PNG).
        numpy.testing.assert_array_equal(f["beauty"], self.frame(query + "&exposure=3")["beauty"])
        self.assertGreater(float(f["beauty"].max()), 0.0)

    def test_png_with_aovs_names_npz_and_a_bad_format_is_refused(self):
        status, _, body = self.call("GET", "/v1/render?width=8&height=8&aovs=depth")
        self.assertEqual(status, 422)
        self.assertIn("needs format exr or npz", json.loads(body)["detail"])
        status, _, body = self.call("GET", "/v1/render?width=8&height=8&format=npy")
        self.assertEqual(status, 400)
        self.assertIn("npz", json.loads(body)["detail"])
        status, _, body = self.call("POST", "/v1/render",
                                    json.dumps({"width": 8, "height": 8, "format": "npz"}).encode())
        self.assertEqual(status, 200)
        self.assertEqual(numpy.load(io.BytesIO(body))["beauty"].shape, (8, 8, 3))


if __name__ == "__main__":
    unittest.main()

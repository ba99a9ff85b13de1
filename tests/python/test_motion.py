"""Motion blur through the Python client against a real strata-server: an instance's motion
keys put it where they say at the shutter's opening (what picks see), SRT keys turn rigidly where
linear ones shrink, key edits are one TLAS update, a blurred render differs from a still one, and
bad keys are refused with their pointer and change nothing. A mesh's vertex keys (deformation
blur, packed by strata_client.mesh_edits) put its vertices where they say at a ray's time, a
change of them rebuilds that mesh alone (keys added or removed with their own reason), and undo
takes them back."""

import unittest

import numpy

from strata_client import UnprocessableError, mesh_edits
from test_client import ServerTestCase


def camera(time: float, x: float = 0.0) -> dict:
    return {"eye": [x, 0, 10], "target": [x, 0, 0], "up": [0, 1, 0], "fov_y_deg": 20,
            "shutter_open": time, "shutter_close": time}


class MotionTest(ServerTestCase):

    def setUp(self):
        keys = [{"translate": [-2, 0, 0]}, {"translate": [0, 0, 0]}, {"translate": [2, 0, 0]}]
        self.client.edit([{"op": "clear"},
                          {"op": "add_mesh", "id": "ball", "shape": {"type": "sphere"}},
                          {"op": "add_instance", "id": "b", "mesh": "ball", "motion": keys}])
        self.client.commit()

    def test_picks_see_the_keys_at_the_shutter_opening(self):
        for time, x in [(0.0, -2.0), (0.25, -1.0), (0.5, 0.0), (1.0, 2.0)]:
            hit = self.client.pick(50, 50, 101, 101, camera=camera(time, x))
            self.assertIsNotNone(hit, f"time {time}")
            self.assertAlmostEqual(hit.distance, 9.0, places=2)
            self.assertIsNone(self.client.pick(50, 50, 101, 101, camera=camera(time, x + 3)))
        self.assertEqual(len(self.client.scene("instances", "b")["motion"]), 3)

    def test_key_edits_are_one_tlas_update_and_blur_the_frame(self):
        self.client.edit([{"op": "update_instance", "instance": "b",
                           "motion": [{"translate": [0, 0, 0]}, {"translate": [1, 0, 0]}]}])
        report = self.client.commit()
        self.assertEqual((report.tlas.action, report.blas_rebuilds, report.blas_refits),
                         ("update", 0, 0))
        self.client.edit([{"op": "set_camera", "eye": [0, 0, 8], "target": [0, 0, 0],
                           "shutter_open": 0, "shutter_close": 0}])
        still = self.client.render(64, 48, spp=8)
        self.client.edit([{"op": "set_camera", "shutter_close": 1}])
        blurred = self.client.render(64, 48, spp=8)
        self.assertNotEqual(still, blurred)

    def test_srt_keys_turn_a_bar_rigidly(self):
        # A bar along x turning 170 degrees about z: halfway, SRT keys hold it upright at full
        # length, a linear blend of the matrices shrinks it to almost nothing.
        keys = [{"rotate_deg": [0, 0, 0]}, {"rotate_deg": [0, 0, 170]}]
        self.client.edit([{"op": "add_mesh", "id": "bar", "shape": {"type": "box",
                                                                  "size": [4, 0.3, 0.3]}},
                          {"op": "add_instance", "id": "turning", "mesh": "bar", "motion": keys,
                           "motion_interpolation": "srt"},
                          {"op": "update_instance", "instance": "b", "visible": False}])
        upright = dict(camera(0.5), eye=[0, 1.5, 10], target=[0, 1.5, 0])
        hit = self.client.pick(50, 50, 101, 101, camera=upright)
        self.assertEqual(hit.instance if hit else None, "turning")
        self.assertEqual(self.client.scene("instances", "turning")["motion_interpolation"], "srt")
        self.client.edit([{"op": "update_instance", "instance": "turning",
                           "motion_interpolation": "linear"}])
        self.assertIsNone(self.client.pick(50, 50, 101, 101, camera=upright))

    def test_bad_keys_are_refused_with_their_pointer(self):
        version = self.client.scene()["version"]
        with self.assertRaises(UnprocessableError) as flat:
            self.client.edit([{"op": "update_instance", "instance": "b",
                               "motion": [{"translate": [0, 0, 0]}, {"scale": [1, 0, 1]}]}])
        self.assertEqual(flat.exception.pointer, "/edits/0/motion/1")
        with self.assertRaises(UnprocessableError) as one:
            self.client.edit([{"op": "update_instance", "instance": "b",
                               "motion": [{"translate": [0, 0, 0]}]}])
        self.assertEqual(one.exception.pointer, "/edits/0/motion")
        with self.assertRaises(UnprocessableError) as shutter:
            self.client.edit([{"op": "set_camera", "shutter_open": 0.9, "shutter_close": 0.1}])
        self.assertEqual(shutter.exception.pointer, "/edits/0/shutter_close")
        self.assertEqual(self.client.scene()["version"], version)


class VertexKeysTest(ServerTestCase):
    """A 2x2 square facing the camera whose vertices move from z = 0 to z = 2 and back to z = 0.5
    over the frame (three vertex keys)."""

    SQUARE = numpy.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], numpy.float32)

    def setUp(self):
        keys = [self.SQUARE, self.SQUARE + [0, 0, 2], self.SQUARE + [0, 0, 0.5]]
        self.client.edit([{"op": "clear"},
                          {"op": "add_mesh", "id": "sheet", "positions_b64":
                           mesh_edits.pack_positions(keys[0]), "indices": [0, 1, 2, 0, 2, 3],
                           "motion_positions_b64": mesh_edits.pack_vertex_keys(keys),
                           "build": {"allow_refit": True}},
                          {"op": "add_instance", "id": "s", "mesh": "sheet"}])
        self.client.commit()

    def distance_at(self, time: float) -> float:
        hit = self.client.pick(50, 50, 101, 101, camera=camera(time))
        self.assertIsNotNone(hit, f"time {time}")
        return hit.distance

    def test_picks_see_the_vertices_where_their_keys_say(self):
        for time, z in [(0.0, 0.0), (0.25, 1.0), (0.5, 2.0), (0.75, 1.25), (1.0, 0.5)]:
            self.assertAlmostEqual(self.distance_at(time), 10.0 - z, places=3, msg=f"t {time}")
        mesh = self.client.scene("meshes", "sheet")
        self.assertEqual((mesh["motion_keys"], mesh["motion_positions"]), (3, True))

    def test_key_edits_rebuild_the_mesh_alone(self):
        moved = [self.SQUARE, self.SQUARE + [0, 0, 3], self.SQUARE + [0, 0, 3]]
        self.client.edit([mesh_edits.vertex_keys("sheet", moved)])
        report = self.client.commit()
        self.assertEqual([(e.mesh, e.reason) for e in report.rebuilt],
                         [("sheet", "positions_changed")])
        self.assertEqual(report.refit, [])
        self.assertAlmostEqual(self.distance_at(0.5), 7.0, places=3)
        self.client.edit([mesh_edits.remove_vertex_keys("sheet")])
        report = self.client.commit()
        self.assertEqual([(e.mesh, e.reason) for e in report.rebuilt],
                         [("sheet", "keys_changed")])
        self.assertAlmostEqual(self.distance_at(0.5), 10.0, places=3)
        self.assertEqual(self.client.scene("meshes", "sheet")["motion_keys"], 1)
        self.client.undo()
        self.assertAlmostEqual(self.distance_at(0.5), 7.0, places=3)

    def test_bad_keys_are_refused_with_their_pointer(self):
        version = self.client.scene()["version"]
        with self.assertRaises(UnprocessableError) as uneven:
            self.client.edit([{"op": "update_mesh", "mesh": "sheet",
                               "motion_positions": [0, 0, 0] * 3}])
        self.assertEqual(uneven.exception.pointer, "/edits/0/motion_positions")
        with self.assertRaises(UnprocessableError) as nan:
            self.client.edit([{"op": "update_mesh", "mesh": "sheet", "offset": 1,
                               "motion_positions": [0, 0, 0, 0, 1e39, 0]}])
        self.assertIn("motion_positions", nan.exception.pointer)
        self.assertEqual(self.client.scene()["version"], version)


if __name__ == "__main__":
    unittest.main()

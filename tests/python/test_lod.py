"""Level-of-detail groups through the Python client against a real strata-server: the level a
pick names follows the camera's distance from the group, camera moves cost no BVH work, new
switch distances are one TLAS update, the scene documents show the group's flag and the levels'
ranges, and a bad range is refused with its pointer and changes nothing."""

import unittest

from strata_client import UnprocessableError, lod
from test_client import ServerTestCase


def camera(distance: float) -> dict:
    return {"eye": [0, 0, distance], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 20}


class LevelOfDetailTest(ServerTestCase):

    def setUp(self):
        self.client.edit([{"op": "clear"},
                          {"op": "add_mesh", "id": "ball", "shape": {"type": "sphere"}},
                          {"op": "add_mesh", "id": "box", "shape": {"type": "box"}}]
                         + lod.add_lod_group("tree", [("tree.fine", "ball"),
                                                      ("tree.coarse", "box")],
                                             switch_distances=[20]))
        self.client.commit()

    def level_at(self, distance: float):
        hit = self.client.pick(50, 50, 101, 101, camera=camera(distance))
        return hit.instance if hit else None

    def test_the_camera_distance_chooses_the_level_and_costs_nothing(self):
        self.assertEqual(self.level_at(10), "tree.fine")
        self.assertEqual(self.level_at(30), "tree.coarse")
        self.client.edit([{"op": "set_camera", **camera(30)}])
        report = self.client.commit()
        self.assertEqual((report.tlas.action, report.blas_rebuilds, report.blas_refits),
                         ("none", 0, 0))
        self.assertTrue(self.client.scene("groups", "tree")["lod"])
        fine = self.client.scene("instances", "tree.fine")
        self.assertEqual((fine["lod_near"], fine["lod_far"]), (0, 20))

    def test_new_switch_distances_are_one_tlas_update(self):
        self.client.edit(lod.set_switch_distances(["tree.fine", "tree.coarse"], [40]))
        report = self.client.commit()
        self.assertEqual((report.tlas.action, report.blas_rebuilds, report.blas_refits),
                         ("update", 0, 0))
        self.assertEqual(self.level_at(30), "tree.fine")
        self.assertEqual(self.level_at(50), "tree.coarse")

    def test_a_bad_range_is_refused_with_its_pointer(self):
        version = self.client.scene()["version"]
        with self.assertRaises(UnprocessableError) as inverted:
            self.client.edit([{"op": "update_instance", "instance": "tree.fine",
                               "lod_near": 30}])
        self.assertEqual(inverted.exception.pointer, "/edits/0/lod_far")
        with self.assertRaises(UnprocessableError) as negative:
            self.client.edit([{"op": "add_group", "id": "g", "lod": True, "lod_near": -1}])
        self.assertEqual(negative.exception.pointer, "/edits/0/lod_near")
        self.assertEqual(self.client.scene()["version"], version)
        with self.assertRaises(ValueError):
            lod.add_lod_group("x", [("a", "ball"), ("b", "box")], switch_distances=[])
        with self.assertRaises(ValueError):
            lod.set_switch_distances(["a", "b", "c"], [10, 5])


if __name__ == "__main__":
    unittest.main()

"""Points and curve meshes through the Python client against a real strata-server: numpy
arrays packed by strata_client.mesh_edits make spheres and strands that picks hit at the
distance their radii say, radius edits and a new strand layout rebuild only their mesh, a bad strand list is
refused with the member's pointer and changes nothing, and undo puts the old strands back."""

import unittest

import numpy

from strata_client import UnprocessableError, mesh_edits
from test_client import ServerTestCase

CAMERA = {"eye": [0, 0, 10], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 20}


class PointsAndCurvesTest(ServerTestCase):

    def setUp(self):
        centres = numpy.array([[0, 0, 0], [3, 0, 0]], numpy.float32)
        strand = numpy.stack([numpy.linspace(-2, 2, 4), numpy.full(4, 1.5), numpy.zeros(4)], 1)
        self.client.edit([{"op": "clear"},
                          mesh_edits.add_points("p", centres, numpy.array([1.0, 0.5])),
                          mesh_edits.add_curves("c", strand, [0.25] * 4, strands=[4],
                                                basis="bezier"),
                          {"op": "add_instance", "id": "ip", "mesh": "p"},
                          {"op": "add_instance", "id": "ic", "mesh": "c"}])
        self.client.commit()

    def hit_at(self, x: float, y: float):
        camera = dict(CAMERA, eye=[x, y, 10], target=[x, y, 0])
        return self.client.pick(50, 50, 101, 101, camera=camera)

    def test_picks_hit_spheres_and_tubes_at_their_radii(self):
        sphere = self.hit_at(3, 0)
        self.assertEqual((sphere.mesh, sphere.primitive), ("p", 1))
        self.assertAlmostEqual(sphere.distance, 9.5, places=3)
        tube = self.hit_at(0.1, 1.5)
        self.assertEqual((tube.mesh, tube.primitive), ("c", 0))
        self.assertAlmostEqual(tube.distance, 9.75, places=2)
        mesh = self.client.scene("meshes", "c")
        self.assertEqual((mesh["kind"], mesh["basis"], mesh["strands"], mesh["primitives"]),
                         ("curves", "bezier", 1, 1))
        self.assertTrue(mesh["radii"])

    def test_radius_edits_and_new_strands_rebuild_only_their_mesh(self):
        self.client.edit([mesh_edits.update_radii("p", [0.75], offset=1)])
        report = self.client.commit()
        self.assertEqual(report.refit, [])
        self.assertEqual([(e.mesh, e.reason) for e in report.rebuilt],
                         [("p", "positions_changed")])
        self.assertAlmostEqual(self.hit_at(3, 0).distance, 9.25, places=3)

        seven = numpy.stack([numpy.linspace(-2, 2, 7), numpy.full(7, 1.5), numpy.zeros(7)], 1)
        self.client.edit([{"op": "update_mesh", "mesh": "c",
                           "positions_b64": mesh_edits.pack_positions(seven),
                           "radii_b64": mesh_edits.pack_radii([0.25] * 7), "strands": [7]}])
        report = self.client.commit()
        self.assertEqual([(e.mesh, e.reason) for e in report.rebuilt],
                         [("c", "topology_changed")])
        self.assertEqual(self.client.scene("meshes", "c")["primitives"], 2)
        self.client.undo()
        self.assertEqual(self.client.scene("meshes", "c")["primitives"], 1)

    def test_bad_strands_and_radii_are_refused_with_their_pointer(self):
        version = self.client.scene()["version"]
        with self.assertRaises(UnprocessableError) as refused:
            self.client.edit([mesh_edits.update_radii("p", [0.5]),
                              {"op": "update_mesh", "mesh": "c", "strands": [2, 2]}])
        self.assertEqual(refused.exception.pointer, "/edits/1/strands/0")
        self.assertIn("3k + 1", refused.exception.detail)
        with self.assertRaises(UnprocessableError) as negative:
            self.client.edit([{"op": "add_mesh", "id": "q", "kind": "points",
                               "positions": [0, 0, 0], "radii": [-1]}])
        self.assertEqual(negative.exception.pointer, "/edits/0/radii/0")
        with self.assertRaises(UnprocessableError) as tube:
            self.client.edit([{"op": "add_mesh", "id": "q", "shape": {"type": "box"},
                               "radii": [1] * 24}])
        self.assertEqual(tube.exception.pointer, "/edits/0/radii")
        self.assertEqual(self.client.scene()["version"], version)


if __name__ == "__main__":
    unittest.main()

"""Local mesh edits through the Python client against a real strata-server: numpy arrays packed
by strata_client.mesh_edits reach the mesh (vertex lists and runs of triangles), a local
topology edit on a big mesh rebuilds a few of its clusters, a bad run is refused with the
member's pointer and changes nothing, and one undo puts the triangles back."""

import unittest

import numpy

from strata_client import UnprocessableError, mesh_edits
from test_client import ServerTestCase

N = 256  # quads per side: 131,072 triangles, numbered row by row, big enough to cluster


def other_diagonal(z: int) -> numpy.ndarray:
    """Row z of the plane's quads, each cut along its other diagonal: (512, 3) uint32."""
    x = numpy.arange(N, dtype=numpy.uint32)
    a = numpy.uint32(z * (N + 1)) + x
    b, c = a + 1, a + (N + 1)
    d = c + 1
    return numpy.stack([numpy.stack([a, c, d], 1), numpy.stack([a, d, b], 1)], 1).reshape(-1, 3)


class MeshEditsTest(ServerTestCase):

    def setUp(self):
        self.client.edit([{"op": "clear"},
                          {"op": "add_mesh", "id": "g",
                           "shape": {"type": "plane", "size": 20, "subdivisions": [N, N]}},
                          {"op": "add_instance", "id": "i", "mesh": "g"}])
        self.client.commit()

    def triangles(self) -> int:
        return self.client.scene("meshes", "g")["triangles"]

    def test_a_local_topology_edit_rebuilds_only_a_few_clusters(self):
        self.client.edit([mesh_edits.replace_triangles("g", 512 * 10, 512, other_diagonal(10))])
        first = self.client.commit()
        self.assertEqual([(e.mesh, e.reason) for e in first.rebuilt], [("g", "clustered")])
        clusters = first.rebuilt[0].clusters
        self.assertGreater(clusters, 100)

        self.client.edit([mesh_edits.replace_triangles("g", 512 * 200, 512, other_diagonal(200))])
        plan = self.client.plan()
        report = self.client.commit()
        for r in (plan, report):
            self.assertEqual(r.rebuilt, [])
            self.assertEqual([(e.mesh, e.reason) for e in r.refit], [("g", "triangles_replaced")])
            self.assertGreaterEqual(r.refit[0].clusters_rebuilt, 1)
            self.assertLess(r.refit[0].clusters_rebuilt, clusters // 4)
        self.assertEqual(report.blas_rebuilds, 0)
        self.assertIn("512 triangles replaced by 512", report.refit[0].detail)

    def test_vertex_lists_and_holes_reach_the_mesh_and_undo_brings_the_triangles_back(self):
        ids = numpy.arange(5 * (N + 1), 6 * (N + 1), dtype=numpy.uint32)
        lifted = numpy.zeros((len(ids), 3), numpy.float32)
        lifted[:, 1] = 0.5
        self.client.edit([mesh_edits.update_vertices("g", ids, lifted)])
        self.client.commit()

        self.client.edit([mesh_edits.replace_triangles("g", 0, 512 * 3, [])])
        self.assertEqual(self.triangles(), 2 * N * N - 512 * 3)
        self.client.commit()
        self.client.undo()
        self.assertEqual(self.triangles(), 2 * N * N)
        self.client.commit()

    def test_a_bad_run_is_refused_with_its_pointer_and_changes_nothing(self):
        version = self.client.scene()["version"]
        with self.assertRaises(UnprocessableError) as refused:
            self.client.edit([mesh_edits.replace_triangles("g", 10, 1, [[0, 1, 2]]),
                              mesh_edits.replace_triangles("g", 0, 1, [[0, 1, 10 ** 6]])])
        self.assertEqual(refused.exception.pointer, "/edits/1/indices_b64")
        self.assertIn("uses vertex 1000000", refused.exception.detail)
        with self.assertRaises(UnprocessableError) as past:
            self.client.edit([{"op": "replace_triangles", "mesh": "g", "first": 2 * N * N + 1,
                               "count": 0, "indices": []}])
        self.assertEqual(past.exception.pointer, "/edits/0/first")
        self.assertEqual(self.client.scene()["version"], version)
        self.assertEqual(self.triangles(), 2 * N * N)

    def test_the_packers_take_rows_flat_numbers_and_numpy_alike(self):
        rows = mesh_edits.pack_indices([[0, 1, 2], [2, 1, 3]])
        self.assertEqual(rows, mesh_edits.pack_indices([0, 1, 2, 2, 1, 3]))
        self.assertEqual(rows, mesh_edits.pack_indices(numpy.array([[0, 1, 2], [2, 1, 3]])))
        with self.assertRaises(ValueError):
            mesh_edits.pack_indices([[0, 1]])
        with self.assertRaises(ValueError):
            mesh_edits.pack_positions(numpy.zeros(4))


if __name__ == "__main__":
    unittest.main()

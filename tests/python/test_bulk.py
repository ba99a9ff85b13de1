"""Bulk instance ops through the Python client against a real strata-server: numpy transforms
packed by strata_client.bulk land where they should, a bulk move and hide cost one TLAS update
with no BLAS work, a refused item is named (its index, its id, the member's pointer) and changes
nothing, and one undo takes a whole bulk add back."""

import unittest

import numpy

from strata_client import Client, TooLargeError, UnprocessableError, bulk
from strata_process import ServerProcess
from test_client import SERVER, ServerTestCase

N = 20_000


def grid(n: int, y: float = 0.0) -> numpy.ndarray:
    """n transforms (n, 3, 4): identity rotations on a 200-wide grid at height y."""
    xs = numpy.zeros((n, 3, 4), numpy.float32)
    xs[:, 0, 0] = xs[:, 1, 1] = xs[:, 2, 2] = 1
    i = numpy.arange(n)
    xs[:, 0, 3] = i % 200
    xs[:, 1, 3] = y
    xs[:, 2, 3] = i // 200
    return xs


class BulkInstancesTest(ServerTestCase):

    def setUp(self):
        self.client.edit([{"op": "clear"},
                          {"op": "add_mesh", "id": "rock", "shape": {"type": "box", "size": 0.4}},
                          {"op": "add_material", "id": "red"}])
        self.client.commit()

    def count(self) -> int:
        return self.client.scene()["counts"]["instances"]

    def transform(self, instance: str):
        """Its transform, 4x4 row-major."""
        return self.client.scene("instances", instance)["transform"]

    def test_numpy_transforms_land_where_they_should(self):
        self.client.edit([bulk.add_instances(bulk.id_range("r", N), "rock",
                                             transforms=grid(N), material="red")])
        self.assertEqual(self.count(), N)
        self.assertEqual(self.transform("r4321")[:12], [1, 0, 0, 4321 % 200, 0, 1, 0, 0,
                                                   0, 0, 1, 4321 // 200])
        report = self.client.commit()
        self.assertEqual(report.tlas.instances, N)
        self.assertEqual(report.blas_rebuilds, 0)  # the mesh was built by setUp's commit

        # 4x4 matrices (a homogeneous last row) and ids as a list.
        moved = numpy.tile(numpy.eye(4, dtype=numpy.float64), (3, 1, 1))
        moved[:, 1, 3] = [5, 6, 7]
        self.client.edit([bulk.update_instances(["r1", "r2", "r3"], transforms=moved),
                          bulk.update_instances(bulk.id_range("r", 100, first=1000),
                                                visible=False)])
        self.assertEqual(self.transform("r3")[7], 7)
        self.assertFalse(self.client.scene("instances", "r1050")["visible"])
        report = self.client.commit()
        self.assertEqual(report.tlas.action, "update")
        self.assertEqual(report.instances_changed, 103)
        self.assertEqual(report.blas_rebuilds, 0)
        self.assertEqual(report.blas_refits, 0)

        # What the instances cost: the scene's share grows with them, and per_instance is it
        # plus the TLAS, per instance.
        memory = self.client.stats()["memory_bytes"]
        self.assertGreater(memory["instances"], N * 200)
        self.assertEqual(memory["per_instance"], (memory["instances"] + memory["tlas"]) // N)

        self.client.edit([bulk.remove_instances(bulk.id_range("r", N // 2))])
        self.assertEqual(self.count(), N - N // 2)
        self.client.edit([bulk.remove_instances(bulk.id_range("r", N - N // 2, first=N // 2))])
        self.assertIsNone(self.client.stats()["memory_bytes"]["per_instance"])

    def test_rows_and_arrays_pack_the_same(self):
        xs = grid(3, y=2.5)
        rows = [list(x.reshape(12)) for x in xs]
        self.assertEqual(bulk.pack_transforms(rows), bulk.pack_transforms(xs))
        self.assertEqual(bulk.pack_transforms(xs.reshape(3, 12)), bulk.pack_transforms(xs))
        with self.assertRaises(ValueError):
            bulk.pack_transforms(numpy.zeros((3, 2, 2)))
        with self.assertRaises(ValueError):
            bulk.pack_transforms([[1, 2, 3]])

    def test_a_refused_item_is_named_and_changes_nothing(self):
        self.client.edit([bulk.add_instances(["a", "b"], "rock")])
        version = self.client.scene()["version"]
        xs = grid(4)
        xs[2, 0, 0] = numpy.nan
        with self.assertRaises(UnprocessableError) as caught:
            self.client.edit([bulk.add_instances(bulk.id_range("n", 4), "rock", transforms=xs)])
        problem = caught.exception
        self.assertEqual(problem.pointer, "/edits/0/transforms_b64")
        self.assertIn("item 2 ('n2')", problem.detail)
        with self.assertRaises(UnprocessableError) as caught:
            self.client.edit([bulk.add_instances(["c", "d", "b"], "rock")])
        self.assertEqual(caught.exception.pointer, "/edits/0/ids/2")
        self.assertIn("'b' already exists", caught.exception.detail)
        with self.assertRaises(UnprocessableError) as caught:
            self.client.edit([bulk.add_instances(["e", "f"], ["rock", "stone"])])
        self.assertEqual(caught.exception.pointer, "/edits/0/mesh/1")
        self.assertEqual(self.client.scene()["version"], version)
        self.assertEqual(self.count(), 2)

    def test_a_range_past_the_instance_budget_is_refused_before_anything_is_built(self):
        with ServerProcess(SERVER, ["--max-scene-instances", "1000"]) as small, \
                Client(small.url) as client:
            client.edit([{"op": "add_mesh", "id": "rock", "shape": {"type": "box"}}])
            with self.assertRaises(TooLargeError) as caught:
                client.edit([bulk.add_instances(bulk.id_range("r", 16_777_216), "rock")])
            self.assertEqual(caught.exception.pointer, "/edits/0/ids")
            self.assertIn("max_scene_instances", caught.exception.detail)
            client.edit([bulk.add_instances(bulk.id_range("r", 1000), "rock")])
            self.assertEqual(client.scene()["counts"]["instances"], 1000)

    def test_one_undo_takes_a_bulk_add_back(self):
        self.client.edit([bulk.add_instances(bulk.id_range("u", 5000), "rock",
                                             transforms=grid(5000))])
        self.assertEqual(self.count(), 5000)
        self.client.undo()
        self.assertEqual(self.count(), 0)
        self.client.redo()
        self.assertEqual(self.count(), 5000)
        self.assertEqual(self.transform("u201")[3], 1)


if __name__ == "__main__":
    unittest.main()

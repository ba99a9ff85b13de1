"""Keyframe animation through the Python client against a real strata-server: set_time moves an
animated instance to where its keyframes say (what picks see), a step costs one TLAS update of
the animated instances alone, a render's or a pick's own `time` leaves the scene alone, a loop
wraps, the clock is part of the scene document and undo, and bad keyframes are refused with
their pointer and change nothing."""

import os
import unittest

from strata_client import UnprocessableError, animation
from test_client import ServerTestCase

ANIMATED_GLTF = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "fuzz",
                             "asset_corpus", "gltf", "animated-nodes.gltf")

# The pick camera looks down -z at x = 0: the ball is under the centre pixel only where x = 0.
CAMERA = {"eye": [0, 0, 10], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 20}


class AnimationTest(ServerTestCase):

    def setUp(self):
        keys = animation.keyframes([0, 2], [{"translate": [-4, 0, 0]}, {"translate": [4, 0, 0]}])
        statics = [{"op": "add_instance", "id": f"s{i}", "mesh": "ball",
                    "transform": {"translate": [i, 5, -20]}} for i in range(20)]
        self.client.edit([{"op": "clear"},
                          {"op": "add_mesh", "id": "ball", "shape": {"type": "sphere"}},
                          {"op": "add_instance", "id": "b", "mesh": "ball"},
                          animation.animate("b", keys, interpolation="linear"),
                          animation.set_time(0), *statics])
        self.client.commit()

    def centre(self, **opts):
        return self.client.pick(50, 50, 101, 101, camera=CAMERA, **opts)

    def test_set_time_moves_the_animated_instance_and_costs_it_alone(self):
        self.assertIsNone(self.centre())  # at x = -4
        self.client.edit([animation.set_time(1.0)])  # halfway: x = 0
        report = self.client.commit()
        self.assertEqual((report.tlas.action, report.instances_changed, report.blas_rebuilds,
                          report.blas_refits), ("update", 1, 0, 0))
        hit = self.centre()
        self.assertEqual(hit.instance if hit else None, "b")
        self.assertAlmostEqual(hit.distance, 9.0, places=2)
        timeline = self.client.scene()["timeline"]
        self.assertEqual(timeline["time"], 1.0)
        self.assertAlmostEqual(timeline["frame_duration"], 1 / 24, places=6)
        self.assertEqual(len(self.client.scene("instances", "b")["animation"]), 2)

    def test_a_launch_time_leaves_the_scene_alone(self):
        version = self.client.scene()["version"]
        hit = self.centre(time=1.0)
        self.assertEqual(hit.instance if hit else None, "b")
        at_one = self.client.render(64, 48, time=1.0)
        self.assertIsNone(self.centre())  # the scene is still at time 0
        self.assertEqual(self.client.scene()["version"], version)
        self.assertEqual(self.client.scene()["timeline"]["time"], 0)
        self.client.edit([animation.set_time(1.0)])
        self.assertEqual(self.client.render(64, 48), at_one)

    def test_loops_wrap_and_undo_takes_the_clock_back(self):
        keys = animation.keyframes([0, 1], [{"translate": [0, 0, 0]}, {"translate": [3, 0, 0]}])
        self.client.edit([animation.animate("b", keys, loop=True, interpolation=None)])
        self.client.edit([animation.set_time(7.0)])  # 7 s wraps to 0 s: x = 0
        self.assertEqual(self.client.scene("instances", "b")["animation_loop"], True)
        hit = self.centre()
        self.assertEqual(hit.instance if hit else None, "b")
        self.client.undo()
        self.assertEqual(self.client.scene()["timeline"]["time"], 0)

    def test_spin_turns_about_its_axis(self):
        keys = animation.spin(period=2.0, axis=[0, 0, 1], keys_per_turn=4)
        self.assertEqual(len(keys), 5)
        self.client.edit([{"op": "add_mesh", "id": "bar",
                           "shape": {"type": "box", "size": [4, 0.3, 0.3]}},
                          {"op": "add_instance", "id": "bar", "mesh": "bar"},
                          animation.animate("bar", keys, loop=True),
                          {"op": "update_instance", "instance": "b", "visible": False}])
        # A quarter turn in (0.5 s), the bar stands upright: a ray at y = 1.5 meets it.
        upright = dict(CAMERA, eye=[0, 1.5, 10], target=[0, 1.5, 0])
        self.assertIsNone(self.client.pick(50, 50, 101, 101, camera=upright))
        hit = self.client.pick(50, 50, 101, 101, camera=upright, time=0.5)
        self.assertEqual(hit.instance if hit else None, "bar")
        hit = self.client.pick(50, 50, 101, 101, camera=upright, time=2.5)  # looped
        self.assertEqual(hit.instance if hit else None, "bar")

    def test_an_animated_group_carries_its_instances(self):
        keys = animation.keyframes([0, 2], [{"translate": [0, -4, 0]}, {"translate": [0, 4, 0]}])
        self.client.edit([{"op": "add_group", "id": "lift"},
                          {"op": "add_instance", "id": "rider", "mesh": "ball", "parent": "lift",
                           "transform": {"translate": [3, 0, 0]}},
                          animation.animate_group("lift", keys, interpolation="linear"),
                          animation.animate("b", [])])  # b still: the step moves the rider only
        aimed = dict(CAMERA, eye=[3, 0, 10], target=[3, 0, 0])
        self.assertIsNone(self.client.pick(50, 50, 101, 101, camera=aimed))  # y = -4 at 0 s
        self.client.edit([animation.set_time(1.0)])
        report = self.client.commit()
        self.assertEqual((report.tlas.action, report.instances_changed), ("update", 1))
        hit = self.client.pick(50, 50, 101, 101, camera=aimed)
        self.assertEqual(hit.instance if hit else None, "rider")
        self.assertEqual(len(self.client.scene("groups", "lift")["animation"]), 2)

    def test_a_gltf_animation_is_imported_as_keyframes_the_clock_plays(self):
        # Node 0 (a group) steps its scale to 3 at 1 s; node 1 below it slides and turns; node 2
        # (a root leaf) has a cubic-spline channel, whose tangents are dropped with a warning.
        answer = self.client.import_asset(ANIMATED_GLTF, prefix="anim")
        self.assertIn("animations[0].channels[3]: CUBICSPLINE tangents ignored (keys "
                      "interpolated linearly)", answer.warnings)
        group = self.client.scene("groups", "anim.group0")
        self.assertEqual((len(group["animation"]), group["motion_interpolation"]), (2, "srt"))
        leaf = self.client.scene("instances", "anim.node1")
        self.assertEqual([k["time"] for k in leaf["animation"]], [0, 1, 2])
        self.client.edit([animation.set_time(1.0)])
        report = self.client.commit()
        self.assertEqual(report.tlas.action, "update")
        # At 1 s: the group scaled 3 and lifted 5, the leaf at x = 1 turned 45 degrees, scaled 2.
        world = self.client.scene("instances", "anim.node1")["world_transform"]
        self.assertAlmostEqual(world[3], 3.0, places=4)  # x: 3 * 1
        self.assertAlmostEqual(world[7], 5.0, places=4)  # y: 5 + 3 * 0
        self.assertAlmostEqual(world[0], 3 * 2 * 0.7071068, places=4)

    def test_bad_keyframes_and_times_are_refused_with_their_pointer(self):
        version = self.client.scene()["version"]
        cases = [
            ([{"op": "update_instance", "instance": "b",
               "animation": [{"time": 1, "transform": {"translate": [0, 0, 0]}},
                             {"time": 0.5, "transform": {"translate": [1, 0, 0]}}]}],
             "/edits/0/animation/1/time"),
            ([{"op": "update_instance", "instance": "b",
               "motion": [{"translate": [0, 0, 0]}, {"translate": [1, 0, 0]}]}],
             "/edits/0/animation"),
            ([{"op": "set_time", "frame_duration": -1}], "/edits/0/frame_duration"),
            ([{"op": "set_time", "time": 1e9}], "/edits/0/time"),
        ]
        for edits, pointer in cases:
            with self.assertRaises(UnprocessableError, msg=pointer) as refused:
                self.client.edit(edits)
            self.assertEqual(refused.exception.pointer, pointer)
        with self.assertRaises(UnprocessableError) as render:
            self.client.render(16, 16, time=1e9)
        self.assertEqual(render.exception.pointer, "/time")
        self.assertEqual(self.client.scene()["version"], version)


if __name__ == "__main__":
    unittest.main()

"""Named scenes through the Python client against a real strata-server: scenes(),
create_scene(), delete_scene(), Client(scene=...) and for_scene(), sync and asyncio; their data
directories surviving a SIGKILL; and deleting a scene giving its memory back (measured from the
process's resident set)."""

import asyncio
import os
import shutil
import tempfile
import unittest
import urllib.request

from strata_client import (AsyncClient, Client, ForbiddenError, NotFoundError, SceneBudget,
                           SceneConflictError, SceneSummary, TooLargeError, UnauthorizedError,
                           UnprocessableError)
from strata_process import ServerProcess
from test_client import SERVER

BALL = [
    {"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 16}},
    {"op": "add_instance", "id": "b0", "mesh": "ball"},
]


def resident_bytes(pid: int) -> int:
    """The process's resident set (VmRSS), in bytes."""
    with open(f"/proc/{pid}/status", encoding="ascii") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise AssertionError("no VmRSS in /proc/PID/status")


def metric(server: ServerProcess, name: str) -> float:
    """One unlabelled sample of GET /metrics."""
    with urllib.request.urlopen(server.url + "/metrics") as answer:
        for line in answer.read().decode().splitlines():
            if line.startswith(name + " "):
                return float(line.split()[1])
    raise AssertionError(f"{name} is not exported")


class ScenesTest(unittest.TestCase):

    def setUp(self):
        self.server = ServerProcess(SERVER, ["--max-scenes", "3"])
        self.client = Client(self.server.url)

    def tearDown(self):
        self.client.close()
        self.server.stop()

    def test_a_named_scene_is_a_scene_of_its_own(self):
        made = self.client.create_scene("city", max_instances=5)
        self.assertIsInstance(made, SceneSummary)
        self.assertEqual((made.name, made.version, made.instances, made.durable),
                         ("city", 0, 0, False))
        self.assertIsInstance(made.budget, SceneBudget)
        self.assertEqual(made.budget.max_instances, 5)
        with self.client.for_scene("city") as city:
            self.assertEqual(city.edit(BALL, message="first"), 1)
            city.edit([{"op": "set_transform", "instance": "b0",
                        "transform": {"translate": [0, 1, 0]}}])
            self.assertEqual([i["id"] for i in city.instances()], ["b0"])
            self.assertEqual(city.undo().target, 2)
            self.assertEqual(city.history().entries[-1].message, "first")
            frame = city.render_frame(32, 32)
            self.assertEqual(frame.info.version, 3)
            with self.assertRaises(TooLargeError):
                city.edit([{"op": "add_instances", "mesh": "ball",
                            "ids": {"prefix": "x", "first": 0, "count": 5}}])
        # The default scene saw none of it.
        self.assertEqual(self.client.scene()["version"], 0)
        self.assertEqual(list(self.client.instances()), [])
        self.assertEqual([s.name for s in self.client.scenes()], ["default", "city"])
        self.assertEqual(self.client.scene_summary("city").instances, 1)

    def test_the_directory_refuses_what_it_cannot_do(self):
        self.client.create_scene("a")
        self.assertEqual(self.client.create_scene("a").version, 0)  # found, not made again
        with self.assertRaises(SceneConflictError):
            self.client.create_scene("a", max_instances=1)
        with self.assertRaises(SceneConflictError):
            self.client.delete_scene("default")
        with self.assertRaises(UnprocessableError):
            self.client.create_scene("b", max_triangles=1 << 40)
        with self.assertRaises(NotFoundError):
            self.client.delete_scene("nope")
        with self.assertRaises(NotFoundError), Client(self.server.url, scene="nope") as nope:
            nope.scene()
        with self.assertRaises(ValueError):
            Client(self.server.url, scene="Not A Name")
        self.client.create_scene("b")
        self.client.create_scene("c")
        with self.assertRaises(TooLargeError):  # --max-scenes 3
            self.client.create_scene("d")
        self.client.delete_scene("c")
        with self.assertRaises(NotFoundError), self.client.for_scene("c") as gone:
            gone.scene()
        self.assertEqual([s.name for s in self.client.scenes()], ["default", "a", "b"])

    def test_the_async_client_works_on_named_scenes_too(self):
        async def run():
            async with AsyncClient(self.server.url) as strata:
                await strata.create_scene("async")
                async with strata.for_scene("async") as scene:
                    self.assertEqual(await scene.edit(BALL), 1)
                    self.assertEqual((await scene.scene())["version"], 1)
                self.assertEqual([s.name for s in await strata.scenes()], ["default", "async"])
                self.assertEqual((await strata.scene_summary("async")).meshes, 1)
                await strata.delete_scene("async")
                self.assertEqual((await strata.scene())["version"], 0)
        asyncio.run(run())


class DurableScenesTest(unittest.TestCase):

    def setUp(self):
        self.data = tempfile.mkdtemp(prefix="strata-scenes-")

    def tearDown(self):
        shutil.rmtree(self.data, ignore_errors=True)

    def start(self) -> ServerProcess:
        return ServerProcess(SERVER, ["--data", self.data])

    def test_named_scenes_survive_a_kill_and_deleted_ones_stay_deleted(self):
        server = self.start()
        try:
            with Client(server.url) as strata:
                strata.create_scene("kept", max_instances=10)
                strata.create_scene("dropped")
                with strata.for_scene("kept") as kept:
                    kept.edit(BALL)
                    kept.edit([{"op": "add_instance", "id": "b1", "mesh": "ball"}])
                with strata.for_scene("dropped") as dropped:
                    dropped.edit(BALL)
                with strata.for_scene("kept") as kept:
                    before = kept.render_frame(48, 32).image
                self.assertTrue(strata.scene_summary("kept").durable)
        finally:
            server.kill()
        server = self.start()
        try:
            with Client(server.url) as strata:
                names = [s.name for s in strata.scenes()]
                self.assertEqual(names, ["default", "dropped", "kept"])
                kept = strata.scene_summary("kept")
                self.assertEqual((kept.version, kept.instances, kept.budget.max_instances),
                                 (2, 2, 10))
                with strata.for_scene("kept") as kept_scene:
                    self.assertEqual(kept_scene.render_frame(48, 32).image, before)
                    # The undo history came back with the scene.
                    self.assertEqual(kept_scene.undo().target, 2)
                strata.delete_scene("dropped")
        finally:
            server.kill()
        server = self.start()
        try:
            with Client(server.url) as strata:
                self.assertEqual([s.name for s in strata.scenes()], ["default", "kept"])
                with self.assertRaises(NotFoundError):
                    strata.scene_summary("dropped")
                self.assertEqual(strata.create_scene("dropped").version, 0)
        finally:
            server.stop()

    def test_leftovers_of_an_interrupted_creation_or_deletion_are_removed_at_start(self):
        scenes = os.path.join(self.data, "scenes")
        for name in (".new-a-1", ".deleted-b-2", "Not-A-Scene"):
            os.makedirs(os.path.join(scenes, name))
        server = self.start()
        try:
            with Client(server.url) as strata:
                self.assertEqual([s.name for s in strata.scenes()], ["default"])
            self.assertIn("Not-A-Scene: not a scene", server.log())
        finally:
            server.stop()
        self.assertEqual(sorted(os.listdir(scenes)), ["Not-A-Scene"])

    def test_a_damaged_scene_file_stops_the_server_naming_it(self):
        settings = os.path.join(self.data, "scenes", "city", "scene.json")
        os.makedirs(os.path.dirname(settings))
        with open(settings, "w", encoding="utf-8") as f:
            f.write('{"budget": {"max_instances": "many"}}')
        with self.assertRaises(RuntimeError) as failed:
            self.start()
        self.assertIn("scene 'city'", str(failed.exception))
        self.assertIn("scene.json", str(failed.exception))


class SceneAccessTest(unittest.TestCase):
    """--tokens-file through the client: roles per scene, typed refusals, hidden scenes."""

    def setUp(self):
        self.tokens = tempfile.NamedTemporaryFile("w", suffix=".tokens", delete=False)
        self.tokens.write("# test tokens\nt-admin *:admin\nt-city city:edit\nt-look *:read\n")
        self.tokens.close()
        self.server = ServerProcess(SERVER, ["--tokens-file", self.tokens.name])

    def tearDown(self):
        self.server.stop()
        os.unlink(self.tokens.name)

    def test_each_token_does_what_its_roles_allow(self):
        with Client(self.server.url, token="t-admin") as admin:
            admin.create_scene("city")
            admin.create_scene("park")
        with Client(self.server.url, token="t-city", scene="city") as city:
            self.assertEqual(city.edit(BALL), 1)
            self.assertEqual([s.name for s in city.scenes()], ["city"])
            with self.assertRaises(ForbiddenError):
                city.create_scene("city2")
            with self.assertRaises(ForbiddenError), city.for_scene(None) as default:
                default.scene()  # no role in the default scene
            with self.assertRaises(NotFoundError), city.for_scene("park") as park:
                park.scene()  # as if it did not exist
        with Client(self.server.url, token="t-look", scene="city") as look:
            self.assertEqual(look.scene()["version"], 1)
            self.assertEqual(look.render_frame(16, 16).info.version, 1)
            with self.assertRaises(ForbiddenError):
                look.edit(BALL)
            with self.assertRaises(ForbiddenError):
                look.delete_scene("city")
        with self.assertRaises(UnauthorizedError), Client(self.server.url, token="nope") as nope:
            nope.scenes()


class SceneMemoryTest(unittest.TestCase):

    def test_deleting_a_scene_gives_its_memory_back(self):
        server = ServerProcess(SERVER)
        try:
            with Client(server.url) as strata:
                strata.create_scene("warm")  # what the first scene's code and threads cost
                strata.delete_scene("warm")
                base = resident_bytes(server.process.pid)
                strata.create_scene("big")
                big = strata.for_scene("big")
                big.edit([{"op": "add_mesh", "id": f"m{k}",
                           "shape": {"type": "sphere", "segments": 512}} for k in range(4)]
                         + [{"op": "add_instance", "id": f"i{k}", "mesh": f"m{k}"}
                            for k in range(4)])
                big.commit()
                loaded = resident_bytes(server.process.pid)
                big.close()
                strata.delete_scene("big")
                after = resident_bytes(server.process.pid)
            grown, kept = loaded - base, after - base
            print(f"\n  resident: {base >> 20} MiB before, {loaded >> 20} MiB with the scene "
                  f"(+{grown >> 20}), {after >> 20} MiB after deleting it (+{kept >> 20})")
            self.assertGreater(grown, 64 << 20)  # four 512-segment spheres and their BLASes
            self.assertLess(kept, grown // 4)
        finally:
            server.stop()

    def test_copies_of_one_city_share_its_blases_and_an_edit_copies_only_what_it_changes(self):
        def city(variant):
            # Two meshes; `variant` > 0 makes every scene's content its own.
            return [{"op": "add_mesh", "id": "tower",
                     "shape": {"type": "sphere", "segments": 384 + variant}},
                    {"op": "add_mesh", "id": "hall", "shape": {"type": "box"}},
                    {"op": "add_instance", "id": "t0", "mesh": "tower"},
                    {"op": "add_instance", "id": "h0", "mesh": "hall",
                     "transform": {"translate": [0, -1.5, 0]}}]

        def grow(server, strata, prefix, copies, variant):
            """Resident growth of `copies` scenes of the city; their summaries."""
            before = resident_bytes(server.process.pid)
            for k in range(copies):
                strata.create_scene(f"{prefix}{k}")
                with strata.for_scene(f"{prefix}{k}") as scene:
                    scene.edit(city(variant(k)))
                    scene.commit()
            grown = resident_bytes(server.process.pid) - before
            return grown, {s.name: s for s in strata.scenes() if s.name.startswith(prefix)}

        copies = 8
        server = ServerProcess(SERVER, ["--max-scenes", str(2 * copies + 1)])
        try:
            with Client(server.url) as strata:
                strata.create_scene("warm")  # what the first scene's code and threads cost
                strata.delete_scene("warm")
                shared, same = grow(server, strata, "same", copies, lambda k: 0)
                own, apart = grow(server, strata, "apart", copies, lambda k: k + 1)
                blas = [same[f"same{k}"].memory_bytes.blas for k in range(copies)]
                print(f"\n  {copies} scenes of one city: +{shared >> 20} MiB resident, BLAS bytes "
                      f"{blas[0] >> 10} KiB once; {copies} different cities: +{own >> 20} MiB, "
                      f"BLAS {sum(s.memory_bytes.blas for s in apart.values()) >> 10} KiB")
                self.assertGreater(blas[0], 1 << 20)
                self.assertEqual(blas[1:], [0] * (copies - 1), "counted once, by its builder")
                self.assertLess(shared, own * 0.6, "copies held what different cities hold")
                # The hall is one box in all sixteen scenes, the tower one sphere in the first
                # eight: 15 + 7 builds avoided.
                self.assertEqual(metric(server, "strata_shared_blas_holds"), 22)
                self.assertEqual(metric(server, "strata_shared_blas_count"), 1 + 1 + copies)
                # An edit to one scene's tower copies it for that scene alone.
                one, other = strata.for_scene("same3"), strata.for_scene("same4")
                before = other.render(64, 48, spp=1)
                self.assertEqual(one.render(64, 48, spp=1), before)
                # The tower's top rings pulled into a spike towards the camera (+z).
                one.edit([{"op": "update_mesh", "mesh": "tower", "offset": 0,
                           "positions": [0, 1.2, 2.5] * 2000}])
                report = one.commit()
                self.assertEqual([(e.mesh, e.reason) for e in report.rebuilt],
                                 [("tower", "unshared")])
                self.assertNotEqual(one.render(64, 48, spp=1), before)
                self.assertEqual(other.render(64, 48, spp=1), before)
                self.assertGreater(strata.scene_summary("same3").memory_bytes.blas, 1 << 20)
                self.assertEqual(metric(server, "strata_shared_blas_holds"), 21)
                one.close()
                other.close()
        finally:
            server.stop()


if __name__ == "__main__":
    unittest.main()

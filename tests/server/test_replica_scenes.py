"""Named scenes on replicas of one edit log (issue 26), with a real redis-server and real
strata-server processes: a scene made on one replica is served and edited on every replica,
each scene in its own Redis stream; a deletion reaches every replica and a scene made again
starts empty; a replica restarted on its data directory follows its scenes from where it was
and drops the one deleted meanwhile; a directory emptied by hand costs no replica its scenes.
Skipped, saying so, only where redis-server is not installed (scripts/install-deps.sh installs it).
"""

import json
import os
import shutil
import tempfile
import threading
import time
import unittest
import uuid

import durable_scene
from hostile import Server
from redis_fixture import REDIS_SERVER, RedisProcess

RENDER = "/v1/render?width=48&height=32&spp=1"
SCENE = "/v1/scenes/city"


def scoped(scene, path):
    """`path` (a /v1 path of the default scene) as scene `scene` serves it."""
    return f"/v1/scenes/{scene}/{path[len('/v1/'):]}"


def eventually(check, timeout=10.0):
    """Polls `check` until it returns something true, at most `timeout` seconds; its last value."""
    deadline = time.monotonic() + timeout
    while True:
        value = check()
        if value or time.monotonic() > deadline:
            return value
        time.sleep(0.05)


@unittest.skipIf(REDIS_SERVER is None,
                 "redis-server is not installed (scripts/install-deps.sh installs it)")
class ReplicaScenes(unittest.TestCase):
    def setUp(self):
        self.redis = RedisProcess()
        self.addCleanup(self.redis.stop)
        self.stream = "strata-" + uuid.uuid4().hex[:8]

    def replica(self, *extra):
        s = Server(["--log", self.redis.url(self.stream), "--threads", "4"] + list(extra))
        self.addCleanup(s.stop)
        return s

    def directory(self):
        """The log's scene directory: name -> (incarnation, settings)."""
        flat = self.redis.command("HGETALL", self.stream + ":scenes")
        pairs = dict(zip(flat[0::2], flat[1::2]))
        return {k.decode(): tuple(v.decode().split(" ", 1)) for k, v in pairs.items()}

    def edit(self, server, scene, n):
        status, answer = server.json("POST", scoped(scene, "/v1/edits"),
                                     durable_scene.batch(n))
        self.assertEqual(status, 200, answer)
        self.assertEqual(answer["version"], n + 1)

    def at(self, server, scene, version, path="/v1/scene"):
        sep = "&" if "?" in path else "?"
        return server.call("GET", f"{scoped(scene, path)}{sep}min_version={version}")

    def assert_converged(self, servers, scene, version):
        scenes, frames = [], []
        for s in servers:
            status, _, body = self.at(s, scene, version)
            self.assertEqual(status, 200, body)
            scenes.append(json.loads(body))
            status, _, frame = self.at(s, scene, version, RENDER)
            self.assertEqual(status, 200, frame[:300])
            frames.append(frame)
        for got in scenes:
            self.assertEqual(got["version"], version)
            self.assertEqual(got, scenes[0])
        self.assertEqual(frames[1:], frames[:1] * (len(frames) - 1), "frames differ")

    def test_a_scene_made_on_one_replica_is_served_and_edited_on_every_replica(self):
        a, b = self.replica(), self.replica()
        status, made = a.json("PUT", SCENE, {"budget": {"max_instances": 5000}})
        self.assertEqual(status, 201, made)
        # B holds it at once: a request naming it asks the log's directory.
        status, seen = b.json("GET", SCENE)
        self.assertEqual(status, 200, seen)
        self.assertEqual(seen["budget"], made["budget"])
        self.assertEqual(b.json("PUT", SCENE, {"budget": {"max_instances": 5000}})[0], 200)
        status, problem = b.json("PUT", SCENE, {"budget": {"max_instances": 10}})
        self.assertEqual(status, 409, problem)
        # Batches on either replica, each scene in its own stream: both replicas converge.
        servers = [a, b]
        for n in range(12):
            self.edit(servers[n % 2], "city", n)
        self.assert_converged(servers, "city", 12)
        self.assertEqual(durable_scene.check(_Scoped(b, "city"), 12), "")
        incarnation, _ = self.directory()["city"]
        self.assertEqual(self.redis.command("XLEN", f"{self.stream}:scene:city:{incarnation}"), 12)
        self.assertEqual(self.redis.command("XLEN", self.stream), 0)
        self.assertEqual(a.version(), 0)  # the default scene did not move
        # If-Match on the named scene is its own version, on every replica.
        stale = {"If-Match": '"3"'}
        status, _, _ = b.call("POST", scoped("city", "/v1/edits"), durable_scene.batch(12), stale)
        self.assertEqual(status, 412)
        # The follower lists it on a replica that never asked for it by name.
        c = self.replica()
        listed = eventually(lambda: [s["name"] for s in c.json("GET", "/v1/scenes")[1]["scenes"]])
        self.assertIn("city", listed)
        self.assert_converged([a, b, c], "city", 12)

    def test_two_replicas_making_one_name_at_once_agree_on_one_scene(self):
        a, b = self.replica(), self.replica()
        for round in range(5):
            name = f"race{round}"
            answers = {}
            threads = [threading.Thread(target=lambda s=s, k=k: answers.__setitem__(
                k, s.json("PUT", f"/v1/scenes/{name}")[0])) for k, s in (("a", a), ("b", b))]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            self.assertEqual(sorted(answers.values()), [200, 201], answers)
            self.edit(b if answers["a"] == 201 else a, name, 0)
            self.assert_converged([a, b], name, 1)
        self.assertEqual(sorted(self.directory()), [f"race{n}" for n in range(5)])

    def test_a_deleted_scene_goes_from_every_replica_and_a_new_one_starts_empty(self):
        a, b = self.replica(), self.replica()
        self.assertEqual(a.json("PUT", SCENE)[0], 201)
        for n in range(3):
            self.edit(b, "city", n)
        incarnation, _ = self.directory()["city"]
        self.assertEqual(self.at(a, "city", 3)[0], 200)
        self.assertEqual(b.call("DELETE", SCENE)[0], 204)
        self.assertEqual(b.call("GET", SCENE)[0], 404)
        self.assertEqual(eventually(lambda: a.call("GET", SCENE)[0] == 404), True)
        self.assertNotIn("city", self.directory())
        self.assertEqual(self.redis.command("EXISTS", f"{self.stream}:scene:city:{incarnation}"),
                         0)
        self.assertIsNotNone(self.redis.command("ZSCORE", f"{self.stream}:scenes:deleted",
                                                f"city {incarnation}"))
        self.assertEqual(a.call("DELETE", SCENE)[0], 404)
        # Made again, it is a new incarnation: version 0 on both, whatever the old one held.
        self.assertEqual(a.json("PUT", SCENE)[0], 201)
        self.assertNotEqual(self.directory()["city"][0], incarnation)
        for s in (a, b):
            status, scene = s.json("GET", scoped("city", "/v1/scene"))
            self.assertEqual((status, scene["version"]), (200, 0))
        self.edit(a, "city", 0)
        self.assert_converged([a, b], "city", 1)
        # A deleted scene's replicas stop quietly: its log going is no failure of the log.
        for s in (a, b):
            self.assertNotIn("replica stopped", s.log())

    def test_a_replica_restarted_on_its_data_directory_follows_its_scenes(self):
        data = tempfile.mkdtemp(prefix="strata-replica-scenes-")
        self.addCleanup(shutil.rmtree, data, True)
        a, b = self.replica(), self.replica("--data", data)
        for name in ("keep", "gone"):
            self.assertEqual(a.json("PUT", f"/v1/scenes/{name}")[0], 201)
            for n in range(4):
                self.edit(a, name, n)
            status, _, body = self.at(b, name, 4)
            self.assertEqual(status, 200, body.decode() + b.log()[-3000:])
        b.kill()
        for n in range(4, 9):
            self.edit(a, "keep", n)
        self.assertEqual(a.call("DELETE", "/v1/scenes/gone")[0], 204)
        # Restarted, B recovers both from its directory, follows "keep" from version 4 and
        # drops "gone", whose tombstone says it was deleted.
        b = self.replica("--data", data)
        self.assert_converged([a, b], "keep", 9)
        self.assertEqual(durable_scene.check(_Scoped(b, "keep"), 9), "")
        self.assertEqual(eventually(lambda: b.call("GET", "/v1/scenes/gone")[0] == 404), True)
        self.assertTrue(eventually(
            lambda: not os.path.exists(os.path.join(data, "scenes", "gone"))))
        self.assertIn("scene 'gone' was deleted on another server", b.log())

    def test_a_directory_emptied_by_hand_costs_no_replica_its_scenes(self):
        a = self.replica()
        self.assertEqual(a.json("PUT", SCENE)[0], 201)
        self.edit(a, "city", 0)
        self.redis.command("DEL", self.stream + ":scenes")
        self.assertTrue(eventually(lambda: "without a tombstone" in a.log()))
        self.assertEqual(a.call("GET", scoped("city", "/v1/scene"))[0], 200)


class _Scoped:
    """A server seen through one named scene's paths, for durable_scene.check."""

    def __init__(self, server, scene):
        self.server, self.scene = server, scene

    def json(self, method, path, body=None):
        return self.server.json(method, scoped(self.scene, path), body)


if __name__ == "__main__":
    unittest.main()

"""The strata command line as a user runs it: exit codes, the per-step table, the diff of a
failed expectation, problem details instead of raw JSON, frames, tokens, and the README snippets."""

import json
import os
import re
import subprocess
import sys
import tempfile
import unittest

from strata_process import ServerProcess

SERVER = os.environ.get("STRATA_SERVER_BINARY", "build/server/strata-server")
STRATA = os.environ.get("STRATA_CLI_BINARY", "build/clients/cli/strata")
SOURCE = os.environ.get("STRATA_SOURCE_DIR", ".")

SETUP = ('{"edits": [{"op": "clear"}, {"op": "add_mesh", "id": "ball", "shape": {"type": '
         '"sphere", "segments": 16}}, {"op": "add_instance", "id": "b0", "mesh": "ball"}]}\n')


def untimed(line):
    """A line of printed output with its wall times ("0.433" ms, "(0.65 s)", "ms=9.6") blanked and
    its spaces collapsed, so that everything else can be compared exactly."""
    line = re.sub(r"\(\d+\.\d+ s\)", "(* s)", line)
    line = re.sub(r"\bms=[0-9.]+", "ms=*", line)
    return " ".join(re.sub(r"\b\d+\.\d{3}\b", "*", line).split())


def assert_printed(test, printed, output):
    """Every line of a README's printed block (`...` stands for lines left out) appears in
    `output`, in order, up to wall times."""
    lines = [untimed(l) for l in output.splitlines()]
    at = 0
    for want in printed.strip().splitlines():
        if want.strip() == "...":
            continue
        want = untimed(want)
        test.assertIn(want, lines[at:], f"printed in the README but not by the run:\n{output}")
        at = lines.index(want, at) + 1


def strata(*args, env=None, stdin=None, cwd=None):
    """Runs strata; returns (exit code, stdout, stderr)."""
    full_env = dict(os.environ)
    full_env.pop("STRATA_TOKEN", None)
    full_env.update(env or {})
    p = subprocess.run([STRATA, *args], capture_output=True, text=True, env=full_env,
                       input=stdin, cwd=cwd, timeout=120)
    return p.returncode, p.stdout, p.stderr


class PlayTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()

    def tearDown(self):
        self.dir.cleanup()

    def script(self, text):
        path = os.path.join(self.dir.name, "script.jsonl")
        with open(path, "w") as f:
            f.write(text)
        return path

    def test_a_passing_script_prints_a_table_writes_frames_and_exits_0(self):
        path = self.script(
            SETUP
            + '{"commit": {}, "expect": {"tlas": "update", "rebuilt": {"ball": "added"}}}\n'
            + '{"repeat": 3, "steps": [{"edits": [{"op": "set_camera", "eye": ["{n}", 1, 5]}]},'
            + ' {"render": {"width": 16, "height": 8}, "out": "frames/f{n:2}.png",'
            + ' "expect": {"tlas": "none", "blas_rebuilds": 0}}]}\n')
        code, out, err = strata("play", "--embedded", path, cwd=self.dir.name)
        self.assertEqual(code, 0, out + err)
        self.assertIn("playing", out)
        self.assertIn(" step  line  kind", out)
        self.assertIn("frames/f02.png", out)
        self.assertIn("PASS  8 steps, 8 expectations met, 3 frames written", out)
        for n in range(3):
            with open(os.path.join(self.dir.name, "frames", f"f{n:02}.png"), "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")

    def test_a_failed_expectation_prints_a_diff_and_exits_1(self):
        path = self.script(
            SETUP
            + '{"commit": {}}\n'
            + '{"repeat": 2, "steps": [{"edits": [{"op": "mark_dirty", "target": {"mesh": "ball"},'
            + ' "action": "rebuild"}]}, {"commit": {}, "label": "asked",'
            + ' "expect": {"rebuilt": {"ball": "topology_changed"}, "blas_rebuilds": 0}}]}\n'
            + '{"commit": {}}\n')
        code, out, err = strata("play", "--embedded", path)
        self.assertEqual(code, 1, out + err)
        self.assertIn('FAIL  ' + path + ': step 4 (line 3, n=0) commit "asked"', out)
        self.assertIn("blas_rebuilds  0", out)
        self.assertIn("ball was rebuild_requested", out)
        code, out, _ = strata("--json", "play", "--embedded", path)
        self.assertEqual(code, 1)
        verdict = json.loads(out.strip().splitlines()[-1])
        self.assertEqual(verdict["result"], "fail")
        self.assertEqual(verdict["failure"]["line"], 3)

    def test_a_bad_script_names_its_line_and_exits_2(self):
        for text, message in (
                (SETUP + '{"commit": {}, "expect": {"blas_rebuild": 0}}\n',
                 'line 2: unknown member "blas_rebuild" in "expect"'),
                (SETUP + '{"comit": {}}\n', "line 2: unknown step"),
                ('{"edits": [\n', "line 1: not JSON"),
                ('# comment\n{"repeat": 2, "steps": [{"edits": [{"op": "clear", "x": "{n +}"}]}]}\n',
                 "line 2: bad expression 'n +'")):
            code, out, err = strata("play", "--embedded", self.script(text))
            self.assertEqual(code, 2, text + out + err)
            self.assertIn(message, err)
            self.assertEqual(out, "")
        code, _, err = strata("play", "--embedded", "/nonexistent.jsonl")
        self.assertEqual(code, 2)
        self.assertIn("cannot open script", err)

    def test_a_refused_step_shows_the_problem_and_exits_3(self):
        path = self.script('{"edits": [{"op": "add_instance", "id": "x", "mesh": "rock"}]}\n')
        code, out, err = strata("play", "--embedded", path)
        self.assertEqual(code, 3, out + err)
        self.assertIn("step 1 (line 1) edits: request failed: 422 Unknown id", err)
        self.assertIn("pointer:    /edits/0/mesh", err)
        self.assertNotIn('{"', err)

    def test_a_script_plays_from_standard_input(self):
        code, out, err = strata("play", "--embedded", "-q", "-", stdin=SETUP + '{"commit": {}}\n')
        self.assertEqual(code, 0, err)
        self.assertIn("PASS  2 steps", out)


class ServerCommandsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.token_file = tempfile.NamedTemporaryFile("w", suffix=".token", delete=False)
        cls.token_file.write("t0ken")
        cls.token_file.close()
        cls.server = ServerProcess(SERVER, ["--token-file", cls.token_file.name])
        cls.env = {"STRATA_SERVER": cls.server.url, "STRATA_TOKEN": "t0ken"}

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()
        os.unlink(cls.token_file.name)

    def test_every_subcommand_talks_to_the_server(self):
        code, out, err = strata("edit", "-", env=self.env, stdin=SETUP)
        self.assertEqual(code, 0, err)
        self.assertRegex(out, r"^v\d+: 3 edits applied\n$")
        code, out, _ = strata("plan", env=self.env)
        self.assertEqual(code, 0)
        self.assertIn("rebuilt   ball  added  224 prims", out)
        code, out, _ = strata("--json", "commit", env=self.env)
        self.assertEqual(code, 0)
        self.assertEqual(json.loads(out)["tlas"]["action"], "update")
        with tempfile.TemporaryDirectory() as d:
            png = os.path.join(d, "out.png")
            code, out, err = strata("render", "-o", png, "--width", "32", "--height", "16",
                                    "--eye", "0,2,6", "--fov", "50", env=self.env)
            self.assertEqual(code, 0, err)
            self.assertIn("wrote " + png, out)
            with open(png, "rb") as f:
                self.assertEqual(f.read(4), b"\x89PNG")
        code, out, _ = strata("stats", env=self.env)
        self.assertEqual(code, 0)
        self.assertIn("counters", out)
        code, out, _ = strata("--json", "scene", env=self.env)
        self.assertEqual(json.loads(out)["counts"]["instances"], 1)
        code, out, err = strata("--server", self.server.url, "--token", "t0ken", "play", "-q",
                                os.path.join(SOURCE, "tests/regression/noop_commit.jsonl"),
                                env={"STRATA_TOKEN": "wrong"})
        self.assertEqual(code, 0, out + err)

    def test_import_uploads_a_model_file(self):
        with tempfile.TemporaryDirectory() as d:
            obj = os.path.join(d, "tri.obj")
            with open(obj, "w") as f:
                f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
            code, out, err = strata("import", obj, "--prefix", "clitri", env=self.env)
            self.assertEqual(code, 0, err)
            self.assertRegex(out, r"^imported .*tri.obj: 1 meshes, 0 materials, 1 groups, "
                                  r"1 instances; "
                                  r"the scene is now version \d+\n$")
            code, out, err = strata("--json", "scene", "get", "instance", "clitri.node0",
                                    env=self.env)
            self.assertEqual(code, 0, err)
            self.assertEqual(json.loads(out)["mesh"], "clitri.mesh0")
            code, out, err = strata("import", obj, "--prefix", "clitri", env=self.env)
            self.assertEqual(code, 3)
            self.assertIn("422 Duplicate id", err)

    def test_import_packs_a_gltf_directory(self):
        gltf = os.path.join(os.environ.get("STRATA_ASSIMP_MODELS_DIR", "/usr/share/assimp/models"),
                            "glTF2", "BoxTextured-glTF", "BoxTextured.gltf")
        if not os.path.exists(gltf):
            self.skipTest(gltf + " missing")
        code, out, err = strata("--json", "import", gltf, "--prefix", "clibox", env=self.env)
        self.assertEqual(code, 0, err)
        answer = json.loads(out)
        self.assertEqual(answer["model"], "BoxTextured.gltf")
        self.assertEqual(answer["textures"], ["clibox.texture0"])
        code, out, err = strata("--json", "scene", "get", "texture", "clibox.texture0",
                                env=self.env)
        self.assertEqual(code, 0, err)
        self.assertEqual(json.loads(out)["format"], "png")

    def test_scene_list_get_and_pick_read_the_scene_object_by_object(self):
        edits = [{"op": "clear"},
                 {"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 16}},
                 {"op": "set_camera", "eye": [0, 0, 5], "target": [0, 0, 0]}]
        edits += [{"op": "add_instance", "id": f"/World/b{i}", "mesh": "ball",
                   "visible": i != 3, "transform": {"translate": [3 * i, 0, 0]}}
                  for i in range(7)]
        code, _, err = strata("edit", "-", env=self.env, stdin=json.dumps({"edits": edits}))
        self.assertEqual(code, 0, err)
        code, out, err = strata("scene", "list", "instances", "--page-size", "2", env=self.env)
        self.assertEqual(code, 0, err)
        # Slot order: slots freed by earlier tests' clears are reused, so compare as a set (each
        # instance exactly once).
        self.assertEqual(sorted(line.split()[0] for line in out.splitlines()),
                         [f"/World/b{i}" for i in range(7)])
        self.assertIn("/World/b3  mesh=ball  hidden", out)
        self.assertRegex(err, r"7 instances at version \d+")
        code, out, _ = strata("--json", "scene", "list", "instances", "--visible", "false",
                              env=self.env)
        self.assertEqual([json.loads(line)["id"] for line in out.splitlines()], ["/World/b3"])
        code, out, _ = strata("scene", "list", "instances", "--max", "3", env=self.env)
        self.assertEqual(len(out.splitlines()), 3)
        code, out, _ = strata("--json", "scene", "get", "instance", "/World/b2", env=self.env)
        self.assertEqual(code, 0)
        self.assertEqual(json.loads(out)["transform"][3], 6)
        code, _, err = strata("scene", "get", "instance", "nope", env=self.env)
        self.assertEqual(code, 3)
        self.assertIn("no instance with id 'nope'", err)
        code, out, err = strata("pick", "32", "32", "--width", "64", "--height", "64",
                                env=self.env)
        self.assertEqual(code, 0, err)
        self.assertRegex(out, r"^instance /World/b0  mesh ball  primitive \d+  distance 4")
        code, out, _ = strata("pick", "0", "0", "--width", "64", "--height", "64", env=self.env)
        self.assertIn("nothing at (0, 0)", out)
        code, _, err = strata("pick", "64", "0", "--width", "64", "--height", "64", env=self.env)
        self.assertEqual(code, 3)
        self.assertIn("/pixels/0", err)
        code, _, _ = strata("scene", "list", "cameras", env=self.env)
        self.assertEqual(code, 2)
        code, _, err = strata("edit", "-", env=self.env, stdin=json.dumps(
            {"edits": [{"op": "add_light", "id": "lamp", "type": "spot"}]}))
        self.assertEqual(code, 0, err)
        code, out, err = strata("scene", "list", "lights", env=self.env)
        self.assertEqual(code, 0, err)
        self.assertEqual(out, "lamp  type=spot\n")
        # A mesh with vertex keys says how many it has.
        code, _, err = strata("edit", "-", env=self.env, stdin=json.dumps({"edits": [
            {"op": "add_mesh", "id": "sheet", "positions": [0, 0, 0, 1, 0, 0, 0, 1, 0],
             "indices": [0, 1, 2], "motion_positions": [0, 0, 1, 1, 0, 1, 0, 1, 1]}]}))
        self.assertEqual(code, 0, err)
        code, out, err = strata("scene", "list", "meshes", env=self.env)
        self.assertEqual(code, 0, err)
        self.assertIn("sheet  vertices=3  triangles=1  instances=0  keys=2\n", out)
        self.assertIn("ball  vertices=", out)
        self.assertNotIn("keys=", out.split("ball", 1)[1].split("\n", 1)[0])
        code, out, err = strata("--json", "scene", "get", "light", "lamp", env=self.env)
        self.assertEqual(code, 0, err)
        self.assertEqual(json.loads(out)["type"], "spot")

    def test_scene_tree_groups_and_group_path(self):
        edits = [{"op": "clear"},
                 {"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 16}},
                 {"op": "set_camera", "eye": [0, 0, 5], "target": [0, 0, 0]},
                 {"op": "add_group", "id": "car"},
                 {"op": "add_group", "id": "wheels", "parent": "car", "visible": False},
                 {"op": "add_instance", "id": "body", "mesh": "ball", "parent": "car"},
                 {"op": "add_instance", "id": "w0", "mesh": "ball", "parent": "wheels"},
                 {"op": "add_instance", "id": "lamp", "mesh": "ball",
                  "transform": {"translate": [0, 9, 0]}}]
        code, _, err = strata("edit", "-", env=self.env, stdin=json.dumps({"edits": edits}))
        self.assertEqual(code, 0, err)
        code, out, err = strata("scene", "list", "groups", env=self.env)
        self.assertEqual(code, 0, err)
        self.assertEqual(out.splitlines(), ["car  groups=1  instances=1",
                                            "wheels  parent=car  groups=0  instances=1  hidden"])
        code, out, _ = strata("scene", "list", "instances", "--parent", "car", env=self.env)
        self.assertEqual(out.splitlines(), ["body  mesh=ball  parent=car"])
        code, out, _ = strata("scene", "list", "instances", "--parent", "", env=self.env)
        self.assertEqual([line.split()[0] for line in out.splitlines()], ["lamp"])
        code, out, _ = strata("--json", "scene", "get", "group", "wheels", env=self.env)
        self.assertEqual(code, 0)
        self.assertFalse(json.loads(out)["world_visible"])
        code, out, err = strata("scene", "tree", env=self.env)
        self.assertEqual(code, 0, err)
        self.assertEqual(out.splitlines(), ["car/  (1 groups, 1 instances)",
                                            "  wheels/  (0 groups, 1 instances, hidden)",
                                            "    w0  mesh=ball  hidden",
                                            "  body  mesh=ball",
                                            "lamp  mesh=ball"])
        code, out, err = strata("pick", "32", "32", "--width", "64", "--height", "64",
                                env=self.env)
        self.assertEqual(code, 0, err)
        self.assertRegex(out, r"^instance body  mesh ball  groups car  primitive \d+")

    def test_a_missing_token_is_a_401_problem(self):
        code, _, err = strata("stats", env={"STRATA_SERVER": self.server.url})
        self.assertEqual(code, 3)
        self.assertIn("401 Unauthorized", err)
        self.assertIn("detail:     this server requires Authorization: Bearer <token>", err)

    def test_an_unreachable_server_exits_3_saying_so(self):
        code, _, err = strata("--server", "http://127.0.0.1:1", "commit")
        self.assertEqual(code, 3)
        self.assertIn("could not connect (http://127.0.0.1:1)", err)

    def test_usage_errors_exit_2(self):
        self.assertEqual(strata("--server", "localhost:7070", "stats")[0], 2)
        self.assertEqual(strata("render")[0], 2)  # -o is required
        self.assertEqual(strata("play", "--demo", "x.jsonl")[0], 2)
        self.assertEqual(strata()[0], 2)


class ReadmeSnippetsTest(unittest.TestCase):
    """The client examples of the top-level README.md, as written there (with the test server's
    URL for 127.0.0.1:7070)."""

    def setUp(self):
        with open(os.path.join(SOURCE, "README.md")) as f:
            text = f.read()
        start = text.index("### Scripts and the `strata` command line")
        self.text = text[start:text.index("### Without a server", start)]
        self.server = ServerProcess(SERVER, ["--demo"])  # the server from README command (1)

    def tearDown(self):
        self.server.stop()

    def block(self, language):
        start = self.text.index("```" + language + "\n") + len(language) + 4
        return self.text[start:self.text.index("```", start)]

    def block_after(self, language):
        """The unlabelled block that follows the first ```language block (its printed output)."""
        start = self.text.index("```" + language + "\n")
        start = self.text.index("```\n", self.text.index("```\n", start) + 4) + 4
        return self.text[start:self.text.index("```", start)]

    def last_block(self):
        end = self.text.rindex("```")
        return self.text[self.text.rindex("```\n", 0, end) + 4:end]

    def test_the_cli_snippet_plays_embedded_and_on_the_server(self):
        commands = [line.split("#")[0].split() for line in self.block("sh").splitlines()]
        self.assertEqual(commands[0][:2], ["build/clients/cli/strata", "play"])
        self.assertIn("--embedded", commands[0])
        printed = self.block_after("sh")
        with open(os.path.join(SOURCE, "clients/cli/README.md")) as f:
            cli_readme = f.read()
        start = cli_readme.index("```\nplaying ") + 4
        cli_printed = cli_readme[start:cli_readme.index("```", start)]
        with tempfile.TemporaryDirectory() as d:
            before = self.server_scene()
            for args in commands:
                args = [os.path.join(SOURCE, a) if a.endswith(".jsonl") else a for a in args[1:]]
                code, out, err = strata(*args, env={"STRATA_SERVER": self.server.url}, cwd=d)
                self.assertEqual(code, 0, out + err)
                out = out.replace(os.path.join(SOURCE, ""), "")
                if "--embedded" in args:
                    assert_printed(self, printed, out)
                    assert_printed(self, cli_printed, out)
                else:  # the same steps and expectations on the demo scene
                    assert_printed(self, printed.strip().splitlines()[-1], out)
            self.assertTrue(os.path.exists(os.path.join(d, "frames/flag/frame_047.png")))
            # The example leaves the server's scene as it found it, camera and lighting included.
            self.assertEqual(self.server_scene(), before)

    def server_scene(self):
        """The server's scene summary (without its version) and the ids of its objects."""
        listings = []
        for collection in ("instances", "meshes", "materials", "groups"):
            code, out, err = strata("--server", self.server.url, "--json", "scene", "list",
                                    collection)
            self.assertEqual(code, 0, out + err)
            listings.append(sorted(json.loads(line)["id"] for line in out.splitlines()))
        code, out, err = strata("--server", self.server.url, "--json", "scene")
        self.assertEqual(code, 0, out + err)
        summary = json.loads(out)
        summary.pop("version")
        return summary, listings

    def test_the_python_snippet_prints_what_it_says(self):
        code = self.block("python").replace("http://127.0.0.1:7070", self.server.url)
        with tempfile.TemporaryDirectory() as d:
            p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                               cwd=d, timeout=120)
            self.assertEqual(p.returncode, 0, p.stderr)
            with open(os.path.join(d, "orb.png"), "rb") as f:
                self.assertEqual(f.read(4), b"\x89PNG")
        # On the fresh demo server of README command (1); the first render builds the demo scene.
        self.assertEqual([untimed(l) for l in p.stdout.splitlines()],
                         [untimed(l) for l in self.last_block().strip().splitlines()], p.stdout)


if __name__ == "__main__":
    unittest.main()

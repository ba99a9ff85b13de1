"""The viewer (clients/web) in headless Debian chromium against a real strata-server --demo:
a frame appears, another client's edit changes it within a second, a click selects the instance
under it, an edit made in the viewer reaches /v1/scene, and the token flow works. Screenshots go
to $STRATA_SCREENSHOT_DIR (build/browser-screenshots in CTest), kept as CI artifacts.
"""

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import unittest
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "python"))
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "clients", "python"))
from strata_process import ServerProcess  # noqa: E402
from strata_client.png import decode_png  # noqa: E402

from cdp import Browser, find_chromium  # noqa: E402

SERVER = os.environ.get("STRATA_SERVER_BINARY", "")
SHOTS = os.environ.get("STRATA_SCREENSHOT_DIR", os.path.join(os.getcwd(), "browser-screenshots"))

# Pixels of the frame, downsampled in the page (same origin: the canvas is not tainted).
SAMPLE = """(() => {
  const img = document.getElementById('frame');
  if (!img.complete || !img.naturalWidth) return null;
  const c = document.createElement('canvas'); c.width = 64; c.height = 36;
  const ctx = c.getContext('2d'); ctx.drawImage(img, 0, 0, 64, 36);
  return Array.from(ctx.getImageData(0, 0, 64, 36).data);
})()"""


def luminance(rgba):
    return [0.2126 * rgba[i] + 0.7152 * rgba[i + 1] + 0.0722 * rgba[i + 2]
            for i in range(0, len(rgba), 4)]


def mean_abs_diff(a, b):
    return sum(abs(x - y) for x, y in zip(a, b)) / len(a)


def request(server, method, path, body=None, token=None):
    headers = {"Content-Type": "application/json"}
    if token:
        headers["Authorization"] = "Bearer " + token
    data = json.dumps(body).encode() if body is not None else None
    req = urllib.request.Request(server.url + path, data=data, method=method, headers=headers)
    with urllib.request.urlopen(req, timeout=30) as r:
        answer = r.read()
        return json.loads(answer) if answer else None  # 204: no body


@unittest.skipUnless(find_chromium(), "chromium is not installed: browser tests skipped "
                     "(scripts/install-deps.sh installs it)")
class ViewerInChromium(unittest.TestCase):
    token = None
    data = False  # True: the server keeps a data directory (past versions to view)

    @classmethod
    def setUpClass(cls):
        env = {"STRATA_TOKEN": cls.token} if cls.token else {}
        cls.data_dir = tempfile.TemporaryDirectory() if cls.data else None
        args = ["--demo"] + (["--data", cls.data_dir.name] if cls.data_dir else [])
        cls.server = ServerProcess(SERVER, args, env=env)
        cls.browser = Browser(width=1000, height=720)

    @classmethod
    def tearDownClass(cls):
        cls.browser.close()
        cls.server.stop()
        if cls.data_dir:
            cls.data_dir.cleanup()

    def shot(self, name):
        self.browser.screenshot(os.path.join(SHOTS, name + ".png"))

    # A small frame and few samples: quick to render on a busy CI machine (one with two cores
    # shared by other builds renders 640x360 in about a second).
    PAGE = "/?width=320&height=180&max_samples=4&fps=30"

    def open_viewer(self):
        self.browser.navigate(self.server.url + self.PAGE)
        self.browser.wait_for(SAMPLE + " !== null", timeout=20)

    def wait_settled(self, quiet=1.5, timeout=30.0):
        """Waits until progressive refinement has stopped changing the frame for `quiet` s."""
        deadline = time.monotonic() + timeout
        last = self.browser.evaluate(SAMPLE)
        since = time.monotonic()
        while time.monotonic() < deadline:
            time.sleep(0.1)
            now = self.browser.evaluate(SAMPLE)
            if now != last:
                last, since = now, time.monotonic()
            elif time.monotonic() - since >= quiet:
                return now
        raise AssertionError("the frame kept changing: progressive refinement did not end")


class ViewerWithoutToken(ViewerInChromium):
    def test_1_a_frame_appears_and_is_not_blank(self):
        self.open_viewer()
        lum = luminance(self.browser.evaluate(SAMPLE))
        self.shot("frame")
        self.assertGreater(statistics.pstdev(lum), 10.0, "the frame is flat")
        self.assertGreater(statistics.mean(lum), 10.0, "the frame is black")

    def test_2_an_edit_by_another_client_changes_the_frame_within_a_second(self):
        self.open_viewer()
        before = luminance(self.wait_settled())
        start = time.monotonic()
        request(self.server, "POST", "/v1/edits",
                {"edits": [{"op": "set_transform", "instance": "ball",
                            "transform": {"translate": [2.5, 3.0, 0.5], "scale": 1.6}}]})
        changed = None
        while time.monotonic() - start < 1.0:
            now = luminance(self.browser.evaluate(SAMPLE))
            if mean_abs_diff(before, now) > 2.0:
                changed = time.monotonic() - start
                break
            time.sleep(0.02)
        self.shot("after-edit")
        self.assertIsNotNone(changed, "the frame did not change within a second of the edit")
        print(f"frame changed {changed * 1000:.0f} ms after the edit", file=sys.stderr)

    def test_3_a_click_selects_the_instance_under_it_and_an_edit_reaches_the_scene(self):
        self.open_viewer()
        width, height = self.browser.evaluate("window.strata.size")
        # A pixel that shows the ball, found with the pick endpoint itself.
        target = None
        for fx, fy in [(0.5, 0.5), (0.5, 0.45), (0.5, 0.55), (0.45, 0.5), (0.55, 0.5)]:
            x, y = int(width * fx), int(height * fy)
            hit = request(self.server, "GET", f"/v1/pick?x={x}&y={y}&width={width}&height={height}")["hit"]
            if hit:
                target = (x, y, hit["instance"])
                break
        self.assertIsNotNone(target, "nothing in the middle of the demo frame")
        x, y, instance = target
        rect = self.browser.evaluate(
            "(() => { const r = document.getElementById('frame').getBoundingClientRect();"
            " return [r.left, r.top]; })()")
        self.browser.click(rect[0] + x + 0.5, rect[1] + y + 0.5)
        selected = self.browser.wait_for(
            "document.getElementById('inspector').dataset.instance", timeout=5)
        self.assertEqual(selected, instance)
        mesh = request(self.server, "GET", "/v1/scene/instances/" + instance)["mesh"]
        build = request(self.server, "GET", "/v1/scene/meshes/" + mesh)["build"]
        triangles = request(self.server, "GET", "/v1/scene/meshes/" + mesh)["triangles"]
        self.assertEqual(
            self.browser.evaluate("document.getElementById('sel-primitives').textContent"),
            f"{triangles} triangles")
        # The words for points and curves, from the viewer's own module.
        words = self.browser.evaluate(
            "import('/web/inspector.js').then((m) => [m.meshPrimitives({kind: 'points', vertices: 3}),"
            " m.meshPrimitives({kind: 'curves', primitives: 8, style: 'flat', basis: 'bezier',"
            " strands: 2}), m.meshPrimitives({kind: 'triangles', triangles: 12, motion_keys: 3}),"
            " m.meshPrimitives({kind: 'points', vertices: 3, motion_keys: 1})])")
        self.assertEqual(words, ["3 points", "8 flat bezier curve segments in 2 strands",
                                 "12 triangles, 3 vertex keys", "3 points"])
        ranges = self.browser.evaluate(
            "import('/web/inspector.js').then((m) => [m.lodRange({lod_near: 0, lod_far: 1e15}),"
            " m.lodRange({lod_near: 0, lod_far: 40}), m.lodRange({lod_near: 40, lod_far: 1e15})])")
        self.assertEqual(ranges, ["", "from 0 to 40", "from 40 on"])
        spans = self.browser.evaluate(
            "import('/web/inspector.js').then((m) => [m.animationSpan({}),"
            " m.animationSpan({animation: [{time: 0}, {time: 1.5}], animation_loop: true}),"
            " m.animationSpan({animation: [{time: 2}]})])")
        self.assertEqual(spans, ["", "2 keys from 0 to 1.5 s, looping", "1 key at 2 s"])
        self.assertEqual(
            self.browser.evaluate("document.getElementById('sel-build').textContent"),
            f"{build['prefer']}, {'refit' if build['allow_refit'] else 'no refit'}"
            + (", compacted BLAS" if build["compact"] else ""))
        self.shot("selected")

        # Frame: the viewer's camera aims at the instance's world bounds, from where it looked.
        bounds = request(self.server, "GET", "/v1/scene/instances/" + instance)["bounds"]
        before = self.browser.evaluate("window.strata.sceneCamera")
        self.browser.evaluate("document.getElementById('sel-frame').click()")
        camera = self.browser.wait_for("window.strata.controls.camera", timeout=5)
        center = [(a + b) / 2 for a, b in zip(bounds["min"], bounds["max"])]
        for got, want in zip(camera["target"], center):
            self.assertAlmostEqual(got, want, places=4)
        def direction(c):
            d = [t - e for t, e in zip(c["target"], c["eye"])]
            n = sum(v * v for v in d) ** 0.5
            return [v / n for v in d]
        for got, want in zip(direction(camera), direction(before)):
            self.assertAlmostEqual(got, want, places=4)
        self.shot("framed")
        self.browser.evaluate("window.strata.controls.follow()")

        # The viewer's own edit: a new x translation through the inspector.
        self.browser.evaluate(
            "(() => { document.getElementById('sel-translate-0').value = '-1.25';"
            " document.getElementById('sel-apply').click(); return true; })()")
        deadline = time.monotonic() + 5
        doc = None
        while time.monotonic() < deadline:
            doc = request(self.server, "GET", "/v1/scene/instances/" + instance)
            if abs(doc["transform"][3] - (-1.25)) < 1e-4:
                break
            time.sleep(0.05)
        self.assertAlmostEqual(doc["transform"][3], -1.25, places=4)
        self.browser.wait_for("document.getElementById('message').textContent.includes('Applied')")
        # The panel reloads the instance at its new version before the next edit (an edit based
        # on the old version would be a 412 conflict, shown as such).
        self.browser.wait_for(
            f"document.getElementById('sel-version') && "
            f"document.getElementById('sel-version').textContent == '{doc['version']}'")

        # Hidden from the viewer: the scene says so.
        self.browser.evaluate(
            "(() => { const b = document.getElementById('sel-visible'); b.checked = false;"
            " b.dispatchEvent(new Event('change')); return true; })()")
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline:
            doc = request(self.server, "GET", "/v1/scene/instances/" + instance)
            if not doc["visible"]:
                break
            time.sleep(0.05)
        self.assertFalse(doc["visible"])

    def test_4_the_cost_panel_shows_each_commit(self):
        self.open_viewer()
        version = request(self.server, "POST", "/v1/edits",
                          {"edits": [{"op": "set_transform", "instance": "crate-a",
                                      "transform": {"translate": [1, 0.5, 2]}}]})["version"]
        self.browser.wait_for(
            f"document.getElementById('last-report').dataset.version == '{version}'", timeout=5)
        text = self.browser.evaluate("document.getElementById('last-report').textContent")
        self.assertIn("TLAS:", text)
        self.shot("cost-panel")
        # A compacted mesh: its entry gives both sizes, the memory line the saving.
        version = request(self.server, "POST", "/v1/edits", {"edits": [
            {"op": "add_mesh", "id": "gem", "build": {"compact": True},
             "shape": {"type": "sphere", "radius": 0.5, "segments": 48}},
            {"op": "add_instance", "id": "gem-a", "mesh": "gem",
             "transform": {"translate": [0, 1, 0]}}]})["version"]
        self.browser.wait_for(
            f"document.getElementById('last-report').dataset.version == '{version}'", timeout=5)
        text = self.browser.evaluate("document.getElementById('last-report').textContent")
        self.assertRegex(text,
                         r"rebuilt gem: added, \d+ primitives, compacted [\d.]+ → [\d.]+ MiB")
        self.assertRegex(text, r"compaction saves [\d.]+ MiB over 1 meshes")

    def test_5_the_time_bar_scrubs_plays_and_sets_the_scene_time(self):
        request(self.server, "POST", "/v1/edits", {"edits": [
            {"op": "update_instance", "instance": "ball", "animation": [
                {"time": 0, "transform": {"translate": [-3, 1, 0]}},
                {"time": 2, "transform": {"translate": [3, 1, 0], "scale": 1.5}}]},
            {"op": "set_time", "time": 0}]})
        self.open_viewer()
        self.assertEqual(self.browser.evaluate("document.getElementById('time-label').textContent"),
                         "0.00 s (scene)")
        before = luminance(self.wait_settled())
        # Scrubbing: the viewer's own time travels in the stream's URL; the scene keeps its clock.
        self.browser.evaluate("window.strata.timeBar.scrub(1.5)")
        self.browser.wait_for("window.strata.streamUrl.includes('time=1.500')", timeout=5)
        after = luminance(self.wait_settled())
        self.assertGreater(mean_abs_diff(before, after), 2.0, "scrubbing did not move the ball")
        self.shot("time-scrubbed")
        self.assertEqual(request(self.server, "GET", "/v1/scene")["timeline"]["time"], 0)
        self.assertEqual(self.browser.evaluate("document.getElementById('time-label').textContent"),
                         "1.50 s")
        # Playing moves the time on, a stream per step, until paused.
        self.browser.evaluate("document.getElementById('time-play').click()")
        self.browser.wait_for("window.strata.timeBar.time > 1.7", timeout=5)
        self.browser.evaluate("document.getElementById('time-play').click()")
        paused = self.browser.evaluate("window.strata.timeBar.time")
        time.sleep(0.3)
        self.assertEqual(self.browser.evaluate("window.strata.timeBar.time"), paused)
        # "Set scene time": one set_time edit, and the bar follows the scene's clock again.
        self.browser.evaluate("window.strata.timeBar.scrub(0.5)")
        self.browser.evaluate("document.getElementById('time-set').click()")
        self.browser.wait_for("window.strata.timeBar.time === null", timeout=5)
        self.assertEqual(request(self.server, "GET", "/v1/scene")["timeline"]["time"], 0.5)
        self.assertNotIn("time=", self.browser.evaluate("window.strata.streamUrl"))
        request(self.server, "POST", "/v1/edits", {"edits": [
            {"op": "update_instance", "instance": "ball", "animation": []}]})


class ViewerTreeAndStill(ViewerInChromium):
    def test_1_the_scene_panel_is_a_tree_of_groups_that_fold(self):
        self.open_viewer()
        spot = "#scene-list > li.group[data-id=\"spot\"]"
        child = spot + " > ul > li"
        self.browser.wait_for(f"!!document.querySelector('{child}')", timeout=10)
        # Root instances sit at the top level beside the group; spot's own are nested in it.
        self.assertTrue(self.browser.evaluate(
            "!!document.querySelector('#scene-list > li.instance[data-id=\"ball\"]')"))
        nested = self.browser.evaluate(f"document.querySelectorAll('{child}').length")
        self.assertGreater(nested, 0)
        self.browser.evaluate(f"document.querySelector('{spot} > .fold').click()")
        self.browser.wait_for(f"!document.querySelector('{child}')", timeout=5)
        self.browser.evaluate(f"document.querySelector('{spot} > .fold').click()")
        self.browser.wait_for(f"document.querySelectorAll('{child}').length == {nested}", timeout=5)
        # A click on a nested entry selects it, not the group around it.
        ident = self.browser.evaluate(f"document.querySelector('{child}').dataset.id")
        kind = self.browser.evaluate(f"document.querySelector('{child}').dataset.kind")
        self.browser.evaluate(f"document.querySelector('{child}').click()")
        self.assertEqual(self.browser.wait_for(
            f"document.getElementById('inspector').dataset.{kind}", timeout=5), ident)
        self.shot("tree")

    def test_2_still_mode_renders_one_frame_and_opens_nothing_endless(self):
        self.browser.navigate(self.server.url + "/?still&width=320&height=180&spp=4")
        self.assertEqual(self.browser.wait_for("document.body.dataset.still", timeout=30), "ready")
        lum = luminance(self.browser.evaluate(SAMPLE))
        self.assertGreater(statistics.mean(lum), 10.0, "the still frame is black")
        urls = self.browser.evaluate(
            "performance.getEntriesByType('resource').map((e) => e.name).join(' ')")
        self.assertIn("/v1/render?", urls)
        self.assertNotIn("/v1/stream", urls)
        self.assertNotIn("/v1/events", urls)
        self.assertIn("(still)", self.browser.evaluate("document.title"))

    def test_3_the_screenshot_recipe_of_the_viewer_readme_works(self):
        # clients/web/README.md: a headless chromium's own --screenshot, which waits for the
        # page load to end (an endless stream would never let it).
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "still.png")
            run = subprocess.run(
                [find_chromium(), "--headless=new", "--no-sandbox", "--disable-gpu",
                 "--disable-dev-shm-usage", f"--user-data-dir={folder}/profile",
                 f"--screenshot={path}", "--window-size=1000,700", "--virtual-time-budget=30000",
                 self.server.url + "/?still&width=640&height=360"],
                capture_output=True, timeout=120)
            self.assertEqual(run.returncode, 0, run.stderr[-2000:])
            with open(path, "rb") as f:
                width, height, channels, pixels = decode_png(f.read())
        self.assertEqual((width, height), (1000, 700))
        # The frame sits at the left of the page below the header: not all dark there.
        row = 150 * width * channels
        stripe = pixels[row:row + 500 * channels]
        self.assertGreater(max(stripe), 60, "the screenshot shows no frame")

    def test_4_a_named_scene_has_its_own_viewer_url(self):
        request(self.server, "PUT", "/v1/scenes/lab")
        request(self.server, "POST", "/v1/scenes/lab/edits", {"edits": [
            {"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 24}},
            {"op": "add_instance", "id": "lab-ball", "mesh": "ball"}]})
        self.browser.navigate(self.server.url + "/?scene=lab&width=320&height=180&fps=30")
        self.browser.wait_for(SAMPLE + " !== null", timeout=20)
        status = self.browser.wait_for(
            "(() => { const t = document.getElementById('status').textContent;"
            " return t.includes('1 instances') ? t : null; })()", timeout=10)
        self.assertTrue(status.startswith("scene lab · version 1"), status)
        urls = self.browser.evaluate(
            "performance.getEntriesByType('resource').map((e) => e.name).join(' ')")
        self.assertIn("/v1/scenes/lab/stream?", urls)
        self.assertIn("/v1/scenes/lab/scene", urls)
        self.assertNotIn("/v1/stream?", urls)
        # Another client's edit in that scene reaches this viewer; the default scene's do not
        # (its version stays at 1).
        request(self.server, "POST", "/v1/scenes/lab/edits", {"edits": [
            {"op": "add_instance", "id": "lab-ball-2", "mesh": "ball",
             "transform": {"translate": [2, 0, 0]}}]})
        self.browser.wait_for("window.strata.version === 2", timeout=10)
        self.shot("named-scene")
        request(self.server, "DELETE", "/v1/scenes/lab")


class ViewerWithHistory(ViewerInChromium):
    data = True

    def test_view_shows_a_past_version_until_back_to_live(self):
        self.open_viewer()
        before = luminance(self.wait_settled())
        # Another client sinks the big glass ball out of sight.
        version = request(self.server, "POST", "/v1/edits", {"edits": [
            {"op": "set_transform", "instance": "ball",
             "transform": {"translate": [0, -50, 0]}}]})["version"]
        self.browser.wait_for(
            f"document.getElementById('history-list').dataset.version == '{version}'",
            timeout=10)
        self.browser.wait_for(f"window.strata.version === {version}", timeout=10)
        after = luminance(self.wait_settled())
        self.assertGreater(mean_abs_diff(before, after), 2.0)

        # View on the version before: the ball is back, rendered from the data directory.
        self.browser.evaluate(
            f"document.querySelector('#history-list li[data-version=\"{version - 1}\"] "
            "button.view').click()")
        self.browser.wait_for(f"document.body.dataset.past === '{version - 1}'", timeout=20)
        self.browser.wait_for(SAMPLE + " !== null", timeout=10)
        past = luminance(self.browser.evaluate(SAMPLE))
        self.assertFalse(self.browser.evaluate("document.getElementById('past').hidden"))
        self.assertLess(mean_abs_diff(before, past), mean_abs_diff(after, past))
        self.shot("past-version")
        # A click does not pick in the past; the live scene is one button away.
        self.browser.evaluate("document.getElementById('past-live').click()")
        self.browser.wait_for("document.body.dataset.past === undefined", timeout=5)
        self.browser.wait_for("window.strata.streamKey !== null", timeout=10)
        live = luminance(self.wait_settled())
        self.assertLess(mean_abs_diff(after, live), mean_abs_diff(before, live))


class ViewerWithToken(ViewerInChromium):
    token = "browser-test-token"

    def test_the_token_is_asked_once_kept_in_session_storage_and_used(self):
        self.browser.navigate(self.server.url + self.PAGE)
        self.browser.wait_for("document.getElementById('token-dialog').open")
        self.shot("token-dialog")
        self.browser.evaluate(
            "(() => { document.getElementById('token-input').value = 'browser-test-token';"
            " document.getElementById('token-form').requestSubmit(); return true; })()")
        self.browser.wait_for(SAMPLE + " !== null", timeout=20)
        self.assertEqual(self.browser.evaluate("sessionStorage.getItem('strata.token')"),
                         self.token)
        # A reload keeps it: no second question.
        self.browser.navigate(self.server.url + self.PAGE)
        self.browser.wait_for(SAMPLE + " !== null", timeout=20)
        self.assertFalse(self.browser.evaluate("document.getElementById('token-dialog').open"))
        self.shot("token-accepted")


if __name__ == "__main__":
    unittest.main()

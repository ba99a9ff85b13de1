"""The viewer's selection highlight, group editing, conflicts and touch camera in headless Debian
chromium against a real strata-server --demo (each class its own server):

- a click tints exactly the picked instance's pixels (server-side, from the instance_id AOV): the
  tinted frame differs from the plain frame of the same render where the instance is, and
  nowhere far from it;
- a group chosen from an instance's group path or from the scene panel is moved and hidden
  through the inspector, and GET /v1/scene/groups/{id} says so;
- another client's edit between the viewer's read and its write makes the viewer's If-Match fail
  (412): the page says so clearly, applies nothing, reloads the current values, and a second
  apply succeeds;
- a one-finger drag orbits and a two-finger pinch zooms the viewer's camera (CDP touch events);
- the scene panel lists the scene again when another client adds, hides or removes an instance;
- Ctrl+Z undoes and Ctrl+Shift+Z and Ctrl+Y redo (CDP key events; POST /v1/undo and /v1/redo,
  checked through GET /v1/scene), but not while typing in a field; nothing left to redo is said as
  such; the history panel lists each version with its kind and message, and its buttons undo and
  redo.
"""

import base64
import math
import os
import sys
import time
import unittest
import urllib.error

from test_viewer import ViewerInChromium, request  # noqa: E402

# The frame at its own resolution as base64 RGBA (same origin: the canvas is not tainted).
FULL = """((id) => {
  const img = document.getElementById(id);
  if (!img || !img.complete || !img.naturalWidth) return null;
  const c = document.createElement('canvas'); c.width = img.naturalWidth; c.height = img.naturalHeight;
  const ctx = c.getContext('2d'); ctx.drawImage(img, 0, 0);
  const d = ctx.getImageData(0, 0, c.width, c.height).data;
  let s = ''; for (let i = 0; i < d.length; i += 8192) s += String.fromCharCode(...d.subarray(i, i + 8192));
  return [c.width, c.height, btoa(s)];
})"""


def full_frame(browser, element_id):
    r = browser.evaluate(f"{FULL}('{element_id}')")
    if not r:
        return None
    w, h, data = r
    return w, h, base64.b64decode(data)


class ViewerSelectionAndEdits(ViewerInChromium):
    PAGE = "/?width=320&height=180&max_samples=4&fps=30"

    def settled(self, element_id, quiet=1.5, timeout=30.0):
        """The frame of `element_id` once it has not changed for `quiet` seconds."""
        deadline = time.monotonic() + timeout
        last, since = full_frame(self.browser, element_id), time.monotonic()
        while time.monotonic() < deadline:
            time.sleep(0.1)
            now = full_frame(self.browser, element_id)
            if now != last:
                last, since = now, time.monotonic()
            elif now and time.monotonic() - since >= quiet:
                return now
        raise AssertionError(f"#{element_id} kept changing")

    def instance_mask(self, width, height, instance):
        """Which pixels show `instance`, from POST /v1/pick (the rays the stream's ids come from)."""
        pixels = [[x, y] for y in range(height) for x in range(width)]
        mask = []
        for i in range(0, len(pixels), 10000):
            hits = request(self.server, "POST", "/v1/pick",
                           {"width": width, "height": height, "pixels": pixels[i:i + 10000]})["hits"]
            mask += [bool(h) and h["instance"] == instance for h in hits]
        return mask

    def frame_origin(self):
        return self.browser.evaluate(
            "(() => { const r = document.getElementById('frame').getBoundingClientRect();"
            " return [r.left, r.top]; })()")

    def select_from_panel(self, kind, ident):
        self.browser.wait_for(f"!!document.querySelector('#scene-list li[data-kind=\"{kind}\"][data-id=\"{ident}\"]')")
        self.browser.evaluate(
            f"document.querySelector('#scene-list li[data-kind=\"{kind}\"][data-id=\"{ident}\"]').click()")
        self.browser.wait_for(f"document.getElementById('inspector').dataset.{kind} == '{ident}'")

    def test_1_a_click_tints_the_frame_where_the_instance_is_and_nowhere_else(self):
        self.open_viewer()
        width, height = self.browser.evaluate("window.strata.size")
        mask = self.instance_mask(width, height, "ball")
        self.assertGreater(sum(mask), 200, "the ball should cover part of the frame")
        # A plain stream of the same view beside the viewer's: the same shared render, untinted.
        self.browser.evaluate(
            "(() => { const i = document.createElement('img'); i.id = 'reference';"
            f" i.src = '/v1/stream?width={width}&height={height}&quality=80&max_samples=4&client=ref';"
            " document.body.append(i); return true; })()")
        before = self.settled("frame")
        inside = next(i for i, m in enumerate(mask) if m and all(
            mask[i + d] for d in (-2 * width, 2 * width, -2, 2)))
        x, y = inside % width, inside // width
        left, top = self.frame_origin()
        self.browser.click(left + x + 0.5, top + y + 0.5)
        self.browser.wait_for("document.getElementById('inspector').dataset.instance == 'ball'")
        self.assertIn("highlight=ball", self.browser.evaluate("window.strata.streamUrl"))
        tinted = self.settled("frame")
        plain = self.settled("reference")
        self.shot("highlight")
        self.assertEqual((tinted[0], tinted[1]), (width, height))
        self.assertNotEqual(tinted[2], before[2], "the selection did not change the frame")

        # Pixels far from the ball: no 16x16 JPEG block within a block of them shows it.
        blocks = set()
        for i, m in enumerate(mask):
            if m:
                blocks.add(((i % width) // 16, (i // width) // 16))
        far = inner = 0
        far_diff = inner_diff = 0.0
        for i, m in enumerate(mask):
            px, py = i % width, i // width
            a, b = tinted[2][4 * i:4 * i + 3], plain[2][4 * i:4 * i + 3]
            d = sum(abs(p - q) for p, q in zip(a, b)) / 3
            if not any((px // 16 + dx, py // 16 + dy) in blocks for dx in (-1, 0, 1) for dy in (-1, 0, 1)):
                far += 1
                far_diff += d
            elif m and 2 <= px < width - 2 and 2 <= py < height - 2 and all(
                    mask[i + o] for o in (-2 * width, 2 * width, -2, 2)):
                inner += 1
                inner_diff += d
        self.assertGreater(far, width * height // 3)
        self.assertGreater(inner, 100)
        print(f"highlight: inner pixels differ by {inner_diff / inner:.1f} on average, far pixels"
              f" by {far_diff / far:.3f} ({inner} inner, {far} far)", file=sys.stderr)
        self.assertGreater(inner_diff / inner, 15.0, "the ball's pixels were not tinted")
        self.assertLess(far_diff / far, 0.5, "pixels far from the ball changed")

        # Deselected (a click on the sky): the frame is the plain one again.
        self.browser.evaluate("window.strata.select(null)")
        self.assertNotIn("highlight=", self.browser.evaluate("window.strata.streamUrl"))

    def test_2_a_group_is_selected_from_the_path_and_the_panel_and_edited(self):
        request(self.server, "POST", "/v1/edits", {"edits": [
            {"op": "add_group", "id": "stack", "transform": {"translate": [0, 0, 0]}},
            {"op": "update_instance", "instance": "crate-a", "parent": "stack"},
            {"op": "update_instance", "instance": "crate-b", "parent": "stack"}]})
        self.open_viewer()
        self.select_from_panel("instance", "crate-a")
        self.assertEqual(self.browser.evaluate("document.getElementById('sel-path').textContent"),
                         "/stack")
        # The group from the instance's path.
        self.browser.evaluate(
            "document.querySelector('#sel-path button[data-group=\"stack\"]').click()")
        self.browser.wait_for("document.getElementById('inspector').dataset.group == 'stack'")
        self.assertIn("2 instances", self.browser.evaluate("document.getElementById('inspector').textContent"))
        self.assertNotIn("highlight=", self.browser.evaluate("window.strata.streamUrl"))
        self.browser.evaluate(
            "(() => { const f = document.getElementById('sel-translate-0'); f.value = '1.5';"
            " f.dispatchEvent(new Event('input')); document.getElementById('sel-rotate-1').value = '30';"
            " document.getElementById('sel-apply').click(); return true; })()")
        self.browser.wait_for("document.getElementById('message').textContent.includes('Applied')")
        doc = request(self.server, "GET", "/v1/scene/groups/stack")
        self.assertAlmostEqual(doc["transform"][3], 1.5, places=4)
        self.assertAlmostEqual(doc["transform"][2], math.sin(math.radians(30)), places=3)
        crate = request(self.server, "GET", "/v1/scene/instances/crate-a")
        self.assertAlmostEqual(crate["world_transform"][3] - crate["transform"][3] * math.cos(math.radians(30))
                               - crate["transform"][11] * math.sin(math.radians(30)), 1.5, places=3)
        self.shot("group-moved")

        # The group from the scene panel, hidden.
        self.browser.evaluate("window.strata.select(null)")
        self.browser.evaluate("document.getElementById('scene-search').value = 'stack';"
                              " document.getElementById('scene-search').dispatchEvent(new Event('input'))")
        self.select_from_panel("group", "stack")
        self.browser.wait_for(f"document.getElementById('sel-version').textContent == '{doc['version']}'")
        self.browser.evaluate(
            "(() => { const b = document.getElementById('sel-visible'); b.checked = false;"
            " b.dispatchEvent(new Event('change')); return true; })()")
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline and request(self.server, "GET", "/v1/scene/groups/stack")["visible"]:
            time.sleep(0.05)
        self.assertFalse(request(self.server, "GET", "/v1/scene/groups/stack")["visible"])
        self.assertFalse(request(self.server, "GET", "/v1/scene/instances/crate-b")["world_visible"])

    def test_3_another_clients_edit_between_read_and_write_is_a_clear_conflict(self):
        self.open_viewer()
        self.select_from_panel("instance", "lamp")
        read_version = int(self.browser.evaluate("document.getElementById('sel-version').textContent"))
        old_x = request(self.server, "GET", "/v1/scene/instances/lamp")["transform"][3]
        # The user starts typing...
        self.browser.evaluate(
            "(() => { const f = document.getElementById('sel-translate-0'); f.value = '-3.5';"
            " f.dispatchEvent(new Event('input')); return true; })()")
        # ...another client edits the scene meanwhile...
        other = request(self.server, "POST", "/v1/edits", {"edits": [
            {"op": "set_transform", "instance": "ball", "transform": {"translate": [0.5, 1.5, 0]}}]})
        self.browser.wait_for("!document.getElementById('sel-outdated').hidden", timeout=10)
        self.assertEqual(self.browser.evaluate("document.getElementById('sel-translate-0').value"), "-3.5",
                         "the user's typed value was overwritten")
        # ...and the viewer's write, If-Match on the version it read, is refused.
        self.browser.evaluate("document.getElementById('sel-apply').click()")
        self.browser.wait_for("document.getElementById('message').className == 'conflict'", timeout=10)
        text = self.browser.evaluate("document.getElementById('message').textContent")
        self.shot("conflict")
        self.assertIn("Conflict", text)
        self.assertIn(f"since version {read_version}", text)
        self.assertIn("Nothing was applied", text)
        self.assertEqual(request(self.server, "GET", "/v1/scene/instances/lamp")["transform"][3], old_x)
        # Recovered: the panel shows the current state, and applying again works.
        self.browser.wait_for(
            f"document.getElementById('sel-version').textContent == '{other['version']}'"
            " && document.getElementById('sel-outdated').hidden", timeout=10)
        self.assertAlmostEqual(float(self.browser.evaluate(
            "document.getElementById('sel-translate-0').value")), old_x, places=3)
        self.browser.evaluate(
            "(() => { const f = document.getElementById('sel-translate-0'); f.value = '-3.5';"
            " f.dispatchEvent(new Event('input')); document.getElementById('sel-apply').click();"
            " return true; })()")
        self.browser.wait_for("document.getElementById('message').textContent.includes('Applied')")
        self.assertAlmostEqual(request(self.server, "GET", "/v1/scene/instances/lamp")["transform"][3],
                               -3.5, places=4)

    def test_4_a_one_finger_drag_orbits_and_a_pinch_zooms(self):
        self.open_viewer()
        self.browser.evaluate("window.strata.controls.follow()")
        scene = request(self.server, "GET", "/v1/scene")["camera"]
        left, top = self.frame_origin()
        cx, cy = left + 160, top + 90

        def camera():
            return self.browser.evaluate("window.strata.controls.camera")

        def dist(c):
            return math.dist(c["eye"], c["target"])

        self.browser.touch_drag([(cx, cy)], [(cx + 80, cy + 10)])
        orbit = camera()
        self.assertIsNotNone(orbit, "a one-finger drag did not move the camera")
        self.assertGreater(math.dist(orbit["eye"], scene["eye"]), 0.1, "the eye did not move")
        for a, b in zip(orbit["target"], scene["target"]):
            self.assertAlmostEqual(a, b, places=4)  # an orbit keeps the target
        self.assertAlmostEqual(dist(orbit), math.dist(scene["eye"], scene["target"]), places=3)
        self.browser.wait_for("window.strata.streamUrl.includes('eye=')")

        # Fingers apart: zoom in (closer to the target); together: zoom out.
        self.browser.touch_drag([(cx - 20, cy), (cx + 20, cy)], [(cx - 80, cy), (cx + 80, cy)])
        pinched = camera()
        self.assertLess(dist(pinched), dist(orbit) * 0.6)
        self.browser.touch_drag([(cx - 80, cy), (cx + 80, cy)], [(cx - 20, cy), (cx + 20, cy)])
        self.assertGreater(dist(camera()), dist(pinched) * 1.5)
        self.shot("touch")

    def test_5_the_scene_panel_follows_other_clients_edits(self):
        self.open_viewer()
        self.select_from_panel("instance", "ball")
        item = "#scene-list li[data-kind=\"instance\"][data-id=\"newcomer\"]"
        self.assertFalse(self.browser.evaluate(f"!!document.querySelector('{item}')"))
        request(self.server, "POST", "/v1/edits", {"edits": [
            {"op": "add_instance", "id": "newcomer", "mesh": "crate", "name": "Crate on the shelf",
             "transform": {"translate": [0, 3, -3]}}]})
        self.browser.wait_for(f"!!document.querySelector('{item}')", timeout=5)
        # Its display name leads the entry, and the inspector shows it once selected.
        self.assertTrue(self.browser.evaluate(
            f"document.querySelector('{item}').textContent.startsWith('Crate on the shelf')"))
        # The selection stays marked across the new listing.
        self.assertTrue(self.browser.evaluate(
            "document.querySelector('#scene-list li[data-id=\"ball\"]').classList.contains('selected')"))
        # A search typed before the change still filters the new list.
        self.browser.evaluate(
            "(() => { const f = document.getElementById('scene-search'); f.value = 'on the shelf';"
            " f.dispatchEvent(new Event('input')); return true; })()")
        request(self.server, "POST", "/v1/edits", {"edits": [
            {"op": "update_instance", "instance": "newcomer", "visible": False}]})
        self.browser.wait_for(f"document.querySelector('{item}') &&"
                              f" document.querySelector('{item}').textContent.includes('hidden')",
                              timeout=5)
        self.assertEqual(self.browser.evaluate("document.querySelectorAll('#scene-list li').length"), 1)
        self.select_from_panel("instance", "newcomer")
        self.browser.wait_for("document.getElementById('sel-name') &&"
                              " document.getElementById('sel-name').textContent =="
                              " 'Crate on the shelf'")
        request(self.server, "POST", "/v1/edits", {"edits": [
            {"op": "remove_instance", "instance": "newcomer"}]})
        self.browser.wait_for(f"!document.querySelector('{item}')", timeout=5)

    def test_6_ctrl_z_undoes_ctrl_shift_z_and_ctrl_y_redo_and_the_history_lists_them(self):
        self.open_viewer()

        def entry(version):
            return f"#history-list li[data-version=\"{version}\"]"

        def exists():
            try:
                request(self.server, "GET", "/v1/scene/instances/undo-me")
                return True
            except urllib.error.HTTPError as e:
                if e.code != 404:
                    raise
                return False

        def version():
            return request(self.server, "GET", "/v1/scene")["version"]

        def press(key, modifiers, expect):
            """A key press that should bring the scene to version `expect`; waits until the
            server and the viewer are both there."""
            self.browser.key(key, modifiers)
            deadline = time.monotonic() + 5
            while time.monotonic() < deadline and version() != expect:
                time.sleep(0.05)
            self.assertEqual(version(), expect, f"{'+'.join(modifiers)}+{key}")
            self.browser.wait_for(f"window.strata.version == {expect}", timeout=5)

        added = request(self.server, "POST", "/v1/edits", {
            "message": "a crate to take back",
            "edits": [{"op": "add_instance", "id": "undo-me", "mesh": "crate",
                       "transform": {"translate": [0, 3, -3]}}]})["version"]
        # The viewer sees the version (its undo applies only at the version it shows), and the
        # history panel lists it with its message and ops, on the undo stack.
        self.browser.wait_for(f"window.strata.version == {added}", timeout=10)
        self.browser.wait_for(f"!!document.querySelector('{entry(added)}')", timeout=5)
        text = self.browser.evaluate(f"document.querySelector('{entry(added)}').textContent")
        self.assertIn(f"v{added} · edit · a crate to take back", text)
        self.assertIn("add_instance", text)
        self.assertTrue(self.browser.evaluate(
            f"document.querySelector('{entry(added)}').classList.contains('undoable')"))
        self.browser.evaluate("document.activeElement.blur(), true")

        press("z", ["ctrl"], added + 1)
        self.assertFalse(exists(), "Ctrl+Z did not take the added instance back")
        self.browser.wait_for("document.getElementById('message').textContent == "
                              f"'Undone: version {added}\\'s batch (now version {added + 1}).'")
        self.browser.wait_for(f"!!document.querySelector('{entry(added + 1)}')", timeout=5)
        self.assertIn(f"undo of v{added}", self.browser.evaluate(
            f"document.querySelector('{entry(added + 1)}').textContent"))
        self.assertFalse(self.browser.evaluate(
            f"document.querySelector('{entry(added)}').classList.contains('undoable')"))
        self.shot("undone")

        press("z", ["ctrl", "shift"], added + 2)
        self.assertTrue(exists(), "Ctrl+Shift+Z did not bring the instance back")
        self.assertIn("Redone", self.browser.evaluate("document.getElementById('message').textContent"))
        press("z", ["ctrl"], added + 3)
        self.assertFalse(exists())
        press("y", ["ctrl"], added + 4)
        self.assertTrue(exists(), "Ctrl+Y did not bring the instance back")
        # Nothing left to redo: said as such, and nothing applied.
        self.browser.key("z", ["ctrl", "shift"])
        self.browser.wait_for("document.getElementById('message').textContent == 'Nothing to redo.'")
        self.assertEqual(version(), added + 4)

        # In a text field, Ctrl+Z is the field's own.
        self.browser.evaluate("document.getElementById('scene-search').focus(), true")
        self.browser.key("z", ["ctrl"])
        time.sleep(0.5)
        self.assertEqual(version(), added + 4)
        self.browser.evaluate("document.activeElement.blur(), true")

        # The panel's buttons do what the keys do.
        self.browser.wait_for(f"document.getElementById('history-list').dataset.version == '{added + 4}'"
                              " && !document.getElementById('history-undo').disabled", timeout=5)
        self.assertTrue(self.browser.evaluate("document.getElementById('history-redo').disabled"))
        self.browser.evaluate("document.getElementById('history-undo').click()")
        self.browser.wait_for(f"window.strata.version == {added + 5}", timeout=5)
        self.assertFalse(exists())
        self.browser.wait_for("!document.getElementById('history-redo').disabled", timeout=5)
        self.browser.evaluate("document.getElementById('history-redo').click()")
        self.browser.wait_for(f"window.strata.version == {added + 6}", timeout=5)
        self.assertTrue(exists())
        self.browser.wait_for(f"!!document.querySelector('{entry(added + 6)}')", timeout=5)
        listed = self.browser.evaluate(
            "document.querySelectorAll('#history-list li[data-version]').length")
        self.assertTrue(7 <= listed <= 20, listed)  # the newest 20 at most
        self.assertIn(f"redo of v{added + 4}", self.browser.evaluate(
            f"document.querySelector('{entry(added + 6)}').textContent"))
        self.shot("history")


if __name__ == "__main__":
    unittest.main()

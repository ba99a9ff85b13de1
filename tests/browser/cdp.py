"""A headless Debian chromium driven over the Chrome DevTools protocol (python3-websocket).

    with Browser() as b:
        b.navigate(url)
        b.wait_for("document.readyState === 'complete'")
        b.screenshot(path)

Standard library plus Debian's python3-websocket; nothing is downloaded.
"""

import base64
import json
import os
import shutil
import subprocess
import tempfile
import time
import urllib.request

import websocket

CHROMIUM_NAMES = ("chromium", "chromium-browser")


def find_chromium():
    """The chromium binary, or None."""
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    return None


class Browser:
    def __init__(self, width=1500, height=900, timeout=30.0):
        binary = find_chromium()
        if not binary:
            raise RuntimeError("chromium is not installed (scripts/install-deps.sh installs it)")
        self._profile = tempfile.mkdtemp(prefix="strata-chromium-")
        self._log = open(os.path.join(self._profile, "chromium.log"), "wb")
        self.process = subprocess.Popen(
            [binary, "--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
             "--no-first-run", "--no-default-browser-check", "--disable-extensions",
             "--remote-debugging-port=0", "--remote-allow-origins=*",
             f"--user-data-dir={self._profile}", f"--window-size={width},{height}",
             "about:blank"],
            stdout=self._log, stderr=subprocess.STDOUT)
        port = self._wait_for_port(timeout)
        targets = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10))
        page = next(t for t in targets if t.get("type") == "page")
        self._ws = websocket.create_connection(page["webSocketDebuggerUrl"], timeout=timeout,
                                               suppress_origin=True)
        self._next_id = 0
        self.console = []
        self.send("Runtime.enable")
        self.send("Page.enable")
        self.send("Emulation.setDeviceMetricsOverride",
                  {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False})

    def _wait_for_port(self, timeout):
        path = os.path.join(self._profile, "DevToolsActivePort")
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if os.path.exists(path):
                with open(path) as f:
                    first = f.readline().strip()
                if first.isdigit():
                    return int(first)
            if self.process.poll() is not None:
                raise RuntimeError("chromium exited:\n" + self.log())
            time.sleep(0.05)
        raise RuntimeError("chromium did not open its DevTools port:\n" + self.log())

    def log(self):
        with open(os.path.join(self._profile, "chromium.log"), errors="replace") as f:
            return f.read()[-4000:]

    def send(self, method, params=None):
        """One DevTools command; returns its result (raises on an error answer)."""
        self._next_id += 1
        my_id = self._next_id
        self._ws.send(json.dumps({"id": my_id, "method": method, "params": params or {}}))
        while True:
            msg = json.loads(self._ws.recv())
            if msg.get("id") == my_id:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                return msg.get("result", {})
            if msg.get("method") == "Runtime.consoleAPICalled":
                args = msg["params"].get("args", [])
                self.console.append(" ".join(str(a.get("value", a.get("description", ""))) for a in args))
            elif msg.get("method") == "Runtime.exceptionThrown":
                self.console.append("exception: " + json.dumps(msg["params"]["exceptionDetails"])[:500])

    def evaluate(self, expression):
        """The value of a JavaScript expression in the page (promises awaited)."""
        r = self.send("Runtime.evaluate", {"expression": expression, "returnByValue": True,
                                           "awaitPromise": True})
        if "exceptionDetails" in r:
            raise RuntimeError(f"{expression[:80]}: {r['exceptionDetails']}")
        return r["result"].get("value")

    def wait_for(self, expression, timeout=10.0, interval=0.05):
        """Polls until `expression` is truthy; returns its value (raises on timeout)."""
        deadline = time.monotonic() + timeout
        value = None
        while time.monotonic() < deadline:
            value = self.evaluate(expression)
            if value:
                return value
            time.sleep(interval)
        raise AssertionError(f"timed out waiting for {expression} (last: {value!r}); console: "
                             + "; ".join(self.console[-10:]))

    def navigate(self, url):
        # The old document may still answer at first (the same URL included): mark it, and wait
        # for a document without the mark.
        self.evaluate("window.__strata_old_page = true")
        self.send("Page.navigate", {"url": url})
        self.wait_for("!window.__strata_old_page && document.readyState === 'complete'")

    def click(self, x, y):
        """A left click at page coordinates (pointer events follow from the mouse events)."""
        for kind in ("mouseMoved", "mousePressed", "mouseReleased"):
            self.send("Input.dispatchMouseEvent", {"type": kind, "x": x, "y": y, "button": "left",
                                                   "buttons": 1 if kind == "mousePressed" else 0,
                                                   "clickCount": 1})

    def key(self, key, modifiers=()):
        """One press of a letter key (down, then up) to the focused element, with `modifiers`
        among "alt", "ctrl", "meta" and "shift": key("z", ["ctrl"]) is Ctrl+Z. As for a shortcut,
        no character is typed."""
        bits = {"alt": 1, "ctrl": 2, "meta": 4, "shift": 8}
        shown = key.upper() if "shift" in modifiers else key.lower()
        for kind in ("rawKeyDown", "keyUp"):
            self.send("Input.dispatchKeyEvent", {
                "type": kind, "key": shown, "code": "Key" + key.upper(),
                "windowsVirtualKeyCode": ord(key.upper()),
                "modifiers": sum(bits[m] for m in modifiers)})

    def touch(self, kind, points):
        """One touch event ("touchStart", "touchMove", "touchEnd") with `points` [(x, y), ...]
        in page coordinates (touchEnd: the points still down)."""
        self.send("Input.dispatchTouchEvent", {
            "type": kind,
            "touchPoints": [{"x": x, "y": y, "id": i} for i, (x, y) in enumerate(points)]})

    def touch_drag(self, starts, ends, steps=8):
        """Fingers down at `starts`, moved together in `steps` to `ends`, lifted."""
        self.touch("touchStart", starts)
        for k in range(1, steps + 1):
            f = k / steps
            self.touch("touchMove", [(sx + (ex - sx) * f, sy + (ey - sy) * f)
                                     for (sx, sy), (ex, ey) in zip(starts, ends)])
        self.touch("touchEnd", [])

    def screenshot(self, path):
        data = self.send("Page.captureScreenshot", {"format": "png"})["data"]
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "wb") as f:
            f.write(base64.b64decode(data))

    def close(self):
        try:
            self._ws.close()
        except Exception:
            pass
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._log.close()
        shutil.rmtree(self._profile, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

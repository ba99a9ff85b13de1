"""Memory budgets at the process level (ctest label `memory`): each class of amplifying request
that issue 29 found is sent to a fresh strata-server, and the server's peak resident memory
(VmHWM) may grow by at most BOUND(body) = 4 x the body + 96 MiB over what it held idle; the
refusal, when there is one, arrives before that bound is crossed.

  - an OBJ over the scene budget (counted from its lines before it is parsed), and four at once
  - an MTL naming one image fifty times (one texture)
  - a GLB whose images all name one buffer view (one texture, not one per image)
  - a glTF of 100,000 tiny primitives (each mesh's overhead counted, before tinygltf parses)
  - add_texture with a PNG followed by megabytes of junk, three times (only the PNG is kept)
  - a JSON batch of millions of clears (refused while parsing, --max-json-values)
  - a snapshot of millions of one-byte clears (refused from its count, --max-batch-edits)
  - frame streams of large views beyond --max-stream-mb (503 before the view is made)

and every file of assimp-testmodels through the sandboxed importers, memory coming back after.
"""

import base64
import glob
import io
import json
import os
import struct
import sys
import tarfile
import threading
import unittest
import urllib.parse
import zlib

from hostile import Server
from journal_bytes import clears, snapshot_file

MIB = 1 << 20


def bound(body_bytes):
    return 4 * body_bytes + 96 * MIB


def status_kib(pid, field):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise AssertionError(f"no {field} in /proc/{pid}/status")


def png(width, height, seed=1):
    """An RGB PNG of pseudo-random pixels (incompressible: its size is about 3 bytes a pixel)."""
    rows, x = bytearray(), seed
    for _ in range(height):
        rows.append(0)
        for _ in range(width * 3):
            x = (x * 1103515245 + 12345) & 0x7FFFFFFF
            rows.append(x >> 23)
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) +
            chunk(b"IDAT", zlib.compress(bytes(rows), 1)) + chunk(b"IEND", b""))


class PeakMemory(unittest.TestCase):
    def server(self, *args):
        s = Server(list(args))
        self.addCleanup(s.stop)
        # A first request, so that the idle figure includes what every request path allocates.
        self.assertEqual(s.call("GET", "/v1/scene")[0], 200)
        return s

    def assert_bounded(self, server, body_bytes, send):
        """Runs `send()`; the peak may grow by at most bound(body_bytes). Returns its answer."""
        pid = server.process.pid
        before = status_kib(pid, "VmHWM") * 1024
        answer = send()
        grown = status_kib(pid, "VmHWM") * 1024 - before
        print(f"\n{self.id().rsplit('.', 1)[1]}: body {body_bytes / MIB:.1f} MiB, peak +"
              f"{grown / MIB:.0f} MiB (bound {bound(body_bytes) / MIB:.0f} MiB)", file=sys.stderr)
        self.assertLess(grown, bound(body_bytes),
                        f"peak resident memory grew by {grown / MIB:.0f} MiB for a "
                        f"{body_bytes / MIB:.1f} MiB body; the bound is "
                        f"{bound(body_bytes) / MIB:.0f} MiB")
        self.assertTrue(server.alive())
        return answer

    def assert_imports_one_texture(self, server, query, body, content_type):
        """Imports `body` (its one 512x512 image named many times) within the bound, which
        allows the image's decoded texels once, and checks one texture came of it."""
        status, _, answer = self.assert_bounded(
            server, len(body) + 512 * 512 * 6,
            lambda: server.call("POST", "/v1/assets?" + query, body,
                                {"Content-Type": content_type}))
        self.assertEqual(status, 200, answer[:300])
        self.assertEqual(len(json.loads(answer)["textures"]), 1)

    def test_an_obj_over_the_budget_is_refused_from_its_lines(self):
        s = self.server("--max-scene-triangles", "100000")
        body = b"v 0 0 0\nv 1 0 0\nv 0 1 0\n" + b"f 1 2 3\n" * 2_000_000
        status, _, answer = self.assert_bounded(s, len(body), lambda: s.call(
            "POST", "/v1/assets?format=obj&prefix=big", body, {"Content-Type": "model/obj"}))
        self.assertEqual(status, 413, answer[:300])
        self.assertIn("max_scene_triangles", json.loads(answer)["detail"])

    def test_four_concurrent_over_budget_objs_are_each_refused_from_their_lines(self):
        s = self.server("--max-scene-triangles", "100000")
        body = b"v 0 0 0\nv 1 0 0\nv 0 1 0\n" + b"f 1 2 3\n" * 2_000_000
        answers = []

        def upload(n):
            answers.append(s.call("POST", f"/v1/assets?format=obj&prefix=big{n}", body,
                                  {"Content-Type": "model/obj"}))

        def all_four():
            uploads = [threading.Thread(target=upload, args=(n,)) for n in range(4)]
            for t in uploads:
                t.start()
            for t in uploads:
                t.join()

        self.assert_bounded(s, 4 * len(body), all_four)
        self.assertEqual([a[0] for a in answers], [413] * 4)

    def test_an_mtl_naming_one_image_fifty_times_holds_one_texture(self):
        s = self.server()
        image = png(512, 512)
        obj = b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
        mtl = b""
        for n in range(50):
            mtl += f"newmtl m{n}\nmap_Kd big.png\n".encode()
            obj += f"usemtl m{n}\nf 1 2 3\n".encode()
        archive = io.BytesIO()
        with tarfile.open(fileobj=archive, mode="w") as tar:
            for name, data in (("model.obj", obj), ("m.mtl", mtl), ("big.png", image)):
                info = tarfile.TarInfo(name)
                info.size = len(data)
                tar.addfile(info, io.BytesIO(data))
        body = archive.getvalue()
        self.assert_imports_one_texture(s, "name=model.tar&prefix=mtl", body, "application/x-tar")

    def test_a_glb_whose_images_share_one_buffer_view_holds_one_texture(self):
        s = self.server()
        image = png(512, 512)
        positions = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
        indices = struct.pack("<3H", 0, 1, 2) + b"\0\0"
        binary = positions + indices + image
        binary += b"\0" * (-len(binary) % 4)
        doc = {
            "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1,
                                        "material": 0}]}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]},
                          {"bufferView": 1, "componentType": 5123, "count": 3,
                           "type": "SCALAR"}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                            {"buffer": 0, "byteOffset": 36, "byteLength": 6},
                            {"buffer": 0, "byteOffset": 44, "byteLength": len(image)}],
            "buffers": [{"byteLength": len(binary)}],
            "images": [{"bufferView": 2, "mimeType": "image/png"} for _ in range(50)],
            "textures": [{"source": i} for i in range(50)],
            "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": i}}}
                          for i in range(50)],
        }
        text = json.dumps(doc).encode()
        text += b" " * (-len(text) % 4)
        glb = (struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(binary)) +
               struct.pack("<II", len(text), 0x4E4F534A) + text +
               struct.pack("<II", len(binary), 0x004E4942) + binary)
        self.assert_imports_one_texture(s, "format=glb&prefix=shared", glb, "model/gltf-binary")

    def test_many_tiny_gltf_primitives_are_refused_before_they_are_parsed(self):
        # 100,000 one-triangle primitives sharing two accessors: 4.5 MB of JSON that used to
        # become 100,000 meshes of about 9.6 KB each, after tinygltf's own model of them (about
        # 1 KB each). Each mesh now counts 128 triangles more, and the importer counts the
        # primitives in the text before tinygltf reads it.
        s = self.server("--max-scene-triangles", "100000")
        positions = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
        indices = struct.pack("<3H", 0, 1, 2) + b"\0\0"
        data = base64.b64encode(positions + indices).decode()
        count = 100_000
        doc = {
            "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}] * count}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]},
                          {"bufferView": 1, "componentType": 5123, "count": 3,
                           "type": "SCALAR"}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                            {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
            "buffers": [{"byteLength": 44,
                         "uri": "data:application/octet-stream;base64," + data}],
        }
        body = json.dumps(doc).encode()
        status, _, answer = self.assert_bounded(s, len(body), lambda: s.call(
            "POST", "/v1/assets?format=gltf&prefix=tiny", body,
            {"Content-Type": "model/gltf+json"}))
        self.assertEqual(status, 413, answer[:300])
        self.assertIn("declares 100000 primitives", json.loads(answer)["detail"])

    def test_bytes_after_a_pngs_end_are_not_kept(self):
        s = self.server()
        image = png(16, 16)
        junk = image + b"\0" * (20 * MIB)
        for n in range(3):
            edit = {"edits": [{"op": "add_texture", "id": f"t{n}",
                               "data": base64.b64encode(junk).decode()}]}
            body = json.dumps(edit).encode()
            status, _, answer = self.assert_bounded(
                s, len(body), lambda: s.call("POST", "/v1/edits", body))
            self.assertEqual(status, 200, answer[:300])
        # Each texture keeps its PNG, not the 20 MiB after it. (Resident memory is no measure of
        # that: the heap keeps the freed request buffers for the next request.)
        for n in range(3):
            doc = json.loads(s.call("GET", f"/v1/scene/textures/t{n}")[2])
            self.assertEqual(doc["encoded_bytes"], len(image))

    def test_a_json_batch_of_millions_of_clears_is_refused_while_parsing(self):
        s = self.server()
        body = b'{"edits": [' + b",".join([b'{"op": "clear"}'] * 3_000_000) + b"]}"
        status, _, answer = self.assert_bounded(s, len(body), lambda: s.call(
            "POST", "/v1/edits", body, {"Content-Type": "application/json"}))
        self.assertEqual(status, 413, answer[:300])
        self.assertIn("--max-json-values", json.loads(answer)["detail"])
        self.assertEqual(s.version(), 0)

    def test_a_snapshot_of_millions_of_clears_is_refused_from_its_count(self):
        s = self.server()
        body = snapshot_file(clears(5_000_000), 7)
        status, _, answer = self.assert_bounded(s, len(body), lambda: s.call(
            "POST", "/v1/scene/snapshot", body,
            {"Content-Type": "application/vnd.strata.snapshot"}))
        self.assertEqual(status, 413, answer[:300])
        self.assertIn("5000000 edits", json.loads(answer)["detail"])

    def test_stream_views_beyond_their_budget_are_refused_before_they_are_made(self):
        s = self.server("--max-stream-mb", "64")
        # A 2048x2048 view takes 32 MiB: two fit, the third is refused.
        opened = []
        for n in range(3):
            status, headers, _ = self.assert_bounded(s, 0, lambda: stream_head(
                s.port, f"/v1/stream?width=2048&height={2048 - n}&max_samples=1&fps=1", opened))
            self.assertEqual(status, 200 if n < 2 else 503)
        self.assertEqual(len(opened), 3)
        metrics = s.call("GET", "/metrics")[2].decode()
        self.assertIn("strata_stream_views_refused_total 1", metrics)


def stream_head(port, target, keep):
    """Opens `target` and reads its status line and headers; the socket stays open in `keep`."""
    import socket
    c = socket.create_connection(("127.0.0.1", port), timeout=30)
    c.sendall(f"GET {target} HTTP/1.1\r\nHost: t\r\n\r\n".encode())
    keep.append(c)
    data = b""
    while b"\r\n\r\n" not in data:
        more = c.recv(65536)
        if not more:
            break
        data += more
    head = data.split(b"\r\n\r\n")[0].decode()
    lines = head.split("\r\n")
    status = int(lines[0].split()[1])
    headers = dict(line.split(": ", 1) for line in lines[1:] if ": " in line)
    return status, headers, data


ASSIMP_MODELS = os.environ.get("STRATA_ASSIMP_MODELS_DIR", "/usr/share/assimp/models")


class TestModelsWalk(unittest.TestCase):
    """Every file of Debian's assimp-testmodels (invalid/ included) through POST /v1/assets of one
    server, its importer in the sandbox: each imports (and is then deleted as an asset) or is
    refused with a problem naming the file; the server lives, ends with an empty scene, and its
    resident memory after the walk stays within 128 MiB of what it held before."""

    def test_every_file_imports_or_is_refused_and_memory_comes_back(self):
        if not os.path.isdir(ASSIMP_MODELS):
            self.skipTest(ASSIMP_MODELS + " missing: install assimp-testmodels")
        s = Server()
        self.addCleanup(s.stop)
        # The formats POST /v1/assets reads, as its description lists them (and XGL's .zgl).
        description = json.loads(s.call("GET", "/v1/openapi.json")[2])
        parameters = description["paths"]["/v1/assets"]["post"]["parameters"]
        formats = next(p for p in parameters if p["name"] == "format")["schema"]["enum"]
        extensions = {"." + f for f in formats if f != "tar"} | {".zgl"}
        before = s.rss_mb()
        counts = {"imported": 0, "refused": 0, "not a format Strata reads": 0}
        for n, path in enumerate(sorted(p for p in glob.glob(ASSIMP_MODELS + "/**/*",
                                                             recursive=True)
                                        if os.path.isfile(p))):
            name = os.path.basename(path)
            with open(path, "rb") as f:
                body = f.read()
            query = urllib.parse.urlencode({"name": name, "prefix": f"w{n}"})
            status, _, answer = s.call("POST", "/v1/assets?" + query, body,
                                       {"Content-Type": "application/octet-stream"})
            rel = os.path.relpath(path, ASSIMP_MODELS)
            self.assertTrue(s.alive(), rel)
            if os.path.splitext(name)[1].lower() not in extensions:
                self.assertEqual(status, 400, rel)
                counts["not a format Strata reads"] += 1
                continue
            if status == 200:
                counts["imported"] += 1
                self.assertEqual(s.call("DELETE", f"/v1/assets/w{n}")[0], 200, rel)
                continue
            self.assertIn(status, (413, 422), f"{rel}: {answer[:300]!r}")
            problem = json.loads(answer)
            self.assertEqual(problem["file"], name, rel)
            counts["refused"] += 1
        scene = json.loads(s.call("GET", "/v1/scene")[2])
        self.assertEqual(scene["counts"]["meshes"], 0)
        self.assertEqual(scene["counts"]["instances"], 0)
        self.assertEqual(s.call("POST", "/v1/commit")[0], 200)
        after = s.rss_mb()
        print(f"\nassimp-testmodels over HTTP: {counts}; resident {before:.0f} MiB before, "
              f"{after:.0f} MiB after", file=sys.stderr)
        self.assertGreater(counts["imported"], 20)
        self.assertGreater(counts["refused"], 10)
        self.assertLess(after - before, 128, "resident memory did not come back after the walk")


if __name__ == "__main__":
    unittest.main()

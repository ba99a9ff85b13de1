"""A scene whose state after batch n is a pure function of n, for the durability suites: a test
that knows a server's version knows exactly what the scene must hold, and can check it.

Batch n (producing version n + 1 from an empty directory):
  - every MESH_EVERY-th batch adds mesh `mesh-n` (a few hundred to a few thousand vertices, so
    the journal grows fast and snapshots happen often);
  - adds instance `inst-n` of the newest mesh at (n, 0, 0);
  - moves `inst-(n-1)` to (n-1, 1, 0);
  - removes `inst-(n-KEEP)`.
"""

import random

MESH_EVERY = 4
KEEP = 8


def batch(n: int) -> dict:
    edits = []
    if n % MESH_EVERY == 0:
        rng = random.Random(n)
        vertices = rng.choice([60, 600, 3000])
        edits.append({"op": "add_mesh", "id": f"mesh-{n}",
                      "positions": [round(rng.uniform(-1, 1), 4) for _ in range(vertices * 3)],
                      "indices": list(range(vertices))})
    edits.append({"op": "add_instance", "id": f"inst-{n}", "mesh": f"mesh-{n - n % MESH_EVERY}",
                  "transform": {"translate": [n, 0, 0]}})
    if n >= 1:
        edits.append({"op": "set_transform", "instance": f"inst-{n - 1}",
                      "transform": {"translate": [n - 1, 1, 0]}})
    if n >= KEEP:
        edits.append({"op": "remove_instance", "instance": f"inst-{n - KEEP}"})
    return {"edits": edits}


def expected(version: int) -> dict:
    """What the scene holds at `version` (batches 0 .. version-1 applied)."""
    last = version - 1
    instances = {}
    for k in range(max(0, last - KEEP + 1), last + 1):
        instances[f"inst-{k}"] = [k, 0 if k == last else 1, 0]
    meshes = 0 if version == 0 else last // MESH_EVERY + 1
    return {"meshes": meshes, "instances": instances}


def check(server, version: int) -> str:
    """'' when `server` holds exactly expected(version), else what differs."""
    status, scene = server.json("GET", "/v1/scene")
    if status != 200:
        return f"GET /v1/scene answered {status}"
    if scene["version"] != version:
        return f"version {scene['version']}, expected {version}"
    want = expected(version)
    counts = scene["counts"]
    if counts["meshes"] != want["meshes"] or counts["instances"] != len(want["instances"]):
        return f"counts {counts}, expected {want['meshes']} meshes and " \
               f"{len(want['instances'])} instances"
    for iid, at in want["instances"].items():
        status, inst = server.json("GET", f"/v1/scene/instances/{iid}")
        if status != 200:
            return f"{iid} is missing ({status})"
        t = inst["transform"]
        if [t[3], t[7], t[11]] != at:
            return f"{iid} is at {[t[3], t[7], t[11]]}, expected {at}"
    gone = f"inst-{version - 1 - KEEP}"
    if version - 1 - KEEP >= 0 and server.json("GET", f"/v1/scene/instances/{gone}")[0] != 404:
        return f"{gone} should have been removed"
    return ""

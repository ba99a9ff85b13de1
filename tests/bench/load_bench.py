#!/usr/bin/python3
"""Loading many instances over HTTP (issue 24): first request to first frame, and the server's
resident memory per instance, with bulk ops against one add_instance edit per instance. Never
run by CTest.

    tests/bench/load_bench.py [BUILD_DIR] [--instances N] [--runs R] [--chunk C]
                              [--modes single,bulk,bulk_geometries] [--moves K]

Each run starts a fresh strata-server, adds one 224-triangle sphere (commits it, renders once),
then times, from the first edit request to the end of the first 64x36 frame:
  - "single": batches of 50,000 add_instance edits (one JSON object each, transform as 12
    numbers), the way in before bulk ops;
  - "bulk": add_instances edits of `--chunk` instances each (ids as a numbered range,
    transforms as base64 float32 3x4 rows);
  - "bulk_geometries": the same with the static TLAS tier kept as one Embree instance geometry
    per instance (--tlas-array-min-instances at its maximum), the way before instance arrays.
Request bodies are built before the clock starts (client-side generation excluded). Resident
memory (VmRSS of the server) is read after the sphere's frame, after the edits (the scene) and
after the frame (the TLAS too); bytes per instance are the growth divided by N, beside what
/v1/stats estimates (`memory_bytes.per_instance`). Each figure is
the median over R runs (default 3); modes alternate within a run. With --moves K, K commits that
each move one instance (set_transform) follow the first frame, and the commits' own times (the
report's `ms`) are summarised as p50 and p99, beside the p50 and p99 of each commit phase, the
dynamic TLAS tier's size and the number of commits that swapped in a finished merge. Needs numpy.
"""

import argparse
import base64
import http.client
import json
import os
import statistics
import sys
import time

import numpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path[:0] = [os.path.join(HERE, "..", "python")]

from strata_process import ServerProcess  # noqa: E402

MESH = {"edits": [{"op": "add_mesh", "id": "ball",
                   "shape": {"type": "sphere", "segments": 16}}]}


def transforms(n):
    xs = numpy.zeros((n, 3, 4), numpy.float32)
    xs[:, 0, 0] = xs[:, 1, 1] = xs[:, 2, 2] = 0.45
    i = numpy.arange(n)
    side = int(numpy.ceil(numpy.sqrt(n)))
    xs[:, 0, 3] = (i % side) * 1.2
    xs[:, 2, 3] = (i // side) * 1.2
    return xs


def single_bodies(xs):
    bodies = []
    rows = xs.reshape(len(xs), 12).tolist()
    for start in range(0, len(rows), 50_000):
        edits = [{"op": "add_instance", "id": f"b{k}", "mesh": "ball", "transform": rows[k]}
                 for k in range(start, min(start + 50_000, len(rows)))]
        bodies.append(json.dumps({"edits": edits}).encode())
    return bodies


def bulk_bodies(xs, chunk):
    bodies = []
    for start in range(0, len(xs), chunk):
        part = xs[start:start + chunk]
        op = {"op": "add_instances", "ids": {"prefix": "b", "first": start, "count": len(part)},
              "mesh": "ball",
              "transforms_b64": base64.b64encode(part.astype("<f4").tobytes()).decode()}
        bodies.append(json.dumps({"edits": [op]}).encode())
    return bodies


def post(conn, path, body):
    conn.request("POST", path, body=body, headers={"Content-Type": "application/json"})
    r = conn.getresponse()
    data = r.read()
    if r.status != 200:
        raise RuntimeError(f"{path}: {r.status} {data[:300]}")
    return data


def rss_bytes(pid):
    with open(f"/proc/{pid}/status", encoding="ascii") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise RuntimeError("no VmRSS")


def percentile(values, p):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(p / 100 * (len(ordered) - 1))))]


def move_one(conn, n, k):
    """K commits each moving one instance: the commits' reports."""
    reports = []
    for j in range(k):
        target = (j * 7919) % n
        edit = {"edits": [{"op": "set_transform", "instance": f"b{target}",
                           "transform": {"translate": [j % 50, 3, 0]}}]}
        post(conn, "/v1/edits", json.dumps(edit).encode())
        reports.append(json.loads(post(conn, "/v1/commit", b"{}")))
    return reports


def move_summary(reports):
    """p50 / p99 of the commits' times and of their phases, the dynamic tier's size, and how
    many commits swapped in a finished merge."""
    out = {"move_one_p50_ms": percentile([r["ms"] for r in reports], 50),
           "move_one_p99_ms": percentile([r["ms"] for r in reports], 99)}
    for phase in ("plan_ms", "blas_ms", "tlas_ms", "sync_ms"):
        values = [r["phases"][phase] for r in reports]
        out[f"move_{phase[:-3]}_p50_ms"] = percentile(values, 50)
        out[f"move_{phase[:-3]}_p99_ms"] = percentile(values, 99)
    dynamic = [r["tlas"]["dynamic_instances"] for r in reports]
    out["move_dynamic_p50"] = percentile(dynamic, 50)
    out["move_dynamic_max"] = max(dynamic)
    out["move_swaps"] = sum(1 for r in reports if r["tlas"]["merge"]["swapped"])
    return out


def load(binary, bodies, n, moves, server_args):
    server = ServerProcess(binary, ["--max-body-mb", "512",
                                    "--max-scene-instances", str(max(n + 1, 1 << 23))]
                           + server_args, check_answers=False)
    try:
        conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=600)
        post(conn, "/v1/edits", json.dumps(MESH).encode())
        post(conn, "/v1/render", b'{"width": 64, "height": 36}')
        base = rss_bytes(server.process.pid)
        t0 = time.perf_counter()
        for body in bodies:
            post(conn, "/v1/edits", body)
        t_edits = time.perf_counter() - t0
        scene = rss_bytes(server.process.pid)
        post(conn, "/v1/render", b'{"width": 64, "height": 36}')
        total = time.perf_counter() - t0
        frame = rss_bytes(server.process.pid)
        conn.request("GET", "/v1/stats")
        stats = json.loads(conn.getresponse().read())
        result = {"edits_s": t_edits, "first_frame_s": total,
                  "scene_bytes_per_instance": (scene - base) / n,
                  "bytes_per_instance": (frame - base) / n,
                  "stats_per_instance": stats["memory_bytes"]["per_instance"]}
        if moves:
            result.update(move_summary(move_one(conn, n, moves)))
        conn.close()
        return result
    finally:
        server.stop()


def main():
    p = argparse.ArgumentParser()
    p.add_argument("build", nargs="?", default="build")
    p.add_argument("--instances", type=int, default=1_000_000)
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--chunk", type=int, default=250_000)
    p.add_argument("--modes", default="single,bulk")
    p.add_argument("--moves", type=int, default=0)
    a = p.parse_args()
    binary = os.path.join(a.build, "server", "strata-server")
    xs = transforms(a.instances)
    make = {"single": single_bodies, "bulk": lambda x: bulk_bodies(x, a.chunk),
            "bulk_geometries": lambda x: bulk_bodies(x, a.chunk)}
    server_args = {"bulk_geometries": ["--tlas-array-min-instances", str(2**32 - 1)]}
    modes = {m: make[m](xs) for m in a.modes.split(",")}
    results = {m: [] for m in modes}
    for run in range(a.runs):
        for mode, bodies in modes.items():
            r = load(binary, bodies, a.instances, a.moves, server_args.get(mode, []))
            results[mode].append(r)
            print(f"run {run} {mode}: " + ", ".join(f"{k} {v:.3f}" for k, v in r.items()),
                  flush=True)
    print(f"\n{a.instances} instances, {os.cpu_count()} cpus, median of {a.runs} runs")
    print("| mode | edits (s) | first request to first frame (s) | scene bytes/instance "
          "| bytes/instance after the frame | /v1/stats per_instance "
          "| move one: p50 / p99 commit (ms) |")
    print("|---|---|---|---|---|---|---|")
    for mode, rs in results.items():
        med = {k: statistics.median(r[k] for r in rs) for k in rs[0]}
        moves = (f"{med['move_one_p50_ms']:.2f} / {med['move_one_p99_ms']:.2f}"
                 if "move_one_p50_ms" in med else "")
        print(f"| {mode} | {med['edits_s']:.2f} | {med['first_frame_s']:.2f} | "
              f"{med['scene_bytes_per_instance']:.0f} | {med['bytes_per_instance']:.0f} | "
              f"{med['stats_per_instance']:.0f} | {moves} |")


if __name__ == "__main__":
    main()

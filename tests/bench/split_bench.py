#!/usr/bin/python3
"""Split-render benchmark (issue 16, frames across replicas), on loopback: one client asking a
replica for frames of the demo scene with split=1 (the baseline: one process), 2 and 3, three
replicas following one Redis stream, each started with the other two as --peers. Never run by
CTest.

    tests/bench/split_bench.py [BUILD_DIR] [--runs N] [--seconds S] [--size WxH] [--spp N]

Each figure is the median over N runs (default 3) of frames per second over S seconds (default
4) of back-to-back GET /v1/render on one keep-alive connection; every run starts a fresh
redis-server and three fresh strata-server processes, and measures split=1, 2, 3 in turn. Each
split frame is checked against the split=1 frame (same bytes) once per run. Standard library only.
"""

import argparse
import http.client
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path[:0] = [os.path.join(HERE, "..", "server"), os.path.join(HERE, "..", "python")]

from redis_fixture import RedisProcess, free_ports  # noqa: E402
from strata_process import ServerProcess  # noqa: E402



def get(conn, path):
    conn.request("GET", path)
    r = conn.getresponse()
    body = r.read()
    if r.status != 200:
        raise RuntimeError(f"{path}: {r.status} {body[:200]}")
    return body, r.getheader("X-Strata-Split", "")


def frames_per_second(conn, path, seconds):
    n, t0 = 0, time.monotonic()
    while time.monotonic() - t0 < seconds:
        get(conn, path)
        n += 1
    return n / (time.monotonic() - t0)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("build", nargs="?", default="build")
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--seconds", type=float, default=4.0)
    p.add_argument("--size", default="640x360")
    p.add_argument("--spp", type=int, default=4)
    a = p.parse_args()
    binary = os.path.join(a.build, "server", "strata-server")
    w, h = (int(v) for v in a.size.split("x"))
    base = f"/v1/render?width={w}&height={h}&spp={a.spp}&min_version=1"
    results = {}
    for run in range(a.runs):
        redis = RedisProcess()
        ports = free_ports(3)
        urls = [f"http://127.0.0.1:{port}" for port in ports]
        servers = []
        try:
            for i, port in enumerate(ports):
                peers = ",".join(u for u in urls if u != urls[i])
                servers.append(ServerProcess(binary, ["--log", redis.url(f"split{run}"),
                                                      "--peers", peers, "--demo"], port=port))
            for s in servers:  # the demo scene applied and built everywhere
                get(http.client.HTTPConnection("127.0.0.1", s.port, timeout=60), base)
            conn = http.client.HTTPConnection("127.0.0.1", servers[0].port, timeout=60)
            single, _ = get(conn, base)
            for split in (1, 2, 3):
                path = base + (f"&split={split}" if split > 1 else "")
                frame, bands = get(conn, path)
                if frame != single:
                    raise RuntimeError(f"split={split} differs from split=1 ({bands})")
                if "local (" in bands:
                    raise RuntimeError(f"a peer did not serve its band: {bands}")
                name = f"frames/s {w}x{h} {a.spp} spp, split={split}"
                results.setdefault(name, []).append(frames_per_second(conn, path, a.seconds))
        finally:
            for s in servers:
                s.stop()
            redis.stop()
        print(f"run {run + 1}/{a.runs} done", file=sys.stderr)
    print(f"| measure | median of {a.runs} | runs |")
    print("| --- | --- | --- |")
    for name, values in results.items():
        print(f"| {name} | {statistics.median(values):.2f} | "
              + ", ".join(f"{v:.2f}" for v in values) + " |")


if __name__ == "__main__":
    main()

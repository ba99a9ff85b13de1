#!/usr/bin/python3
"""Replica benchmark (issue 16), on loopback: edit throughput and apply lag with 1 and 3 replicas
following one Redis stream, and render throughput over 1 and 3 replicas. Never run by CTest.

    tests/bench/replica_bench.py [BUILD_DIR] [--runs N] [--seconds S]

Each figure is the median over N runs (default 3); a run starts a fresh redis-server (AOF on,
appendfsync always, in a temporary directory) and fresh strata-server processes. The baseline
(`local`) is one server without --log, measured in the same invocation. Results go to stdout as
a Markdown table. Standard library only; the clients are Python threads on keep-alive
connections, so on a small machine they share the cores with the servers and Redis.
"""

import argparse
import http.client
import json
import os
import statistics
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path[:0] = [os.path.join(HERE, "..", "server"), os.path.join(HERE, "..", "python")]

from redis_fixture import RedisProcess  # noqa: E402
from strata_process import ServerProcess  # noqa: E402


class Client:
    def __init__(self, server):
        self.conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=60)

    def request(self, method, path, body=None, headers=None):
        data = json.dumps(body).encode() if body is not None else None
        self.conn.request(method, path, body=data, headers=headers or {})
        r = self.conn.getresponse()
        return r.status, r.read()


def start(binary, count, redis, stream, extra=()):
    args = ["--threads", "8"] + list(extra)
    if redis is not None:
        args += ["--log", redis.url(stream)]
    return [ServerProcess(binary, args) for _ in range(count)]


def edit_throughput(servers, clients, seconds):
    """Batches/s with `clients` threads, client k posting to servers[k % len(servers)]."""
    done, stop, failed = [0] * clients, threading.Event(), []
    tag = f"{clients}-{time.monotonic_ns()}"

    def run(k):
        c = Client(servers[k % len(servers)])
        n = 0
        while not stop.is_set():
            status, body = c.request("POST", "/v1/edits",
                                     {"edits": [{"op": "add_material", "id": f"c{tag}-{k}-{n}"}]})
            if status != 200:
                failed.append(f"{status} {body[:200]}")
                break
            n += 1
        done[k] = n

    threads = [threading.Thread(target=run, args=(k,)) for k in range(clients)]
    t0 = time.monotonic()
    for t in threads:
        t.start()
    time.sleep(seconds)
    stop.set()
    for t in threads:
        t.join()
    if failed:
        raise RuntimeError(failed[0])
    return sum(done) / (time.monotonic() - t0)


def apply_lag(servers, samples):
    """Median and p90 (ms) of: POST on servers[0] answered 200 -> GET min_version on servers[1]
    answered 200, minus the median of the same GET without min_version (the HTTP round trip)."""
    writer, reader = Client(servers[0]), Client(servers[-1])
    plain, lagged = [], []
    for n in range(samples):
        status, body = writer.request("POST", "/v1/edits",
                                      {"edits": [{"op": "add_material", "id": f"lag-{n}"}]})
        version = json.loads(body)["version"]
        t0 = time.perf_counter()
        status, _ = reader.request("GET", f"/v1/scene?min_version={version}")
        lagged.append((time.perf_counter() - t0) * 1e3)
        assert status == 200
        t0 = time.perf_counter()
        reader.request("GET", "/v1/scene")
        plain.append((time.perf_counter() - t0) * 1e3)
    base = statistics.median(plain)
    lagged.sort()
    return lagged[len(lagged) // 2] - base, lagged[int(len(lagged) * 0.9)] - base, base


def render_throughput(servers, clients, seconds, size):
    frames, stop = [0] * clients, threading.Event()

    def run(k):
        c = Client(servers[k % len(servers)])
        n = 0
        while not stop.is_set():
            status, body = c.request("GET", f"/v1/render?width={size[0]}&height={size[1]}")
            if status != 200:
                raise RuntimeError(f"{status} {body[:200]}")
            n += 1
        frames[k] = n

    threads = [threading.Thread(target=run, args=(k,)) for k in range(clients)]
    t0 = time.monotonic()
    for t in threads:
        t.start()
    time.sleep(seconds)
    stop.set()
    for t in threads:
        t.join()
    return sum(frames) / (time.monotonic() - t0)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("build", nargs="?", default="build")
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--seconds", type=float, default=4.0)
    a = p.parse_args()
    binary = os.path.join(a.build, "server", "strata-server")
    results = {}

    def record(name, value):
        results.setdefault(name, []).append(value)

    for run in range(a.runs):
        for replicas in (0, 1, 3):
            redis = RedisProcess() if replicas else None
            servers = start(binary, max(replicas, 1), redis, f"bench{run}", ["--demo"])
            try:
                label = "local (no --log)" if replicas == 0 else f"{replicas} replica(s)"
                # Let the demo scene land and be built once everywhere.
                for s in servers:
                    Client(s).request("GET", "/v1/render?width=64&height=48&min_version=1")
                for clients in (1, 4):
                    record(f"edits/s, {clients} client(s), {label}",
                           edit_throughput(servers, clients, a.seconds))
                if replicas == 3:
                    med, p90, base = apply_lag(servers, 200)
                    record("apply lag ms (median), replica 0 -> replica 2", med)
                    record("apply lag ms (p90), replica 0 -> replica 2", p90)
                    record("plain GET /v1/scene ms (the subtracted round trip)", base)
                if replicas != 1:
                    record(f"renders/s 320x240 1 spp, 3 clients, {label}",
                           render_throughput(servers, 3, a.seconds, (320, 240)))
            finally:
                for s in servers:
                    s.stop()
                if redis:
                    redis.stop()
        print(f"run {run + 1}/{a.runs} done", file=sys.stderr)

    print(f"| measure | median of {a.runs} | runs |")
    print("| --- | --- | --- |")
    for name, values in results.items():
        print(f"| {name} | {statistics.median(values):.2f} | "
              + ", ".join(f"{v:.2f}" for v in values) + " |")


if __name__ == "__main__":
    main()

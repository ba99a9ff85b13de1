"""docker/compose.replicas.yml run for real without Docker (issue 16): the redis service's own
command (AOF on, fsync always), three strata-server processes with exactly the replica services'
environment on top of the image's ENV (docker/Dockerfile), and Debian's nginx with
docker/nginx-replicas.conf in front. Only what a container supplies is translated: service
hostnames and container ports become free loopback ports, volumes and secrets become temporary
files; every other flag, variable and nginx directive is used as written, so a mistake in either
file fails here. Through nginx: edits, read-your-writes with min_version and X-Strata-Min-Version,
PNG renders equal to each replica's own, reads and renders spread over all three replicas (each
replica's /metrics), nginx still serving reads and writes after a replica is SIGKILLed, a write
answered 503 not sent on to another replica, the viewer's streams arriving unbuffered, and 160
viewer streams held on one replica.
Skipped, saying so, only where redis-server or nginx is not installed
(scripts/install-deps.sh installs both).
"""

import importlib.util
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import tempfile
import time
import unittest
import urllib.error
import urllib.request

import yaml

import durable_scene
from hostile import SERVER, Server
from redis_fixture import REDIS_SERVER, RedisProcess, free_ports

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
DOCKER = os.path.join(ROOT, "docker")
COMPOSE = os.path.join(DOCKER, "compose.replicas.yml")
NGINX = shutil.which("nginx") or next(
    (p for p in ("/usr/sbin/nginx",) if os.access(p, os.X_OK)), None)
REPLICAS = ("strata-1", "strata-2", "strata-3")
RENDER = "/v1/render?width=64&height=48&spp=2"



def image_spec() -> dict:
    """The runtime stage of docker/Dockerfile, read by scripts/docker-spec.py (as CI reads it)."""
    spec = importlib.util.spec_from_file_location(
        "docker_spec", os.path.join(ROOT, "scripts", "docker-spec.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    problems = []
    stage = module.read_stage(os.path.join(DOCKER, "Dockerfile"), problems)
    if problems:
        raise AssertionError("docker/Dockerfile: " + "; ".join(problems))
    return stage


def inline_cmd(service: dict, name: str) -> list:
    """The exec-form CMD of a service built from a dockerfile_inline."""
    inline = service.get("build", {}).get("dockerfile_inline", "")
    lines = [l.strip() for l in inline.splitlines() if l.strip().startswith("CMD ")]
    if len(lines) != 1:
        raise AssertionError(f"service {name}: expected one exec-form CMD in its dockerfile_inline")
    return json.loads(lines[0][4:])


def flag_value(args: list, flag: str):
    return args[args.index(flag) + 1] if flag in args else None


class Endpoint:
    """HTTP through one port (nginx or a replica), with the bearer token; `min_version` is sent as
    X-Strata-Min-Version on every request (durable_scene.check reads through it)."""

    def __init__(self, port: int, token: str, min_version=None):
        self.port, self.token, self.min_version = port, token, min_version

    def call(self, method, path, body=None, headers=None, timeout=30.0):
        h = {"Authorization": f"Bearer {self.token}"} if self.token else {}
        if self.min_version is not None:
            h["X-Strata-Min-Version"] = str(self.min_version)
        h.update(headers or {})
        data = None if body is None else json.dumps(body).encode()
        req = urllib.request.Request(f"http://127.0.0.1:{self.port}{path}", data=data,
                                     method=method, headers=h)
        try:
            with urllib.request.urlopen(req, timeout=timeout) as r:
                return r.status, dict(r.headers), r.read()
        except urllib.error.HTTPError as e:
            return e.code, dict(e.headers), e.read()

    def json(self, method, path, body=None, headers=None):
        status, headers, data = self.call(method, path, body, headers)
        if "json" not in headers.get("Content-Type", ""):  # nginx's own error pages
            return status, {"body": data.decode(errors="replace")[:300]}
        return status, json.loads(data) if data else {}


@unittest.skipIf(REDIS_SERVER is None,
                 "redis-server is not installed (scripts/install-deps.sh installs it)")
@unittest.skipIf(NGINX is None, "nginx is not installed (scripts/install-deps.sh installs it)")
class ComposeTopology(unittest.TestCase):
    def setUp(self):
        with open(COMPOSE, encoding="utf-8") as f:
            self.compose = yaml.safe_load(f)
        services = self.compose["services"]
        missing = [s for s in ("redis", "nginx") + REPLICAS if s not in services]
        self.assertEqual(missing, [], f"{COMPOSE} lacks services")
        self.tmp = tempfile.mkdtemp(prefix="strata-compose-")
        os.chmod(self.tmp, 0o755)  # nginx workers (nobody when run as root) write temp files
        self.addCleanup(shutil.rmtree, self.tmp, True)
        self.token = "compose-" + os.urandom(16).hex()
        self.image = image_spec()
        self.start_redis(services["redis"])
        # Container address "service:port" -> loopback address, for every server in the topology.
        self.addresses = {f"redis:{self.redis_container_port}": f"127.0.0.1:{self.redis.port}"}
        ports = free_ports(len(REPLICAS))
        self.replica_ports = dict(zip(REPLICAS, ports))
        for name in REPLICAS:
            env = self.container_env(services[name])
            self.addresses[f"{name}:{env['STRATA_PORT']}"] = f"127.0.0.1:{self.replica_ports[name]}"
        self.env_of = {}  # replica -> the environment it was started with
        self.replicas = {name: self.start_replica(name, services[name]) for name in REPLICAS}
        # Cleanups run last-first: all three begin their graceful stop at once.
        self.addCleanup(lambda: [r.signal(signal.SIGTERM) for r in self.replicas.values()
                                 if r.alive()])
        self.nginx = Endpoint(self.start_nginx(services["nginx"]), self.token)

    # --- the topology ----------------------------------------------------------------------

    def start_redis(self, service):
        args = inline_cmd(service, "redis")
        self.assertEqual(os.path.basename(args[0]), "redis-server")
        args = args[1:]
        self.assertEqual(flag_value(args, "--appendonly"), "yes", "the log must be in the AOF")
        self.assertEqual(flag_value(args, "--appendfsync"), "always")
        self.redis_container_port = flag_value(args, "--port") or "6379"
        volumes = [str(v).split(":") for v in service.get("volumes", [])]
        data_dir = flag_value(args, "--dir")
        self.assertIn(data_dir, [v[1] for v in volumes if len(v) >= 2],
                      "redis --dir is not on a volume: the log would die with the container")
        redis_dir = os.path.join(self.tmp, "redis")
        os.mkdir(redis_dir)
        translated, skip = [], False
        for i, a in enumerate(args):
            if skip:
                skip = False
                continue
            if a == "--port":  # the fixture adds the loopback port
                skip = True
                continue
            if i > 0 and args[i - 1] == "--bind" and a == "0.0.0.0":
                a = "127.0.0.1"
            elif a == data_dir:
                a = redis_dir
            translated.append(a)
        self.redis = RedisProcess(config=translated)
        self.addCleanup(self.redis.stop)

    def container_env(self, service) -> dict:
        """What a replica's container has: the image's ENV, then the service's environment."""
        env = {k: v for k, v in self.image["env"].items() if k != "PATH"}
        env.update({k: str(v) for k, v in (service.get("environment") or {}).items()})
        return env

    def start_replica(self, name, service):
        env = self.container_env(service)
        container_port = env["STRATA_PORT"]
        data = os.path.join(self.tmp, name + "-data")
        os.mkdir(data)
        secrets = {}
        for secret in service.get("secrets", []):
            source = self.compose.get("secrets", {}).get(secret, {})
            self.assertIn("file", source, f"secret {secret} has no file")
            path = os.path.join(self.tmp, "secret-" + secret)
            with open(path, "w", encoding="utf-8") as f:
                f.write(self.token + "\n")
            secrets["/run/secrets/" + secret] = path
        volume = self.image["volume"]

        def translate(value: str) -> str:
            """Container paths and addresses -> this machine's; anything else as written."""
            if value == volume or value.startswith(volume + "/"):
                value = data + value[len(volume):]
            value = secrets.get(value, value)
            for address, loopback in self.addresses.items():
                value = value.replace(address, loopback)
            return value

        for key, value in list(env.items()):
            if key == "STRATA_HOST" and value == "0.0.0.0":
                env[key] = "127.0.0.1"
            elif key == "STRATA_PORT" and value == container_port:
                env[key] = str(self.replica_ports[name])
            else:
                env[key] = translate(value)
        command = service.get("command") or []
        self.assertIsInstance(command, list, f"{name}: write command in exec form")
        command = [translate(str(a)) for a in command]
        self.assertEqual([os.path.basename(a) for a in self.image["entrypoint"]],
                         ["strata-server"])
        self.env_of[name] = env
        server = Server(command, env=env, port=self.replica_ports[name], default_flags=False,
                        wait_ready=True)
        self.addCleanup(server.stop)
        return server

    def start_nginx(self, service) -> int:
        """nginx as the nginx service runs it, on a loopback port; returns the port."""
        cmd = inline_cmd(service, "nginx")
        self.assertEqual(cmd[0], "nginx")
        mounts = [str(v).split(":") for v in service.get("volumes", [])]
        confs = [m for m in mounts if m[1].startswith("/etc/nginx/conf.d/")]
        self.assertEqual(len(confs), 1, "expected one file mounted into /etc/nginx/conf.d/")
        source, target = confs[0][0], confs[0][1]
        # Debian's nginx.conf includes conf.d/*.conf inside its http block.
        self.assertTrue(target.endswith(".conf"), f"{target}: Debian's nginx.conf skips it")
        with open(os.path.join(DOCKER, source), encoding="utf-8") as f:
            conf = f.read()
        published = [str(p).rsplit(":", 1)[-1] for p in service.get("ports", [])]
        self.assertEqual(len(published), 1, "nginx should publish one port")
        port = free_ports(1)[0]
        conf = self.rewrite_nginx(conf, published[0], port)
        conf_path = os.path.join(self.tmp, os.path.basename(target))
        with open(conf_path, "w", encoding="utf-8") as f:
            f.write(conf)
        wrapper = os.path.join(self.tmp, "nginx.conf")
        temp = {k: os.path.join(self.tmp, k) for k in ("body", "proxy", "fastcgi", "uwsgi", "scgi")}
        with open(wrapper, "w", encoding="utf-8") as f:
            f.write("events {}\nhttp {\n"
                    f"    access_log {self.tmp}/access.log;\n"
                    f"    client_body_temp_path {temp['body']};\n"
                    f"    proxy_temp_path {temp['proxy']};\n"
                    f"    fastcgi_temp_path {temp['fastcgi']};\n"
                    f"    uwsgi_temp_path {temp['uwsgi']};\n"
                    f"    scgi_temp_path {temp['scgi']};\n"
                    f"    include {conf_path};\n}}\n")
        self.nginx_log = open(os.path.join(self.tmp, "nginx.log"), "wb")
        self.addCleanup(self.nginx_log.close)
        # The image's CMD sets "daemon off;"; the pid file and error log move out of /run and
        # /var/log.
        globals_ = f"{cmd[cmd.index('-g') + 1]} pid {self.tmp}/nginx.pid; error_log stderr;"
        process = subprocess.Popen([NGINX, "-e", "stderr", "-p", self.tmp, "-c", wrapper,
                                    "-g", globals_], stdout=self.nginx_log,
                                   stderr=subprocess.STDOUT)
        self.nginx_process = process

        def stop():
            if process.poll() is None:
                process.send_signal(signal.SIGQUIT)  # graceful
                try:
                    process.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait()
        self.addCleanup(stop)
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            if process.poll() is not None:
                self.fail("nginx exited: " + self.nginx_output())
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                return port
            except OSError:
                time.sleep(0.02)
        self.fail("nginx did not listen: " + self.nginx_output())

    def nginx_output(self) -> str:
        self.nginx_log.flush()
        with open(self.nginx_log.name, encoding="utf-8", errors="replace") as f:
            return f.read()

    def rewrite_nginx(self, conf: str, published: str, port: int) -> str:
        """Upstream servers -> the replicas' loopback addresses, listen -> the loopback port.
        Everything else stays as written."""
        upstreams = list(re.finditer(r"upstream\s+\S+\s*\{(.*?)\}", conf, re.S))
        if not upstreams:
            raise AssertionError("docker/nginx-replicas.conf has no upstream block to rewrite")
        out, at = [], 0
        for block in upstreams:
            out.append(conf[at:block.start(1)])
            body = block.group(1)
            servers = re.findall(r"^\s*server\s+(\S+?)[\s;]", body, re.M)
            self.assertEqual(sorted(servers), sorted(a for a in self.addresses
                                                     if not a.startswith("redis:")),
                             "the upstream must list every replica at its container port")
            body = re.sub(r"^(\s*server\s+)(\S+?)([\s;])",
                          lambda m: m.group(1) + self.addresses[m.group(2)] + m.group(3),
                          body, flags=re.M)
            out.append(body)
            at = block.end(1)
        out.append(conf[at:])
        conf = "".join(out)
        listens = re.findall(r"^\s*listen\s+([^;]+);", conf, re.M)
        self.assertEqual(listens, [published],
                         "nginx must listen on the container port the service publishes")
        return re.sub(r"^(\s*listen\s+)[^;]+;", rf"\g<1>127.0.0.1:{port};", conf, flags=re.M)

    # --- helpers -----------------------------------------------------------------------------

    def direct(self, name, min_version=None) -> Endpoint:
        return Endpoint(self.replicas[name].port, self.token, min_version)

    def responses(self, code_class: str) -> dict:
        """name -> strata_http_responses_total{code=code_class} from each live replica."""
        out = {}
        for name, replica in self.replicas.items():
            if replica.alive():
                text = self.direct(name).call("GET", "/metrics")[2].decode()
                out[name] = int(re.search(r'^strata_http_responses_total\{code="%s"\} (\d+)'
                                          % code_class, text, re.M).group(1))
        return out

    def metrics(self) -> dict:
        """name -> (renders, 2xx responses) from each replica's own /metrics."""
        out = {}
        for name in self.replicas:
            if not self.replicas[name].alive():
                continue
            status, _, body = self.direct(name).call("GET", "/metrics")
            self.assertEqual(status, 200)
            text = body.decode()
            renders = re.search(r"^strata_renders_total (\d+)", text, re.M)
            ok = re.search(r'^strata_http_responses_total\{code="2xx"\} (\d+)', text, re.M)
            out[name] = (int(renders.group(1)), int(ok.group(1)))
        return out

    def post_batches(self, first, count) -> int:
        for n in range(first, first + count):
            status, answer = self.nginx.json("POST", "/v1/edits", durable_scene.batch(n))
            self.assertEqual(status, 200, answer)
            self.assertEqual(answer["version"], n + 1)
        return first + count

    # --- tests ---------------------------------------------------------------------------------

    def test_the_replicas_pass_the_compose_healthcheck_and_nginx_passes_the_token_through(self):
        test = self.compose["services"]["strata-1"]["healthcheck"]["test"]
        self.assertEqual(test[:2], ["CMD", "strata-server"])
        for name in REPLICAS:
            result = subprocess.run([SERVER] + test[2:], env=dict(os.environ, **self.env_of[name]),
                                    capture_output=True, text=True, timeout=10)
            self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        self.assertEqual(Endpoint(self.nginx.port, None).call("GET", "/readyz")[0], 200)
        self.assertEqual(Endpoint(self.nginx.port, None).call("GET", "/v1/scene")[0], 401)
        self.assertEqual(Endpoint(self.nginx.port, "wrong").call("GET", "/v1/scene")[0], 401)
        self.assertEqual(self.nginx.call("GET", "/v1/scene")[0], 200)

    def test_edits_through_nginx_read_back_and_render_as_each_replica_renders_them(self):
        version = self.post_batches(0, 12)
        stream = self.env_of["strata-1"]["STRATA_LOG"].rsplit("/", 1)[1]
        self.assertEqual(int(self.redis.command("GET", stream + ":version")), version)
        for _ in range(6):
            # Read-your-writes through whichever replica nginx picks.
            self.assertEqual(durable_scene.check(Endpoint(self.nginx.port, self.token, version),
                                                 version), "")
            status, scene = self.nginx.json("GET", f"/v1/scene?min_version={version}")
            self.assertEqual((status, scene["version"]), (200, version))
        frames = []
        for k in range(6):
            if k % 2:
                status, headers, frame = self.nginx.call("GET", RENDER,
                                                         headers={"X-Strata-Min-Version":
                                                                  str(version)})
            else:
                status, headers, frame = self.nginx.call("GET",
                                                         f"{RENDER}&min_version={version}")
            self.assertEqual(status, 200, frame[:300])
            self.assertTrue(frame.startswith(b"\x89PNG\r\n\x1a\n"))
            frames.append(frame)
        for name in REPLICAS:
            status, _, own = self.direct(name).call("GET", f"{RENDER}&min_version={version}")
            self.assertEqual(status, 200, own[:300])
            for frame in frames:
                self.assertEqual(frame, own, f"a frame through nginx differs from {name}'s")

    def test_reads_and_renders_through_nginx_reach_all_three_replicas(self):
        version = self.post_batches(0, 4)
        before = self.metrics()
        for _ in range(9):
            self.assertEqual(self.nginx.call("GET", f"{RENDER}&min_version={version}")[0], 200)
            self.assertEqual(self.nginx.call("GET", f"/v1/scene?min_version={version}")[0], 200)
        after = self.metrics()
        for name in REPLICAS:
            renders = after[name][0] - before[name][0]
            # 2xx answers besides the renders, less at most two for the /metrics answers.
            scene_reads = after[name][1] - before[name][1] - renders - 2
            self.assertGreater(renders, 0, f"{name} rendered nothing: {before} -> {after}")
            self.assertGreater(scene_reads, 0, f"{name} served no scene read: {before} -> {after}")
        self.assertEqual(sum(after[n][0] - before[n][0] for n in REPLICAS), 9)

    def test_a_replica_killed_leaves_nginx_serving_reads_renders_and_writes(self):
        version = self.post_batches(0, 4)
        self.replicas["strata-2"].kill()
        # Writes first, before reads have made nginx mark the dead replica down: a write that
        # finds it is passed on (nothing was sent to it, so it cannot have been appended).
        version = self.post_batches(version, 6)
        for _ in range(9):
            status, _, frame = self.nginx.call("GET", f"{RENDER}&min_version={version}")
            self.assertEqual(status, 200, frame[:300])
            self.assertEqual(durable_scene.check(Endpoint(self.nginx.port, self.token, version),
                                                 version), "")
        for name in ("strata-1", "strata-3"):
            self.assertEqual(durable_scene.check(self.direct(name, version), version), "")
        # nginx did try the dead replica (else this proved nothing) and passed on.
        self.assertIn("Connection refused", self.nginx_output())

    def test_a_write_answered_503_is_not_sent_to_another_replica(self):
        version = self.post_batches(0, 2)
        self.redis.kill()  # every replica now answers a write 503: the log is unreachable
        before = self.responses("5xx")
        status, answer = self.nginx.json("POST", "/v1/edits", durable_scene.batch(version))
        self.assertEqual(status, 503, answer)
        self.assertEqual(answer.get("status"), 503, answer)  # the replica's problem, not nginx's
        after = self.responses("5xx")
        self.assertEqual(sum(after[n] - before[n] for n in REPLICAS), 1,
                         f"nginx sent one write to several replicas: {before} -> {after}")
        # Reads of what was applied still work through nginx.
        self.assertEqual(durable_scene.check(Endpoint(self.nginx.port, self.token, version),
                                             version), "")

    def read_until(self, sock, done, seconds=3.0) -> bytes:
        got, deadline = b"", time.monotonic() + seconds
        sock.settimeout(0.2)
        while not done(got) and time.monotonic() < deadline:
            try:
                chunk = sock.recv(65536)
            except socket.timeout:
                continue
            if not chunk:
                break
            got += chunk
        return got

    def open_stream(self, target):
        sock = socket.create_connection(("127.0.0.1", self.nginx.port), timeout=5)
        self.addCleanup(sock.close)
        sock.sendall(f"GET {target} HTTP/1.1\r\nHost: x\r\n"
                     f"Authorization: Bearer {self.token}\r\n\r\n".encode())
        return sock

    def test_the_viewer_streams_reach_the_browser_through_nginx_as_they_are_sent(self):
        events = self.open_stream("/v1/events")
        got = self.read_until(events, lambda b: b"event: hello" in b)
        self.assertIn(b"event: hello", got, f"nginx held the first event back: {got!r}")
        self.post_batches(0, 1)
        for name in REPLICAS:  # a commit on whichever replica holds the stream
            self.assertEqual(self.direct(name).call("GET", f"{RENDER}&min_version=1")[0], 200)
        got = self.read_until(events, lambda b: b"event: commit" in b)
        self.assertIn(b"event: commit", got, f"nginx held the commit event back: {got!r}")
        # A whole frame (JPEG start to end marker) arrives without waiting for the next one.
        frames = self.open_stream("/v1/stream?width=64&height=48")
        got = self.read_until(frames, lambda b: b"\xff\xd8" in b and b"\xff\xd9" in b)
        self.assertIn(b"multipart/x-mixed-replace", got)
        self.assertIn(b"\xff\xd9", got[got.find(b"\xff\xd8"):] if b"\xff\xd8" in got else b"",
                      "nginx held the tail of the first frame back")

    def test_one_replica_holds_more_viewers_through_nginx_than_one_client_may_open_directly(self):
        # Behind nginx every connection comes from nginx's address: the per-client connection
        # limit must allow a replica's share of the viewers' long-lived streams.
        limit = int(self.env_of["strata-1"].get("STRATA_MAX_CONNECTIONS_PER_CLIENT", "128"))
        self.replicas["strata-2"].kill()
        self.replicas["strata-3"].kill()
        viewers = 160
        streams = [self.open_stream("/v1/events") for _ in range(viewers)]
        held = [self.read_until(s, lambda b: b"event: hello" in b or b"\r\n\r\n" in b
                                and not b.startswith(b"HTTP/1.1 200")) for s in streams]
        refused = [h.split(b"\r\n", 1)[0] for h in held if b"event: hello" not in h]
        self.assertEqual(refused, [], f"{len(refused)} of {viewers} viewers refused "
                                      f"(STRATA_MAX_CONNECTIONS_PER_CLIENT {limit})")


if __name__ == "__main__":
    unittest.main()

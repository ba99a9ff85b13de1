#!/usr/bin/python3
"""Reads the runtime stage of docker/Dockerfile and checks docker/docker-compose.yml against it.

    scripts/docker-spec.py DOCKERFILE COMPOSE_FILE

Prints shell assignments (for eval) describing the final stage: RT_ENV (an array of NAME=value),
RT_USER, RT_UID, RT_GID, RT_WORKDIR, RT_PORT, RT_VOLUME, RT_PREFIX, RT_ENTRYPOINT and
RT_HEALTHCHECK (arrays). scripts/check-docker.sh runs that stage's steps in a Debian root with
these values, so the check follows the Dockerfile instead of repeating it. Exits 1, naming every
problem, when the stage or the compose example is not what the image promises: exec-form
ENTRYPOINT and HEALTHCHECK, STOPSIGNAL SIGTERM, a numeric USER, EXPOSE and VOLUME equal to
STRATA_PORT and STRATA_DATA, and a compose service that agrees with all of that.
"""
import json
import shlex
import sys

import yaml


def instructions(path):
    """The Dockerfile's instructions as (KEYWORD, rest) pairs, continuation lines joined."""
    out, pending = [], ""
    with open(path, encoding="utf-8") as f:
        for raw in f:
            line = raw.rstrip("\n")
            if line.lstrip().startswith("#") or (not line.strip() and not pending):
                continue
            if line.endswith("\\"):
                pending += line[:-1] + " "
                continue
            line = (pending + line).strip()
            pending = ""
            if line:
                keyword, _, rest = line.partition(" ")
                out.append((keyword.upper(), rest.strip()))
    return out


def final_stage(path):
    stages = [[]]
    for keyword, rest in instructions(path):
        if keyword == "FROM":
            stages.append([])
        stages[-1].append((keyword, rest))
    return stages[-1]


def exec_form(text, what, problems):
    try:
        value = json.loads(text)
    except json.JSONDecodeError:
        value = None
    if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
        problems.append(f"{what} must be in exec form (a JSON array of strings): {text}")
        return []
    return value


def read_stage(path, problems):
    spec = {"env": {}, "healthcheck": [], "entrypoint": [], "prefix": None}
    for keyword, rest in final_stage(path):
        if keyword == "ENV":
            for pair in shlex.split(rest):
                name, eq, value = pair.partition("=")
                if not eq:
                    problems.append(f"ENV {rest}: write ENV NAME=value")
                spec["env"][name] = value
        elif keyword in ("USER", "WORKDIR", "STOPSIGNAL"):
            spec[keyword.lower()] = rest
        elif keyword == "EXPOSE":
            spec["expose"] = rest.removesuffix("/tcp")
        elif keyword == "VOLUME":
            volumes = exec_form(rest, "VOLUME", problems) if rest.startswith("[") else rest.split()
            if len(volumes) != 1:
                problems.append(f"VOLUME {rest}: expected exactly one volume")
            spec["volume"] = volumes[0] if volumes else ""
        elif keyword == "ENTRYPOINT":
            spec["entrypoint"] = exec_form(rest, "ENTRYPOINT", problems)
        elif keyword == "HEALTHCHECK":
            command = rest
            while command.startswith("--"):  # --interval=10s and the like
                command = command.split(None, 1)[1] if " " in command else ""
            head, _, args = command.partition(" ")
            if head != "CMD":
                problems.append(f"HEALTHCHECK needs CMD: {rest}")
            else:
                spec["healthcheck"] = exec_form(args.strip(), "HEALTHCHECK CMD", problems)
        elif keyword == "COPY" and rest.startswith("--from=build "):
            src, dst = rest.split()[1:3]
            if src.rstrip("/") != dst.rstrip("/"):
                problems.append(f"COPY --from=build copies {src} to a different path {dst}")
            spec["prefix"] = dst.rstrip("/")
    return spec


def check_stage(spec, problems):
    env = spec["env"]
    user = spec.get("user", "")
    uid, _, gid = user.partition(":")
    if not (uid.isdigit() and gid.isdigit()) or uid == "0":
        problems.append(f"USER must be a numeric, non-root uid:gid, not '{user}'")
    if spec.get("stopsignal") != "SIGTERM":
        problems.append("STOPSIGNAL must be SIGTERM (what strata-server finishes requests on)")
    if spec.get("expose") != env.get("STRATA_PORT"):
        problems.append(f"EXPOSE {spec.get('expose')} differs from STRATA_PORT")
    volume = spec.get("volume", "")
    if volume != env.get("STRATA_DATA"):
        problems.append(f"VOLUME {volume} differs from STRATA_DATA (the --data directory)")
    if not spec["prefix"]:
        problems.append("no COPY --from=build of the installed tree")
    if not spec["entrypoint"] or not spec["healthcheck"]:
        problems.append("ENTRYPOINT and HEALTHCHECK are both required")
    return uid, gid


def check_compose(path, spec, problems):
    with open(path, encoding="utf-8") as f:
        doc = yaml.safe_load(f)
    services = doc.get("services", {})
    if len(services) != 1:
        problems.append(f"{path}: expected one service")
        return
    name, svc = next(iter(services.items()))
    where = f"{path}: service {name}"
    build = svc.get("build", {})
    if build.get("context") != ".." or build.get("dockerfile") != "docker/Dockerfile":
        problems.append(f"{where}: build must be context '..' with dockerfile docker/Dockerfile")
    ports = [str(p).rsplit(":", 1)[-1] for p in svc.get("ports", [])]
    if ports != [spec.get("expose")]:
        problems.append(f"{where}: ports must publish the container port {spec.get('expose')}")
    targets = [str(v).split(":")[1] for v in svc.get("volumes", []) if ":" in str(v)]
    if spec.get("volume") not in targets:
        problems.append(f"{where}: no volume mounted at {spec.get('volume')}")
    test = svc.get("healthcheck", {}).get("test")
    if test != ["CMD"] + spec["healthcheck"]:
        problems.append(f"{where}: healthcheck test {test} differs from the image's HEALTHCHECK")
    env = svc.get("environment", {})
    token_file = env.get("STRATA_TOKEN_FILE", "")
    secret = token_file.removeprefix("/run/secrets/")
    if token_file == secret or secret not in svc.get("secrets", []):
        problems.append(f"{where}: STRATA_TOKEN_FILE must name one of its /run/secrets/")
    elif "file" not in doc.get("secrets", {}).get(secret, {}):
        problems.append(f"{path}: secret {secret} needs a file")
    if not svc.get("restart"):
        problems.append(f"{where}: no restart policy")


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    problems = []
    spec = read_stage(sys.argv[1], problems)
    uid, gid = check_stage(spec, problems)
    check_compose(sys.argv[2], spec, problems)
    if problems:
        for p in problems:
            print(f"docker-spec: {p}", file=sys.stderr)
        sys.exit(1)

    def array(values):
        return "(" + " ".join(shlex.quote(v) for v in values) + ")"

    print("RT_ENV=" + array(f"{k}={v}" for k, v in spec["env"].items()))
    for name, value in (("RT_USER", spec["user"]), ("RT_UID", uid), ("RT_GID", gid),
                        ("RT_WORKDIR", spec.get("workdir", "/")), ("RT_PORT", spec["expose"]),
                        ("RT_VOLUME", spec["volume"]), ("RT_PREFIX", spec["prefix"])):
        print(f"{name}={shlex.quote(value)}")
    print("RT_ENTRYPOINT=" + array(spec["entrypoint"]))
    print("RT_HEALTHCHECK=" + array(spec["healthcheck"]))


if __name__ == "__main__":
    main()

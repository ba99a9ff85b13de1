"""Lints the OpenAPI description a real strata-server serves at GET /v1/openapi.json with npm's
@seriousme/openapi-schema-validator (OpenAPI 3.1 against its JSON Schema, offline; every $ref
must resolve), the way scripts/check-docker.sh lints the Dockerfile: scripts/install-lint-tools.sh
installs the pinned tools into docker/lint/node_modules (a no-op when they are there), the linter
must flag broken canaries (or a clean result proves nothing), and any error fails.

    check_openapi.py STRATA_SERVER [OUT.json]     OUT.json keeps the document (default: a temp file)
"""

import copy
import json
import os
import subprocess
import sys
import tempfile
import urllib.request

from strata_process import ServerProcess

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
VALIDATOR = os.path.join(ROOT, "docker/lint/node_modules/@seriousme/openapi-schema-validator/"
                               "bin/validate-api-cli.js")


def fetch(binary: str) -> dict:
    with ServerProcess(binary) as server:
        with urllib.request.urlopen(server.url + "/v1/openapi.json", timeout=30) as answer:
            assert answer.status == 200, answer.status
            return json.loads(answer.read())


def lint(document: dict, path: str) -> subprocess.CompletedProcess:
    with open(path, "w", encoding="utf-8") as f:
        json.dump(document, f, indent=1)
    return subprocess.run(["node", VALIDATOR, path], capture_output=True, text=True, timeout=120)


def canaries(document: dict):
    """Documents the linter must refuse: a dangling reference, and a parameter where OpenAPI 3
    has none."""
    dangling = copy.deepcopy(document)
    dangling["components"]["schemas"]["Scene"]["properties"]["version"] = {
        "$ref": "#/components/schemas/NoSuchSchema"}
    yield "a dangling $ref", dangling
    swagger2 = copy.deepcopy(document)
    operation = swagger2["paths"]["/v1/scene/meshes/{id}"]["get"]
    operation["parameters"][0]["in"] = "body"  # Swagger 2's, not OpenAPI 3's
    yield "a parameter in the body", swagger2


def main() -> int:
    binary = sys.argv[1]
    out = sys.argv[2] if len(sys.argv) > 2 else None
    subprocess.run([os.path.join(ROOT, "scripts/install-lint-tools.sh")], check=True)
    document = fetch(binary)
    with tempfile.TemporaryDirectory(prefix="strata-openapi-") as tmp:
        for what, broken in canaries(document):
            if lint(broken, os.path.join(tmp, "canary.json")).returncode == 0:
                print(f"check_openapi: FAILED: the linter flags nothing in {what}")
                return 1
        result = lint(document, out or os.path.join(tmp, "openapi.json"))
    if result.returncode != 0:
        print(result.stdout[-20000:], result.stderr[-4000:])
        print("check_openapi: FAILED: GET /v1/openapi.json is not a valid OpenAPI 3.1 document")
        return 1
    paths = document["paths"]
    operations = sum(1 for item in paths.values() for key in item if key in ("get", "post"))
    print(f"check_openapi: OpenAPI {document['openapi']}, {len(paths)} paths, {operations} "
          f"operations, {len(document['components']['schemas'])} schemas: valid")
    return 0


if __name__ == "__main__":
    sys.exit(main())

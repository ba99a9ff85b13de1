"""Holds every JSON answer protocol/README.md shows to the OpenAPI description a real
strata-server serves, so that an example cannot go stale when a document changes.

    python3 check_readme_answers.py SERVER_BINARY protocol/README.md

Two kinds of example are read:
- a curl command in a ```sh block, followed by `# {...}` comment lines: the answer of that
  method and path (the one -X names, else POST with -d or --data-binary, else GET);
- a ```json block directly under an endpoint's heading (`## GET /v1/scene`) or under
  "Rebuild reports" (the answer of POST /v1/commit), and a ```json problem anywhere.
A document whose `type` is a problem URI is checked as a Problem, anything else as the route's
200 answer.

Examples may elide with `...`: `{"id":"b0",...}` (other members), `"applied":...` (a value),
`[...115 ids]` (a list's items). An elided object may lack required members and an elided value
may be anything; everything that is written must be what the schema allows, and a document
without elisions must be complete.
"""

import json
import re
import sys
import urllib.request

from strata_process import OpenApiCheck, ServerProcess

ELIDED = "\u2026"  # stands for what an example left out
HEADINGS = {"Rebuild reports": ("POST", "/v1/commit")}  # sections that are not one endpoint


def unelide(text: str) -> object:
    """The example as JSON, its elisions marked: an elided value is ELIDED, an object with
    elided members has the key ELIDED."""
    text = text.replace(".../", "https://strata.dev/problems/")
    text = re.sub(r"\[\.\.\.[^\]]*\]", f'["{ELIDED}"]', text)      # [...115 ids]
    text = re.sub(r":\s*\.\.\.", f':"{ELIDED}"', text)               # "applied":...
    text = re.sub(r"\{\s*\.\.\.\s*\}", f'{{"{ELIDED}":true}}', text)  # {...}
    # ",..." ends an object (other members) or an array (other items), with an optional note.
    text = re.sub(r",\s*\.\.\.[^,\]\}]*(?=\})", f',"{ELIDED}":true', text)
    text = re.sub(r",\s*\.\.\.[^,\]\}]*(?=\])", "", text)
    return json.loads(text)


def ignorable(error) -> bool:
    """True when a schema error is only about what the example elided."""
    instance = error.instance
    if instance == ELIDED:
        return True
    if error.validator == "required":
        return isinstance(instance, dict) and ELIDED in instance
    if error.validator in ("additionalProperties", "unevaluatedProperties") and \
            isinstance(instance, dict):
        known = set(error.schema.get("properties", {}))
        return not (set(instance) - known - {ELIDED})
    if error.validator in ("anyOf", "oneOf"):
        branches = {}
        for sub in error.context:
            branches.setdefault(sub.relative_schema_path[0], []).append(sub)
        return any(all(ignorable(e) for e in subs) for subs in branches.values())
    return False


def blocks(readme: str):
    """(kind, first line number, the endpoint heading above, the block's lines) for each fenced
    block, and whether a blank line precedes it."""
    lines = readme.splitlines()
    heading, opened = "", None
    for number, line in enumerate(lines, start=1):
        if opened is None and line.startswith("## "):
            heading = line[3:].strip()
        elif line.startswith("```") and opened is None:
            opened = (line[3:].strip(), number + 1, number < 2 or lines[number - 2] == "")
        elif line.startswith("```"):
            kind, first, after_blank = opened
            yield kind, first, heading, after_blank, lines[first - 1:number - 1]
            opened = None


def curl_answers(first: int, lines: list):
    """(line, method, path, answer text) for each curl command followed by `# {...}` lines."""
    command, answer, at = "", None, 0
    for number, line in enumerate(lines + [""], start=first):
        continued = answer is not None and line.startswith("#  ")
        if continued:
            answer += line[1:]
            continue
        if answer is not None:
            url = re.search(r"(?:localhost|127\.0\.0\.1):\d+(/[^' ]*)", command)
            if not url:
                raise AssertionError(f"line {at}: no server URL in {command!r}")
            explicit = re.search(r"(?:^|\s)-X\s*([A-Z]+)(?:\s|$)", command)
            post = re.search(r"(^|\s)(-d|--data-binary)(\s|$)", command) is not None
            method = explicit.group(1) if explicit else "POST" if post else "GET"
            yield at, method, url.group(1).split("?")[0], answer
            answer = None
        if line.startswith("# {"):
            answer, at = line[1:], number
        elif re.match(r"\s*curl ", line):
            command = line
        elif command and not line.startswith("#"):
            command += " " + line.strip()


def examples(readme: str):
    """(line, method, path, JSON text) for each example answer."""
    for kind, first, heading, after_blank, lines in blocks(readme):
        if kind == "sh":
            yield from curl_answers(first, lines)
        endpoint = HEADINGS.get(heading)
        if endpoint is None and re.match(r"(GET|POST) /\S+$", heading):
            endpoint = tuple(heading.split())
        text = "\n".join(lines)
        if kind == "json" and re.match(r'\s*\{\s*"type"\s*:\s*"https://strata.dev/problems/', text):
            yield first, "", "", text  # a problem, whatever the section
        elif kind == "json" and endpoint and after_blank:
            yield first, endpoint[0], endpoint[1], text


def check(document: dict, readme_text: str) -> list:
    checker = OpenApiCheck(document)
    failures, count = [], 0
    for line, method, path, text in examples(readme_text):
        try:
            value = unelide(text)
        except ValueError as e:
            failures.append(f"line {line}: the example is not JSON once its elisions are read "
                            f"({e}):\n    {text}")
            continue
        problem = isinstance(value, dict) and str(value.get("type", "")).startswith(
            "https://strata.dev/problems/")
        if problem:
            ref = "#/components/schemas/Problem"
        else:
            item = next((i for regex, i in checker._routes if regex.match(path)), None)
            operation = (item or {}).get(method.lower())
            if operation is None:
                failures.append(f"line {line}: {method} {path} is not a documented route")
                continue
            content = operation["responses"]["200"].get("content", {})
            ref = content.get("application/json", {}).get("schema", {}).get("$ref")
            if ref is None:
                failures.append(f"line {line}: {method} {path} documents no JSON answer")
                continue
        errors = [e for e in checker._validator(ref).iter_errors(value) if not ignorable(e)]
        count += 1
        for e in errors[:5]:
            failures.append(f"line {line}: {method} {path} ({ref.rsplit('/', 1)[1]}) at "
                            f"/{'/'.join(str(p) for p in e.path)}: {e.message[:300]}")
    return count, failures


def main() -> int:
    server, readme = sys.argv[1], sys.argv[2]
    with ServerProcess(server) as running:
        with urllib.request.urlopen(running.url + "/v1/openapi.json", timeout=30) as answer:
            document = json.loads(answer.read())
    with open(readme, encoding="utf-8") as f:
        count, failures = check(document, f.read())
    for failure in failures:
        print(failure)
    print(f"{count} example answers in {readme} checked against /v1/openapi.json")
    if count < 10:
        print("fewer than 10 examples were found: the reader no longer sees them")
        return 1
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

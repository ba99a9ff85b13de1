"""Holds every answer the in-process HTTP suites recorded (tests/server/answer_log.h) to the
OpenAPI description of the server that gave it, with the check the process suites use
(tests/python/strata_process.py): the status documented for the route, its media type, and a JSON
body that matches the documented schema.

    python3 check_answers.py DIR

DIR holds one file per TestServer: its GET /v1/openapi.json, then one answer per line. Fails when
an answer is not as documented, or when no server recorded anything (the recording is broken).
"""

import json
import pathlib
import sys

from strata_process import OpenApiCheck


def check_file(path: pathlib.Path) -> tuple[int, list[str]]:
    """The number of answers in one server's file, and what is wrong with them."""
    lines = path.read_text(encoding="utf-8").splitlines()
    if not lines:
        return 0, [f"{path.name}: empty (the server's description was not written)"]
    try:
        checker = OpenApiCheck.of(lines[0])
    except (ValueError, KeyError) as e:
        return 0, [f"{path.name}: the first line is not an OpenAPI description ({e})"]
    failures = []
    for number, line in enumerate(lines[1:], start=2):
        answer = json.loads(line)
        # Bodies that are not JSON were kept as their length: a byte stands for them, so that
        # their media type is checked.
        body = answer["body"].encode() if answer["body"] else b"x" * min(answer["bytes"], 1)
        problems = checker.problems(answer["method"], answer["target"], answer["status"],
                                    answer["content_type"], body)
        if problems:
            failures.append(f"{path.name}:{number}: {answer['method']} {answer['target'][:120]} "
                            f"-> {answer['status']}:\n    " + "\n    ".join(problems))
    return len(lines) - 1, failures


def main() -> int:
    directory = pathlib.Path(sys.argv[1])
    files = sorted(directory.glob("*.jsonl")) if directory.is_dir() else []
    if not files:
        print(f"no answers were recorded in {directory}: the in-process suites did not run, or "
              "STRATA_ANSWER_LOG did not reach them")
        return 1
    total, failures = 0, []
    for path in files:
        count, found = check_file(path)
        total += count
        failures += found
    print(f"{total} answers from {len(files)} servers checked against their OpenAPI description")
    for failure in failures:
        print(failure)
    return 1 if failures or total == 0 else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Runs the README's curl session exactly as written against a live `strata-server --demo`.

Usage: check_curl_session.py SERVER_BINARY README.md

The commands come from the ```sh blocks of the README section "A curl session". The server runs on
a free port; `localhost:7070` in the commands is rewritten to that port and nothing else changes.
Each command's documented output (its `# ...` comment lines) is checked: JSON replies and ETags
exactly, rebuild summaries up to their timing, the report's fields that do not depend on timing.
"""
import json
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def session_blocks(readme):
    text = open(readme, encoding="utf-8").read()
    section = text.split("### A curl session", 1)[1].split("\n### ", 1)[0]
    return re.findall(r"```sh\n(.*?)```", section, flags=re.S)


def split_commands(block):
    """Returns [command, documented output lines] pairs; a command may span lines (an open quote
    or a trailing backslash), and the comment lines after it are its documented output."""
    commands, current = [], []
    for line in block.splitlines():
        if line.startswith("#") and not current:
            if commands:
                commands[-1][1].append(line[1:].strip())
            continue
        current.append(line)
        if not line.endswith("\\") and _balanced("\n".join(current)):
            commands.append(["\n".join(current), []])
            current = []
    assert not current, f"unterminated command: {current}"
    return commands


def _balanced(cmd):
    return cmd.count("'") % 2 == 0


def check_output(cmd, output, expected):
    if not expected:
        return
    if expected[0].startswith("{") and expected[0].endswith("}"):
        assert json.loads(output) == json.loads(expected[0]), f"{cmd}\n got {output!r}\n want {expected[0]!r}"
        return
    got_lines = [l.strip() for l in output.strip().splitlines()]
    if expected[0].startswith("ETag") or expected[0].startswith("X-Strata"):
        assert len(got_lines) == len(expected), f"{cmd}\n got {got_lines}\n want {expected}"
        for got, want in zip(got_lines, expected):
            if want.startswith("X-Strata-Rebuild"):
                # Everything but the trailing time must match.
                want, got = want.rsplit(" ms=", 1)[0], got.rsplit(" ms=", 1)[0]
            assert got.lower() == want.lower(), f"{cmd}\n got {got!r}\n want {want!r}"
        return
    # The pretty-printed report: check the documented lines that do not depend on timing.
    report = json.loads(output)
    assert report["blas_rebuilds"] == 0 and report["blas_refits"] == 0, report
    assert report["rebuilt"] == [] and report["refit"] == [], report
    assert report["tlas"]["action"] == "update" and report["tlas"]["instances"] == 21, report
    assert report["version"] == 3, report


def main():
    server, readme = sys.argv[1], sys.argv[2]
    port = free_port()
    proc = subprocess.Popen([server, "--demo", "--port", str(port), "--log-level", "warn"])
    try:
        for _ in range(200):
            try:
                if urllib.request.urlopen(f"http://127.0.0.1:{port}/readyz", timeout=1).status == 200:
                    break
            except OSError:
                time.sleep(0.05)
        else:
            raise SystemExit("server did not become ready")
        workdir = tempfile.mkdtemp()
        ran = 0
        for block in session_blocks(readme):
            for cmd, expected in split_commands(block):
                cmd = cmd.replace("localhost:7070", f"localhost:{port}")
                out = subprocess.run(["bash", "-o", "pipefail", "-c", cmd], cwd=workdir, capture_output=True,
                                     text=True, timeout=60)
                assert out.returncode == 0, f"{cmd}\nexit {out.returncode}: {out.stderr}"
                check_output(cmd, out.stdout, expected)
                ran += 1
        for name in ("before.png", "after.png"):
            with open(os.path.join(workdir, name), "rb") as f:
                assert f.read(8) == b"\x89PNG\r\n\x1a\n", name
        assert ran >= 5, f"only {ran} commands found in the README session"
        print(f"README curl session: {ran} commands ok")
    finally:
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=30) == 0


if __name__ == "__main__":
    main()

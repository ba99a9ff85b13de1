#!/usr/bin/python3
"""Runs the README's `strata-demo --out frames` and checks the output the README prints for it.

Usage: check_demo_output.py STRATA_DEMO_BINARY README.md

The printed block is the first ``` block of the README section "Without a server". Each of its
lines must appear in the program's output, in that order, up to wall times (`ms=...`); lines the
README leaves out may come between them.
"""
import os
import re
import subprocess
import sys
import tempfile


def untimed(line):
    return " ".join(re.sub(r"\bms=[0-9.]+", "ms=*", line).split())


def printed_block(readme):
    text = open(readme, encoding="utf-8").read()
    section = text.split("### Without a server", 1)[1].split("\n## ", 1)[0]
    command = re.search(r"`(build/engine/strata-demo [^`]*)`", section).group(1)
    block = re.search(r"```\n(.*?)```", section, flags=re.S).group(1)
    return command, block.strip().splitlines()


def main():
    binary, readme = os.path.abspath(sys.argv[1]), sys.argv[2]
    command, printed = printed_block(readme)
    args = command.split()[1:]
    with tempfile.TemporaryDirectory() as d:
        p = subprocess.run([binary, *args], capture_output=True, text=True, cwd=d, timeout=300)
    if p.returncode != 0:
        sys.exit(f"{command} exited {p.returncode}:\n{p.stdout}{p.stderr}")
    got = [untimed(l) for l in p.stdout.splitlines()]
    at = 0
    for line in printed:
        want = untimed(line)
        if want not in got[at:]:
            sys.exit(f"README prints {line!r} (after {at} lines of output), {command} does not:\n"
                     + p.stdout)
        at = got.index(want, at) + 1
    print(f"{len(printed)} printed lines found in the output of {command}")


if __name__ == "__main__":
    main()

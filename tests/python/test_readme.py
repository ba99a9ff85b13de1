"""clients/python/README.md's examples run against a real strata-server and print exactly the
outputs the README shows, so neither can go stale without a test failing."""

import os
import re
import subprocess
import sys
import tempfile
import unittest
from typing import List, Tuple

from strata_process import ServerProcess
from test_client import SERVER

README = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "clients",
                      "python", "README.md")
README_URL = "http://127.0.0.1:7070"

_FENCE = re.compile(r"^```(\w*)\n(.*?)^```\n", re.M | re.S)


def examples(text: str) -> List[Tuple[str, str]]:
    """Every ```python block with the ```text block right after it (its printed output); a
    python block without one must print nothing."""
    blocks = [(m.group(1), m.group(2), m.start(), m.end()) for m in _FENCE.finditer(text)]
    found = []
    for (lang, body, _, end), following in zip(blocks, blocks[1:] + [None]):
        if lang != "python":
            continue
        between = text[end:following[2]] if following else ""
        if following and following[0] == "text" and "```" not in between \
                and len(between.strip().splitlines()) <= 1:
            found.append((body, following[1]))
        elif "print(" in body:
            raise AssertionError("a README example prints but shows no tested output:\n" + body)
    return found


class ReadmeExamplesTest(unittest.TestCase):
    def run_examples(self, server_args: List[str], runs: int) -> None:
        with open(README, encoding="utf-8") as f:
            found = examples(f.read())
        # The quick start, asyncio, named scenes, undo, bulk, mesh edits and LOD examples.
        self.assertEqual(len(found), 9)
        with ServerProcess(SERVER, server_args) as server, tempfile.TemporaryDirectory() as cwd:
            for code, expected in found:
                self.assertIn(README_URL, code)
                for _ in range(runs):
                    run = subprocess.run([sys.executable, "-c",
                                          code.replace(README_URL, server.url)],
                                         cwd=cwd, capture_output=True, text=True, timeout=120)
                    self.assertEqual(run.returncode, 0, run.stderr)
                    self.assertEqual(run.stdout, expected)
            with open(os.path.join(cwd, "orb.png"), "rb") as png:
                self.assertEqual(png.read(8), b"\x89PNG\r\n\x1a\n")

    def test_every_example_prints_what_the_readme_shows(self):
        # Twice: each example removes what it adds, so it can run again.
        self.run_examples([], runs=2)

    def test_the_examples_print_the_same_on_the_demo_scene(self):
        self.run_examples(["--demo"], runs=1)

if __name__ == "__main__":
    unittest.main()

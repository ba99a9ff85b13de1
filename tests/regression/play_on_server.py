#!/usr/bin/env python3
"""Plays regression scripts through a running strata-server: starts the server on a free port,
runs `strata --server URL play SCRIPT` for each script, stops the server. Exits with the first
non-zero exit code of strata (or 0). Used by CTest; standard library only.

    play_on_server.py --server-binary build/server/strata-server --strata build/clients/cli/strata \
        [--budgets] SCRIPT...
"""

import argparse
import os
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
from strata_process import ServerProcess  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--server-binary", required=True)
    parser.add_argument("--strata", required=True)
    parser.add_argument("--budgets", action="store_true")
    parser.add_argument("scripts", nargs="+")
    args = parser.parse_args()
    with ServerProcess(args.server_binary) as server:
        for script in args.scripts:
            command = [args.strata, "--server", server.url, "play", "--no-progress", script]
            if args.budgets:
                command.append("--budgets")
            code = subprocess.call(command)
            if code != 0:
                sys.stderr.write(f"play_on_server: {script} failed with exit code {code}; "
                                 f"server log:\n{server.log()[-4000:]}")
                return code
    return 0


if __name__ == "__main__":
    sys.exit(main())

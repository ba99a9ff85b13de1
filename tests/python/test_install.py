"""clients/python installs with pip, offline, into a fresh venv, and the installed package works
from any folder; its version is the project's, project(VERSION) in the top CMakeLists.txt."""

import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

import strata_client
from strata_process import ServerProcess
from test_client import SERVER

SOURCE_DIR = os.environ.get("STRATA_SOURCE_DIR",
                            os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
PACKAGE_DIR = os.path.join(SOURCE_DIR, "clients", "python")


def cmake_project_version() -> str:
    with open(os.path.join(SOURCE_DIR, "CMakeLists.txt"), encoding="utf-8") as f:
        match = re.search(r"project\(\s*strata\s+VERSION\s+([0-9.]+)", f.read())
    assert match, "CMakeLists.txt has no project(strata VERSION x.y.z)"
    return match.group(1)


class VersionTest(unittest.TestCase):
    def test_the_client_version_is_the_cmake_project_version(self):
        self.assertEqual(strata_client.__version__, cmake_project_version())

    def test_pyproject_takes_its_version_from_the_package_and_needs_nothing_to_build(self):
        import tomllib
        with open(os.path.join(PACKAGE_DIR, "pyproject.toml"), "rb") as f:
            pyproject = tomllib.load(f)
        self.assertNotIn("version", pyproject["project"])  # no second version to forget
        self.assertIn("version", pyproject["project"]["dynamic"])
        # Nothing for pip's isolated build environment to download.
        self.assertEqual(pyproject["build-system"]["requires"], [])
        self.assertEqual(pyproject["build-system"]["backend-path"], ["_build"])

def make_venv(folder):
    """A fresh venv in `folder` (Debian's packages visible, as the README's); its python and an
    environment that keeps pip off every index, configuration and PYTHONPATH."""
    venv = os.path.join(folder, "venv")
    env = {k: v for k, v in os.environ.items() if not k.startswith("PIP_") and k != "PYTHONPATH"}
    env["PIP_CONFIG_FILE"] = os.devnull
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", venv],
                   check=True, env=env)
    return os.path.join(venv, "bin", "python"), env


class InstallTest(unittest.TestCase):
    """What README.md's install commands do, with pip kept off every index and link."""

    def test_pip_installs_it_offline_into_a_venv(self):
        with tempfile.TemporaryDirectory() as tmp:
            # A copy, so that the test also proves the folder is all a build needs.
            source = os.path.join(tmp, "python")
            shutil.copytree(PACKAGE_DIR, source, ignore=shutil.ignore_patterns("__pycache__"))
            python, env = make_venv(tmp)
            # What the README says, build isolation included; no index, no network.
            pip = subprocess.run([python, "-m", "pip", "install", "--no-index", "--no-cache-dir",
                                  source], env=env, capture_output=True, text=True)
            self.assertEqual(pip.returncode, 0, pip.stdout + pip.stderr)
            self.assertIn("Successfully installed strata-client-" + cmake_project_version(),
                          pip.stdout)
            with ServerProcess(SERVER) as server:
                check = subprocess.run(
                    [python, "-c",
                     "import importlib.metadata, os, sys, strata_client\n"
                     "package = os.path.dirname(strata_client.__file__)\n"
                     "print(package.startswith(sys.prefix), strata_client.__version__,\n"
                     "      importlib.metadata.version('strata-client'),\n"
                     "      os.path.exists(os.path.join(package, 'py.typed')))\n"
                     "with strata_client.Client(sys.argv[1]) as c:\n"
                     "    print(c.edit([]), c.commit().tlas.action)\n",
                     server.url],
                    cwd=tmp, env=env, capture_output=True, text=True)
            self.assertEqual(check.returncode, 0, check.stderr)
            version = cmake_project_version()
            self.assertEqual(check.stdout, f"True {version} {version} True\n1 none\n")

    def test_an_editable_install_imports_the_source_folder(self):
        with tempfile.TemporaryDirectory() as tmp:
            python, env = make_venv(tmp)
            pip = subprocess.run([python, "-m", "pip", "install", "--no-index", "--no-cache-dir",
                                  "-e", PACKAGE_DIR], env=env, capture_output=True, text=True)
            self.assertEqual(pip.returncode, 0, pip.stdout + pip.stderr)
            where = subprocess.run(
                [python, "-c", "import strata_client; print(strata_client.__file__)"],
                cwd=tmp, env=env, capture_output=True, text=True, check=True).stdout.strip()
            self.assertEqual(os.path.dirname(os.path.realpath(where)),
                             os.path.realpath(os.path.join(PACKAGE_DIR, "strata_client")))


if __name__ == "__main__":
    unittest.main()

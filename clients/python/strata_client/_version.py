"""The client's version: the project version, project(VERSION) in the top CMakeLists.txt.

pyproject.toml reads it from here, and tests/python/test_install.py fails when it differs from
CMakeLists.txt, so a release changes both or neither.
"""

__version__ = "0.1.0"

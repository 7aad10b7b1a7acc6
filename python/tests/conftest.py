"""Shared fixtures of the Python package's tests: servers on ephemeral ports (uavsim.Server), stopped after
their module. They run against the build tree's package and server (ctest sets PYTHONPATH; the server is
found through the package's _build_paths)."""

import os

import pytest

import uavsim

TESTS_DIR = os.path.dirname(os.path.abspath(__file__))
REPO_DIR = os.path.dirname(os.path.dirname(TESTS_DIR))
THREE_QUADS = os.path.join(REPO_DIR, "tests", "data", "worlds", "three_quads.xml")
# a small, fast camera: the world camera above the empty world, 64 x 48 at 10 frames per second
SMALL_CAMERA = {"overview": "width=64,height=48,fps=10"}


@pytest.fixture(scope="module")
def empty_world():
    with uavsim.Server("empty", seed=1, cameras=SMALL_CAMERA, echo=bool(os.environ.get("UAVSIM_ECHO"))) as s:
        yield s


def server_alive(pid):
    """True while a process with this pid exists and is not a zombie."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(")")[-1].split()[0] != "Z"
    except FileNotFoundError:
        return False

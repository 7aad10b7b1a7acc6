"""python/examples run and do what they say (each against a server of its own)."""

import os
import subprocess
import sys

from conftest import REPO_DIR

EXAMPLES = os.path.join(REPO_DIR, "python", "examples")


def run(name, *args, cwd=None):
    out = subprocess.run([sys.executable, os.path.join(EXAMPLES, name), *args], capture_output=True, text=True,
                         timeout=300, cwd=cwd)
    assert out.returncode == 0, out.stdout + out.stderr
    return out.stdout


def test_fly_square():
    out = run("fly_square.py", "--side", "6")
    assert out.count("at corner") == 4 and "landed" in out


def test_balloon_camera_finds_a_balloon(tmp_path):
    out = run("balloon_camera.py", "--out", str(tmp_path / "b.png"))
    assert "wrote" in out and (tmp_path / "b.png").stat().st_size > 0


def test_radio_chat():
    out = run("radio_chat.py", "--seconds", "3")
    assert "uav0 got from uav1: uav1 heard uav0" in out

"""Offscreen OpenGL chosen before MuJoCo is imported, whatever is imported first, and a video rendered
headless (``DISPLAY`` and ``MUJOCO_GL`` unset, as on a server)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SPY = """
import os, sys
seen = []
class Spy:  # records MUJOCO_GL at the moment mujoco is first imported
    def find_spec(self, name, path=None, target=None):
        if name == "mujoco" and not seen:
            seen.append(os.environ.get("MUJOCO_GL"))
        return None
sys.meta_path.insert(0, Spy())
"""


def _headless_env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "MUJOCO_GL", "PYOPENGL_PLATFORM")}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    return env


def _run(code: str, **env: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", SPY + code], capture_output=True, text=True, timeout=120,
                          env={**_headless_env(), **env}, cwd=ROOT)


@pytest.mark.parametrize("first", ["sim.scene", "sim.render", "mpcshare.commands.robot_options", "mpcshare.cli",
                                   "mpcshare.arms"])
def test_egl_is_chosen_before_mujoco_is_imported(first: str) -> None:
    out = _run(f"import {first}\nimport sim.render\nprint(seen, os.environ['MUJOCO_GL'])")
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["['egl']", "egl"]


def test_a_user_choice_or_a_display_is_left_alone() -> None:
    out = _run("import sim.render\nprint(seen)", MUJOCO_GL="disable")
    assert out.stdout.strip() == "['disable']", out.stderr
    out = _run("import sim.scene\nprint(seen)", DISPLAY=":0")
    assert out.stdout.strip() == "[None]", out.stderr


def test_a_headless_process_renders_the_scene(tmp_path) -> None:
    clip = tmp_path / "clip.gif"
    code = f"""
from sim.closed_loop import run_episode
from sim.demonstrator import generate_demonstrations
from tests.sim.controllers import IdleController
trial = generate_demonstrations(n_subjects=1, minutes=0.5, seed=11).trials[0]
ep = run_episode(IdleController(), trial, duration_s=0.5, render={str(clip)!r}, record=False)
print(ep.info["video"], ep.info["render_message"])
"""
    out = _run(code)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == [str(clip), "None"] and "GLFW" not in out.stderr
    from PIL import Image, ImageStat

    with Image.open(clip) as im:
        assert im.n_frames >= 10
        im.seek(im.n_frames - 1)
        spread = ImageStat.Stat(im.convert("L")).stddev[0]
    assert spread > 10.0  # a scene, not a blank frame

"""The examples in python/examples run, on a small size."""

from __future__ import annotations

import os
import subprocess
import sys

from conftest import REPO, SCENARIOS

EXAMPLES = REPO / "python" / "examples"


def run_example(name, *args, cwd):
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run(
        [sys.executable, str(EXAMPLES / name), *args], capture_output=True, text=True, env=env, cwd=cwd
    )
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


def test_wheel_forces_example(tmp_path):
    out = run_example(
        "wheel_forces.py", str(SCENARIOS / "wheelset_on_springs_30.ron"), "--end-time", "0.1",
        "-o", str(tmp_path / "q.png"), cwd=tmp_path,
    )
    assert "2 wheel loads, 2 lateral forces" in out
    assert "Nadal" in out
    assert "wrote" in out or "matplotlib is not installed" in out


def test_creep_surface_example(tmp_path):
    out = run_example("creep_surface.py", "--law", "fastsim:6", "-n", "9", "-o", str(tmp_path / "c.png"), cwd=tmp_path)
    assert "on 81 cases" in out
    assert "wrote" in out or "matplotlib is not installed" in out

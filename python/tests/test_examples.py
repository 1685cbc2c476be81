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


# The EN 14363 sensitivity study on a small size: 2 yaw stiffnesses × 2
# flange back distances at one speed, 1.5 s each (all wheelsets on the
# straight lead-in), from the bundled study file's scenario and settings.
SMALL_EN14363 = """Study(
    scenario: "{scenario}",
    end_time: Some(1.5),
    set: {{
        "Bogie1.kx": "{{kx}}", "Bogie2.kx": "{{kx}}",
        "Bogie1.WS1.fbd": "{{fbd}}", "Bogie1.WS2.fbd": "{{fbd}}",
        "Bogie2.WS1.fbd": "{{fbd}}", "Bogie2.WS2.fbd": "{{fbd}}",
        "v0": "{{@speed}}",
    }},
    cases: Grid({{ "kx": [15e6, 31.391e6], "fbd": [1.357, 1.363], "@speed": [4.4] }}),
    reductions: [Assessment],
)
"""


def test_en14363_sensitivity_example(tmp_path):
    import csv

    import railmbs.study as rs

    # The bundled study file loads and is the full grid the example draws.
    full = rs.load(REPO / "models" / "studies" / "vehicle1_en14363_sensitivity.ron")
    assert len(full) == 18 and full.variables == ["kx", "fbd", "@speed"]
    study = tmp_path / "small.ron"
    study.write_text(SMALL_EN14363.format(scenario=SCENARIOS / "vehicle1_tc1.ron"))
    out = run_example(
        "en14363_sensitivity.py", "--study", str(study), "-o", str(tmp_path / "out"), "--no-progress", cwd=tmp_path
    )
    assert "4 cases, 0 failed" in out
    assert "wrote" in out or "matplotlib is not installed" in out
    with open(tmp_path / "out" / "results.csv", newline="") as f:
        results = {(float(r["kx"]), float(r["fbd"])): r for r in csv.DictReader(f)}
    with open(tmp_path / "out" / "heatmap.csv", newline="") as f:
        heat = list(csv.DictReader(f))
    assert len(heat) == 4
    lam = {}
    for h in heat:
        kx = float(h["kyaw[MNm/rad]"]) * 1e6 / 2  # kψ = 2·kx·b1², b1 = 1 m
        r = results[(round(kx), float(h["fbd[m]"]))]
        # The heat map shows the study's own reductions.
        assert float(h["YQ.max"]) == float(r["YQ.max"])
        assert float(h["sumY.max[kN]"]) == float(r["sumY.max[N]"]) / 1e3
        assert 0 < float(h["YQ.max"]) < 0.8
        lam[float(h["fbd[m]"])] = float(h["conicity"])
    # A larger back-to-back distance narrows the flangeway clearance on the
    # 1435 mm gauge: the flange comes closer and the conicity grows.
    assert 0 < lam[1.357] < lam[1.363] < 1

"""The analyses from Python (Scenario.equilibrium, modes, critical_speed,
curving) against outside references: a mass on a spring (equilibrium
−(L0 + m g/k), eigenvalue −ζω ± iω√(1−ζ²) with ω = √(k/m)), Vehicle 1's
wheel loads by hand statics, an axle load, the limit-cycle amplitude
recomputed from the run's own rows; and studies of the analyses give the
numbers of the direct calls."""

from __future__ import annotations

import math

import numpy as np
import pytest

import railmbs
import railmbs.study as rs
from conftest import SCENARIOS

SPRING = SCENARIOS / "spring_mass.ron"
WHEELSET = SCENARIOS / "wheelset_on_springs_30.ron"


def test_a_mass_on_a_spring_settles_at_the_hand_statics_and_rings_at_sqrt_k_over_m():
    sc = railmbs.Scenario.load(SPRING)
    sc.set("m", 2.5)
    p = sc.model.parameters
    m, k, g, l0, zeta = 2.5, p["k"], p["g"], p["L0"], p["zeta"]
    eq = sc.equilibrium()
    # The residual force is below 1e-9 of max(1, m g) (2.5e-8 N, 2.5e-10 m
    # at 100 N/m): 1e-9 m is safe and a millionth of the sag m g/k.
    assert abs(eq["z"] - (-(l0 + m * g / k))) < 1e-9
    assert eq.roles == ["solved"] and eq.units == ["m"]
    assert len(eq.wheel_loads()) == 0 and eq.total_wheel_load == 0.0
    modes = sc.modes()
    assert len(modes) == 1 and modes.zero_modes == []
    omega = math.sqrt(k / m)
    row = modes.rows()[0]
    # A linear spring: the central-difference Jacobian is exact to rounding.
    assert abs(row["natural_frequency[Hz]"] - omega / (2 * math.pi)) < 1e-8 * omega
    assert abs(row["damping_ratio"] - zeta) < 1e-8
    lam = modes.eigenvalues[0]
    assert abs(lam - complex(-zeta * omega, omega * math.sqrt(1 - zeta**2))) < 1e-8 * omega
    assert row["name"] == "mass vertical"
    assert modes.shapes.shape == (1, 1) and modes.shapes[0, 0] == 1.0
    # The state matrix has the same eigenvalues (positions, then rates).
    assert modes.a.shape == (2, 2)
    assert np.allclose(sorted(np.linalg.eigvals(modes.a).imag), [-lam.imag, lam.imag], rtol=1e-10)
    table = modes.table()
    assert list(table["name"]) == ["mass vertical"]


def test_a_parameter_locus_follows_sqrt_k_over_m():
    sc = railmbs.Scenario.load(SPRING)
    ks = [50.0, 100.0, 200.0]
    locus = sc.modes(parameter="k", values=ks)
    assert locus.axis == "k" and list(locus.values) == ks
    for k, m in zip(ks, locus.modes):
        fn = m.rows()[0]["natural_frequency[Hz]"]
        assert abs(fn - math.sqrt(k) / (2 * math.pi)) < 1e-8 * math.sqrt(k)
    # Nothing lateral: no critical value.
    assert locus.critical is None
    with pytest.raises(ValueError, match="no critical speed"):
        locus.critical_speed


def test_vehicle1_wheel_loads_are_its_weight_distribution_by_hand():
    sc = railmbs.Scenario.load(SCENARIOS / "vehicle1_equilibrium_straight.ron")
    p = sc.model.parameters
    # Each wheel carries (mc/8 + mf/4 + mw/2) g = 54 546 N (the car body on
    # two bogies, each frame on two wheelsets, symmetric).
    q_hand = (p["mc"] / 8 + p["Bogie1.mf"] / 4 + p["Bogie1.WS1.m"] / 2) * p["g"]
    assert abs(q_hand - 54546.05) < 0.01
    eq = sc.equilibrium()
    loads = eq.wheel_loads()
    assert len(loads) == 8 and set(loads["side"]) == {"left", "right"}
    # 1e-5 as the Rust test: the rolling wheels' creep forces pitch the
    # bogies and move about 0.1 N between leading and trailing wheelsets.
    assert np.all(np.abs(loads["Q[N]"] - q_hand) < 1e-5 * q_hand), loads
    assert abs(eq.total_wheel_load - 8 * q_hand) < 1e-6 * 8 * q_hand
    # The wheels' spin rates are solved, everything else is at rest.
    for name, role, v in zip(eq.coordinates, eq.roles, eq.v):
        if role == "rate solved":
            assert name.endswith("ws.ry") and v > 0
        else:
            assert role == "solved" and v == 0.0


def test_curving_carries_the_axle_load_and_a_speed_sweep_gives_a_row_per_speed():
    sc = railmbs.Scenario.load(WHEELSET)
    c = sc.curving(radius=1200.0, cant=0.05, speed=[25.0, 30.0])
    assert len(c) == 2 and list(c.speeds) == [25.0, 30.0]
    wheels = c.wheels()
    assert len(wheels) == 4 and list(wheels["side"]) == ["left", "right"] * 2
    # Statics by hand, normal to the canted track plane (tilt φ = h/(2 e0),
    # 2 e0 = 1.5 m): the two primary springs push down with their preload
    # 45650 N plus kz (z − r0) each (z the wheelset's height in the track
    # frame; their roll deflections cancel), the wheelset (1813 kg) with
    # m (g cos φ + V²/R sin φ); left out: second order in the small angles.
    phi = 0.05 / 1.5
    for s, (v, group) in zip(c.solutions, wheels.groupby("speed[m/s]")):
        z = s["equilibrium"]["ws.z"]
        axle = 2 * (45650.0 + 1220e3 * (z - 0.46)) + 1813.0 * (
            9.81 * math.cos(phi) + v**2 / 1200.0 * math.sin(phi)
        )
        assert abs(group["Q[N]"].sum() - axle) < 1e-4 * axle
        assert np.allclose(group["Y/Q"], group["Y[N]"] / group["Q[N]"], rtol=1e-12)
    ws = c.wheelsets()
    assert list(ws["element"]) == ["contact", "contact"]
    assert {"y[m]", "yaw[rad]", "SumY [N]", "L.Fx [N]"} <= set(ws.columns)
    # Cant deficiency a = V²/R − g h/(2 e0), 2 e0 = 1.5 m.
    for s in c.solutions:
        a = s["speed"] ** 2 / 1200.0 - 9.81 * 0.05 / 1.5
        assert abs(s["cant_deficiency_acceleration"] - a) < 1e-12


def test_a_short_decelerating_run_finds_no_limit_cycle_and_its_amplitude_is_the_rows_half_range():
    sc = railmbs.Scenario.load(WHEELSET)
    sc.end_time = 0.5
    seen = []
    cs = sc.critical_speed(progress=lambda t, t_end: seen.append((t, t_end)))
    assert cs.detection == "no_limit_cycle" and cs.speed is None
    assert cs.signals == ["ws.y"]
    y = cs.result["ws.y"]
    # The window (1 s) holds the whole 0.5 s run: the largest amplitude is
    # half the range of every row.
    assert cs.amplitude == pytest.approx(0.5 * (y.max() - y.min()), rel=1e-12)
    assert seen and seen[-1] == (0.5, 0.5)


def test_a_bifurcation_diagram_measures_each_plateau_of_its_run():
    sc = railmbs.Scenario.load(WHEELSET)
    b = sc.critical_speed(bifurcation=[28.0, 30.0], hold=0.2, ramp=0.1, measure=0.1)
    t = b.table()
    assert list(t["speed[m/s]"]) == [30.0, 28.0]
    r = b.result
    time, y, v = r["time"], r["ws.y"], r["v[m/s]"]
    # Plateaus: [0, 0.4] at 30 m/s (the first twice as long), then a 0.1 s
    # ramp, [0.5, 0.7] at 28 m/s; the amplitude over the last 0.1 s of each.
    for (start, end), speed, amp in zip([(0.0, 0.4), (0.5, 0.7)], [30.0, 28.0], t["amplitude"]):
        inside = (time >= end - 0.1) & (time <= end)
        assert np.allclose(v[(time >= start) & (time <= end)], speed, rtol=1e-12)
        assert amp == pytest.approx(0.5 * (y[inside].max() - y[inside].min()), rel=1e-12)


def test_analysis_errors_are_the_packages_exceptions_with_the_rust_message():
    sc = railmbs.Scenario.load(SPRING)
    sc.set("k", 0.0)
    with pytest.raises(railmbs.AnalysisError, match="no static equilibrium") as e:
        sc.equilibrium()
    assert e.value.file == str(SPRING)
    spring = railmbs.Scenario.load(SPRING)
    with pytest.raises(railmbs.AnalysisError, match="needs a vehicle on a track"):
        spring.curving(radius=300.0, speed=10.0)
    with pytest.raises(ValueError, match="radius 0 m"):
        spring.curving(radius=0.0, speed=10.0)
    with pytest.raises(ValueError, match="window"):
        spring.critical_speed(window=-1.0)
    with pytest.raises(ValueError, match="train"):
        railmbs.Scenario.load(SCENARIOS / "train3_straight.ron").equilibrium()
    with pytest.raises(railmbs.AnalysisError, match="no parameter \"nope\""):
        spring.modes(parameter="nope", values=[1.0])
    with pytest.raises(TypeError, match="speed"):
        spring.modes(speed="fast")


STUDY = """Study(
    scenario: "{scenario}",
    engine: Numeric,
    set: {{ "ky": 0.5e6 }},
    cases: Grid({{ "kx": [0.4e6, 0.5e6] }}),
    reductions: [
        LeastDamping(),
        LinearCriticalSpeed(speeds: (40.0, 60.0, 2.5)),
        Curving(radius: 1200.0, cant: 0.05),
    ],
)
"""


def test_a_study_of_the_analyses_gives_the_direct_calls_numbers(tmp_path):
    path = tmp_path / "analyses.ron"
    path.write_text(STUDY.format(scenario=WHEELSET))
    df = rs.run(path, tmp_path / "out", progress=False)
    assert list(df["status"]) == ["ok", "ok"], list(df["error"])
    assert list(df["steps"]) == [0, 0]
    speeds = list(np.arange(40.0, 60.0 + 1e-9, 2.5))
    # The soft primary suspension of wheelset_on_springs_critical.ron
    # (linear critical speed about 51 m/s) at two longitudinal stiffnesses.
    for kx, cells in zip([0.4e6, 0.5e6], df.sort_values("index").to_dict("records")):
        sc = railmbs.Scenario.load(WHEELSET)
        sc.set("ky", 0.5e6)
        sc.set("kx", kx)
        least = sc.modes().least_damped_lateral()
        locus = sc.modes(speed=speeds)
        wheels = sc.curving(radius=1200.0, cant=0.05, speed=30.0).wheels()
        assert cells["least_damping"] == least["damping_ratio"]
        assert cells["least_damping.f[Hz]"] == least["frequency[Hz]"]
        assert cells["least_damping.mode"] == least["name"]
        assert locus.critical_speed is not None and 40.0 < locus.critical_speed < 60.0
        assert cells["linear_critical_speed[m/s]"] == locus.critical_speed
        assert cells["curving.YQ.max"] == wheels["Y/Q"].max()
        assert cells["curving.Q.min[N]"] == wheels["Q[N]"].min()

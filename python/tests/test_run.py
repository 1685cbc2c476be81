"""A run from Python gives exactly the numbers ``umsim run`` writes for the
same scenario and changes (bit for bit after the CSV round trip), its
summary and its EN 14363 assessment table."""

from __future__ import annotations

import numpy as np
import pytest

import railmbs
from conftest import SCENARIOS


def assert_same_columns(result: railmbs.RunResult, header, cols) -> None:
    assert result.columns == header
    for name in header:
        got = result[name]
        # Bitwise: the same doubles (NaN nowhere: a run never writes NaN).
        assert got.dtype == np.float64
        assert np.array_equal(got.view(np.uint64), cols[name].view(np.uint64)), name


def test_double_pendulum_numeric_with_set_and_end_time(run_cli):
    _, header, cols = run_cli(SCENARIOS / "double_pendulum.ron", "--set", "m2=0.8", "--end-time", "2")
    sc = railmbs.Scenario.load(SCENARIOS / "double_pendulum.ron")
    sc.set("m2", 0.8)
    sc.end_time = 2.0
    r = sc.run(engine="numeric")
    assert_same_columns(r, header, cols)
    assert r.summary["t_end"] == 2.0
    assert r.summary["rows"] == len(r) == len(cols["time"])
    assert r.summary["steps"] > 0 and r.summary["error"] is None
    df = r.to_pandas()
    assert list(df.columns) == header and len(df) == len(r)


def test_double_pendulum_symbolic_through_the_plugin_cache(run_cli):
    _, header, cols = run_cli(SCENARIOS / "double_pendulum.ron", "--engine", "symbolic", "--end-time", "1")
    r = railmbs.run(SCENARIOS / "double_pendulum.ron", end_time=1.0, engine="symbolic")
    assert r.summary["engine"] == "symbolic"
    assert_same_columns(r, header, cols)


def test_wheelset_on_track_and_its_assessment(run_cli):
    """Wheel–rail contact forces, and the assessment table against the one
    the CLI prints (to its 4 decimals)."""
    stdout, header, cols = run_cli(SCENARIOS / "wheelset_on_springs_30.ron", "--end-time", "0.5")
    r = railmbs.run(SCENARIOS / "wheelset_on_springs_30.ron", end_time=0.5)
    assert_same_columns(r, header, cols)
    assert "contact.L.Q [N]" in r.columns
    table = r.assessment()
    assert len(table) > 0
    assert list(table.columns) == ["element", "quantity", "unit", "max", "time", "limit", "limit_name", "ratio"]
    printed = [line for line in stdout.splitlines() if line.startswith("contact ")]
    assert len(printed) == len(table)
    for line, (_, row) in zip(printed, table.iterrows()):
        assert f"{row['quantity']} [{row['unit']}]" in line
        assert f"{row['max']:.4f}" in line.split()
        if row["limit"] == row["limit"] and row["limit"] is not None:
            assert f"{row['limit']:.4f}" in line.split() and row["limit_name"] in line
    nadal = table[table["limit_name"] == "Nadal"]
    assert (nadal["ratio"] == nadal["max"] / nadal["limit"]).all()


def test_parameter_expression_macro_free_and_initial_condition(run_cli):
    """An expression value and an initial condition change the run as the
    same changes in the scenario text do."""
    text = (SCENARIOS / "double_pendulum.ron").read_text()
    sc = railmbs.Scenario.from_string(text, path=SCENARIOS / "double_pendulum.ron")
    sc.end_time = 0.5
    base = sc.run()
    sc.set_initial("q1", value=0.3)
    moved = sc.run()
    assert moved["q1"][0] == 0.3 and base["q1"][0] != 0.3
    sc2 = sc.copy()
    sc2.set("m2", "2 * 0.4")
    sc.set("m2", 0.8)
    assert np.array_equal(sc.run()["q2"], sc2.run()["q2"])


def test_train_runs_as_the_cli(run_cli):
    _, header, cols = run_cli(SCENARIOS / "train3_straight.ron", "--end-time", "0.05")
    sc = railmbs.Scenario.load(SCENARIOS / "train3_straight.ron")
    assert sc.is_train
    sc.end_time = 0.05
    assert_same_columns(sc.run(), header, cols)


def test_creep_law_override_changes_the_forces():
    sc = railmbs.Scenario.load(SCENARIOS / "wheelset_on_springs_30.ron")
    sc.end_time = 0.05
    default = sc.run()
    sc.set_creep_law("kalker")
    assert sc.creep_law == "kalker"
    kalker = sc.run()
    assert kalker.columns == default.columns
    assert not np.array_equal(kalker["ws.y"], default["ws.y"])
    with pytest.raises(ValueError, match="creep law"):
        sc.set_creep_law("fastsim:0")
    # A model without wheel–rail contact refuses a creep law.
    dp = railmbs.Scenario.load(SCENARIOS / "double_pendulum.ron")
    dp.set_creep_law("kalker")
    with pytest.raises(ValueError, match="no wheel–rail element"):
        dp.run()


def test_model_inspection():
    m = railmbs.Model.load(railmbs.Scenario.load(SCENARIOS / "double_pendulum.ron").model.path)
    assert m.name == "double_pendulum"
    assert m.coordinates == ["q1", "q2"]
    assert "m2" in m.parameters and isinstance(m.parameters["m2"], float)


def test_model_and_scenario_from_strings_run_as_the_files():
    """A model given as text runs exactly as the same model read from its file."""
    file_sc = railmbs.Scenario.load(SCENARIOS / "double_pendulum.ron")
    file_sc.end_time = 0.3
    model_path = file_sc.model.path
    model = railmbs.Model.from_string(open(model_path).read(), path=model_path)
    text = (SCENARIOS / "double_pendulum.ron").read_text()
    sc = railmbs.Scenario.from_string(text, path=SCENARIOS / "double_pendulum.ron", model=model)
    sc.end_time = 0.3
    a, b = file_sc.run(), sc.run()
    assert a.columns == b.columns
    for c in a.columns:
        assert np.array_equal(a[c], b[c])


def test_a_failed_simulation_raises_with_the_rows_before():
    """RK4 with a step far beyond its stability limit (ω h = 10⁴·0.01 = 100 ≫
    2.8) overflows: SimulationError with the time and the rows written."""
    text = """Scenario(
        model: "../mechanisms/spring_mass.ron",
        end_time: 100.0,
        integrator: Rk4(step: 0.01),
        output: (interval: 0.01),
    )"""
    sc = railmbs.Scenario.from_string(text, path=SCENARIOS / "python_unstable.ron")
    sc.set("k", 1e8)
    with pytest.raises(railmbs.SimulationError) as info:
        sc.run()
    e = info.value
    assert 0 < e.time < 100.0
    assert e.result is not None and 0 < len(e.result) and e.result["time"][-1] <= e.time
    assert np.all(np.isfinite(e.result["z"]))
    assert "python_unstable.ron" in str(e)


def test_macros_apply_as_their_assignments():
    """The double pendulum's macro `equal_rods` ({l2: l1, m2: m1}) gives the
    run of the same assignments made with `set`; an unknown macro is a
    located ModelError."""
    sc = railmbs.Scenario.load(SCENARIOS / "double_pendulum.ron")
    sc.end_time = 0.3
    by_hand = sc.copy()
    by_hand.set("l2", "l1")
    by_hand.set("m2", "m1")
    sc.macros = ["equal_rods"]
    assert sc.macros == ["equal_rods"]
    a, b = sc.run(), by_hand.run()
    assert np.array_equal(a["q2"], b["q2"])
    assert not np.array_equal(a["q2"], railmbs.run(SCENARIOS / "double_pendulum.ron", end_time=0.3)["q2"])
    sc.macros = ["no_such_macro"]
    with pytest.raises(railmbs.ModelError, match="no_such_macro"):
        sc.run()

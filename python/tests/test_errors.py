"""Errors are Python exceptions carrying what ``umsim`` prints: the file,
the element, the line and the column."""

from __future__ import annotations

import pytest

import railmbs
from conftest import SCENARIOS

BAD_MODEL = """Model(
    name: "bad",
    bodies: [
        Body(name: "b", mass: "m_undefined", joint: Revolute(axis: Z)),
    ],
)
"""


def test_bad_model_string_has_line_and_column():
    with pytest.raises(railmbs.ModelError) as info:
        railmbs.Model.from_string('Model(name: "x", bodies: [Body(name: 1)])', path="bad.ron")
    e = info.value
    assert e.file == "bad.ron"
    assert (e.line, e.column) == (1, 37)
    assert str(e).startswith("bad.ron:1:37: ")
    assert e.problems and e.problems[0][3:] == (1, 37)
    assert isinstance(e, railmbs.RailmbsError) and isinstance(e, ValueError)


def test_bad_expression_names_the_element_and_position():
    with pytest.raises(railmbs.ModelError) as info:
        railmbs.Model.from_string(BAD_MODEL, path="models/bad.ron")
    e = info.value
    assert e.file == "models/bad.ron"
    assert e.line == 4, str(e)
    assert e.column is not None
    assert e.element and "b" in e.element, str(e)


def test_unknown_parameter_of_a_scenario_is_located_in_the_scenario():
    sc = railmbs.Scenario.load(SCENARIOS / "double_pendulum.ron")
    sc.set("no_such_parameter", 1.0)
    with pytest.raises(railmbs.ModelError, match="no_such_parameter") as info:
        sc.run()
    assert info.value.file.endswith("double_pendulum.ron")


def test_bad_end_time_and_missing_file():
    sc = railmbs.Scenario.load(SCENARIOS / "double_pendulum.ron")
    with pytest.raises(railmbs.ModelError) as info:
        sc.end_time = -1.0
    assert info.value.element == "end_time"
    with pytest.raises(railmbs.ModelError, match="cannot read"):
        railmbs.Scenario.load(SCENARIOS / "no_such_file.ron")


def test_unknown_coordinate_and_engine():
    sc = railmbs.Scenario.load(SCENARIOS / "double_pendulum.ron")
    with pytest.raises(ValueError, match="engine"):
        sc.run(engine="fast")
    sc.set_initial("q9", value=1.0)
    with pytest.raises(railmbs.ModelError, match="q9"):
        sc.run()


def test_missing_output_column_suggests_names():
    r = railmbs.run(SCENARIOS / "double_pendulum.ron", end_time=0.1)
    with pytest.raises(KeyError, match="q1"):
        r["q1 "]

"""railmbs: rail vehicle dynamics as multibody systems, from Python.

Run a scenario in process, with the numbers ``umsim run`` writes::

    import railmbs
    sc = railmbs.Scenario.load("models/scenarios/double_pendulum.ron")
    sc.set("m2", 0.8)          # as umsim run --set m2=0.8
    sc.end_time = 2.0          # as --end-time 2
    r = sc.run(engine="symbolic")
    r["time"], r.columns, r.summary, r.to_pandas()

The analyses (static equilibrium, linear modes and the root locus with the
linear critical speed, the nonlinear critical speed, quasi-static curving)
are methods of :class:`Scenario` whose results are in
:mod:`railmbs.analysis`::

    eq = sc.equilibrium()              # state and wheel loads
    sc.modes(speed=[20, 40, 60]).critical_speed

The wheel–rail contact functions over numpy arrays are in
:mod:`railmbs.contact`; parameter studies (the study files of ``umsim
study``, on a local pool or a Dask cluster) in :mod:`railmbs.study`.
Errors derive from :class:`railmbs.RailmbsError` (:mod:`railmbs.errors`).
"""

from __future__ import annotations

from typing import Any, Callable, Dict, Iterable, Mapping, Optional, Tuple, Union

from . import analysis, contact, errors, study
from ._railmbs import CREEP_LAW_SYNTAX, Model, Scenario
from .errors import (
    AnalysisError,
    ContactError,
    ModelError,
    PluginError,
    RailmbsError,
    SimulationError,
    StudyError,
)
from .result import RunResult

__all__ = [
    "AnalysisError",
    "CREEP_LAW_SYNTAX",
    "ContactError",
    "Model",
    "ModelError",
    "PluginError",
    "RailmbsError",
    "RunResult",
    "Scenario",
    "SimulationError",
    "StudyError",
    "analysis",
    "contact",
    "errors",
    "run",
    "study",
]


def run(
    scenario: Union[str, "Any", Scenario],
    *,
    set: Optional[Mapping[str, Union[float, str]]] = None,
    end_time: Optional[float] = None,
    macros: Optional[Iterable[str]] = None,
    initial: Optional[Mapping[str, Tuple[Optional[float], Optional[float]]]] = None,
    creep_law: Optional[str] = None,
    engine: str = "numeric",
    plugin: Optional[str] = None,
    progress: Optional[Callable[[float, float], None]] = None,
) -> RunResult:
    """Runs a scenario (a path or a :class:`Scenario`, which is not changed)
    with the given changes, as ``umsim run SCENARIO --set NAME=VALUE
    --end-time T --engine ENGINE`` does, and returns its :class:`RunResult`.

    ``set``: parameter values (numbers in the parameter's SI unit, or
    expression strings); ``end_time`` s; ``macros`` replace the scenario's;
    ``initial``: coordinate → (value, velocity), either may be ``None``;
    ``creep_law`` as ``umsim creep --method``; ``engine`` ``"numeric"`` or
    ``"symbolic"``; ``plugin`` a compiled plugin to load; ``progress(t, t_end)``
    called now and then (s).
    """
    sc = scenario.copy() if isinstance(scenario, Scenario) else Scenario.load(str(scenario))
    for name, value in (set or {}).items():
        sc.set(name, value)
    if end_time is not None:
        sc.end_time = end_time
    if macros is not None:
        sc.macros = list(macros)
    for coord, (value, velocity) in (initial or {}).items():
        sc.set_initial(coord, value, velocity)
    if creep_law is not None:
        sc.set_creep_law(creep_law)
    return sc.run(engine=engine, plugin=None if plugin is None else str(plugin), progress=progress)

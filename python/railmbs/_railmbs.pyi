"""Type stubs of the extension module railmbs._railmbs (Rust, PyO3).

Units are SI throughout; see the docstrings (``help(railmbs.Scenario)``).
"""

from os import PathLike
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Set, Tuple, Union

import numpy as np
import numpy.typing as npt

from .analysis import Bifurcation, CriticalSpeed, Curving, Equilibrium, Locus, Modes
from .result import RunResult

_Path = Union[str, PathLike]
_F64 = npt.NDArray[np.float64]

#: The syntax of creep laws (``umsim creep --method``).
CREEP_LAW_SYNTAX: str

class Model:
    """A model (``Model(...)`` file): its names and defaults."""

    @staticmethod
    def load(path: _Path) -> Model:
        """Reads a model file (RON). Raises ``railmbs.ModelError`` with file,
        element, line and column."""
    @staticmethod
    def from_string(text: str, path: _Path = "model.ron") -> Model:
        """Resolves model text; ``path`` names it in errors and resolves the
        files it refers to relative to its folder."""
    @property
    def name(self) -> str: ...
    @property
    def path(self) -> Optional[Path]:
        """The file it was read from (the path given with a string)."""
    @property
    def parameters(self) -> Dict[str, float]:
        """Parameter long names and default values (SI units)."""
    @property
    def macros(self) -> List[str]: ...
    @property
    def coordinates(self) -> List[str]:
        """Generalized coordinate names (m or rad), the first CSV columns after ``time``."""
    @property
    def bodies(self) -> List[str]: ...
    @property
    def forces(self) -> List[str]:
        """Force element long names."""

class Scenario:
    """A scenario (``Scenario(...)``) or a train (``Train(...)``), to change and run."""

    @staticmethod
    def load(path: _Path) -> Scenario:
        """Reads a scenario or train file (RON). Raises ``railmbs.ModelError``."""
    @staticmethod
    def from_string(text: str, path: _Path = "scenario.ron", model: Optional[Model] = None) -> Scenario:
        """Resolves scenario or train text; ``path`` names it in errors and
        resolves its model, track and output files relative to its folder;
        ``model`` is run instead of the model file the text names."""
    @property
    def path(self) -> Path:
        """The scenario file (or the path given with its text)."""
    @property
    def is_train(self) -> bool: ...
    @property
    def model(self) -> Model:
        """The model (read from the file the scenario names on first use)."""
    @model.setter
    def model(self, model: Model) -> None: ...
    @property
    def end_time(self) -> float:
        """Simulated time from t = 0, s (checked as ``umsim run --end-time``)."""
    @end_time.setter
    def end_time(self, end_time: float) -> None: ...
    @property
    def parameters(self) -> List[Tuple[str, str]]:
        """Parameter assignments (long name, expression text), in order."""
    def set(self, name: str, value: Union[float, str]) -> None:
        """Sets parameter ``name`` (``umsim run --set NAME=VALUE``): a number in
        the parameter's SI unit or an expression string."""
    @property
    def macros(self) -> List[str]:
        """Macros applied in order before the parameter assignments."""
    @macros.setter
    def macros(self, macros: List[str]) -> None: ...
    def set_initial(self, coordinate: str, value: Optional[float] = None, velocity: Optional[float] = None) -> None:
        """Initial value (m or rad) and/or velocity (m/s or rad/s) of a coordinate."""
    @property
    def initial(self) -> List[Tuple[str, Optional[float], Optional[float]]]: ...
    def set_creep_law(self, law: str) -> None:
        """Creep law of every wheel–rail element (``umsim creep --method`` syntax)."""
    @property
    def creep_law(self) -> Optional[str]: ...
    def copy(self) -> Scenario: ...
    def run(
        self,
        engine: str = "numeric",
        plugin: Optional[_Path] = None,
        progress: Optional[Callable[[float, float], Any]] = None,
    ) -> RunResult:
        """Runs the scenario (``"numeric"`` or ``"symbolic"`` engine; the plugin
        through the CLI's content-hash cache) with the GIL released.
        ``progress(t, t_end)`` (s) is called at most every 100 ms and at the
        end; an exception it raises, or Ctrl-C, stops the run and is re-raised.
        Raises ``ModelError``, ``PluginError``, ``SimulationError`` (with the
        partial ``result``)."""
    def equilibrium(self, engine: str = "numeric", plugin: Optional[_Path] = None) -> Equilibrium:
        """The static (steady) equilibrium at the start (``umsim
        equilibrium``): state ``q`` (m, rad), ``v`` (m/s, rad/s), each
        coordinate's role and the wheel loads Q, Y (N). GIL released.
        Raises ``AnalysisError`` (no equilibrium), ``ModelError``,
        ``PluginError``; ``ValueError`` for a train."""
    def modes(
        self,
        speed: Union[None, float, Sequence[float]] = None,
        parameter: Optional[str] = None,
        values: Optional[Sequence[float]] = None,
        engine: str = "numeric",
        plugin: Optional[_Path] = None,
    ) -> Union[Modes, Locus]:
        """Linear modes at the steady state (``umsim modes``): frequency
        (Hz), damping ratio, name and shape of each. ``speed`` ``None`` (the
        scenario's) or a number (m/s): :class:`Modes`; a sequence of speeds
        (m/s): the root locus, a :class:`Locus` with ``critical_speed`` (m/s,
        the linear critical speed); ``parameter`` with ``values``: a locus
        over a model parameter (``umsim modes --sweep``). GIL released.
        Raises ``AnalysisError``, ``ModelError``, ``PluginError``, ``ValueError``."""
    def critical_speed(
        self,
        bifurcation: Optional[Sequence[float]] = None,
        signals: Optional[Sequence[str]] = None,
        window: float = 1.0,
        threshold: float = 1e-3,
        on: float = 4e-3,
        relative: float = 0.5,
        hold: float = 6.0,
        ramp: float = 0.5,
        measure: Optional[float] = None,
        engine: str = "numeric",
        plugin: Optional[_Path] = None,
        progress: Optional[Callable[[float, float], Any]] = None,
    ) -> Union[CriticalSpeed, Bifurcation]:
        """The nonlinear critical speed (``umsim critical-speed``): a
        decelerating run's limit cycle (window s; threshold and on m) →
        :class:`CriticalSpeed` (speed m/s); with ``bifurcation`` (speeds,
        m/s; plateaus of ``hold`` s, ramps of ``ramp`` s, amplitude over the
        last ``measure`` s) → :class:`Bifurcation`. GIL released; progress
        and Ctrl-C as for :meth:`run`. Raises ``AnalysisError``,
        ``ModelError``, ``PluginError``, ``ValueError``."""
    def curving(
        self,
        radius: float,
        speed: Union[float, Sequence[float]],
        cant: float = 0.0,
        engine: str = "numeric",
        plugin: Optional[_Path] = None,
    ) -> Curving:
        """Quasi-static curving (``umsim curving``) on a circular curve of
        ``radius`` m (positive left) and ``cant`` m at ``speed`` m/s (or a
        sweep over a sequence): per wheelset lateral position (m), angle of
        attack (rad) and contact outputs; per wheel Q, Y (N), Y/Q. GIL
        released. Raises ``ValueError`` (bad curve), ``AnalysisError``,
        ``ModelError``, ``PluginError``."""

_Row = List[str]

class Study:
    """A study file (``Study(...)``, RON, as ``umsim study`` reads it; the
    format is documented in the ``railmbs-study`` crate)."""

    @staticmethod
    def load(path: _Path) -> Study:
        """Reads and checks a study file, its scenario and model(s). Raises
        ``railmbs.ModelError`` (file, element, line, column)."""
    @staticmethod
    def from_string(text: str, path: _Path = "study.ron") -> Study:
        """Reads study text; ``path`` names it in errors and resolves the
        scenario relative to its folder."""
    @property
    def path(self) -> Path: ...
    @property
    def engine(self) -> str:
        """``"symbolic"`` (one compiled plugin for all cases) or ``"numeric"``."""
    @property
    def models(self) -> List[str]:
        """Model names, in the order of ``StudyEngine.plugin_paths``."""
    @property
    def variables(self) -> List[str]: ...
    @property
    def time_series(self) -> bool:
        """Whether each case's output is written as ``series/<case id>.csv``
        (or ``.parquet``: ``series_format``)."""
    @property
    def series_format(self) -> str:
        """The format of the time series files: ``"csv"`` or ``"parquet"``
        (one DOUBLE column per output column, the values bit for bit)."""
    def cases(self) -> List[Dict[str, Any]]:
        """The cases in index order: dicts with ``index`` (int), ``id`` (16
        hex digits, stable across machines and runs) and ``inputs``
        (variable → float, or the text of an expression or macro name)."""
    def result_header(self) -> List[str]:
        """Columns of the result table: ``index``, ``case_id``, the variables,
        ``status``, ``error``, ``steps``, ``rejected_steps``, ``t_end[s]``,
        ``integration_time[s]``, ``cpu_time[s]``, ``wall_time[s]``, the
        reductions."""
    def __len__(self) -> int: ...

class StudyEngine:
    """A study's model plugin, built and loaded once per process, that runs
    its cases (the GIL released)."""

    @staticmethod
    def prepare(study: Study, cache_dir: Optional[_Path] = None) -> StudyEngine:
        """Derives and builds the plugin through the content-hash cache
        (``cache_dir``, else ``$RAILMBS_CACHE_DIR``, else the platform cache)
        unless cached, and loads it. Raises ``railmbs.PluginError``."""
    @staticmethod
    def from_plugins(study: Study, paths: List[_Path]) -> StudyEngine:
        """Loads plugins built elsewhere (one per model of ``study.models``,
        each checked against its model); compiles nothing."""
    @property
    def plugin_paths(self) -> List[Path]:
        """The loaded plugin files (empty for a numeric study)."""
    def builds(self) -> Dict[str, int]:
        """Counters ``derived``, ``indexed``, ``compiled``, ``loaded``."""
    def run_case(self, case: Union[int, str], series_dir: Optional[_Path] = None) -> _Row:
        """Runs one case (index or id) to its row: the table's cells as text
        (times in s). A failed run is a row with status ``failed`` and its
        error. The GIL is released; Ctrl-C raises KeyboardInterrupt. Raises
        ``railmbs.StudyError`` for a reduction that fits no output column."""
    def run_local(
        self, store: ResultStore, jobs: int = 0, on_result: Optional[Callable[[_Row], Any]] = None
    ) -> Dict[str, Any]:
        """Runs the cases ``store`` lacks on ``jobs`` threads (0: one per
        core), appending each row as it finishes and then calling
        ``on_result(row)``; an exception it raises, or Ctrl-C, stops the
        study and is re-raised. Returns ``skipped``, ``recorded``,
        ``failed``, ``interrupted``."""

class ResultStore:
    """The append-only, resumable result table (``results.csv``)."""

    @staticmethod
    def open(path: _Path, header: List[str]) -> ResultStore:
        """Opens or creates the table; drops a partly written last line.
        Raises ``railmbs.StudyError`` for a table of other columns."""
    @property
    def path(self) -> Path: ...
    def finished(self) -> Set[str]:
        """Ids of the cases in the table."""
    @property
    def dropped_partial_line(self) -> bool: ...
    def append(self, row: _Row) -> None:
        """Appends a row (as ``StudyEngine.run_case`` returns it) and flushes it."""

class Profile:
    """A smoothed wheel or rail profile (use ``railmbs.contact.Profile``)."""

    @staticmethod
    def read(path: _Path, kind: Optional[str] = None, smoothing: float = 1e-4, rail_inclination: float = 0.0) -> Profile: ...
    @property
    def name(self) -> str: ...
    @property
    def kind(self) -> str: ...
    @property
    def range(self) -> Tuple[float, float]: ...
    def _evaluate(self, u: _F64) -> Tuple[_F64, _F64, _F64]: ...

class WheelsetGeometry:
    """A wheelset on a track (use ``railmbs.contact.Wheelset``)."""

    def __init__(
        self,
        wheel: Profile,
        rail: Profile,
        *,
        wheel_right: Optional[Profile] = None,
        rail_right: Optional[Profile] = None,
        gauge: float = 1.435,
        flange_back: float = 1.360,
        radius: float = 0.46,
        radius_right: Optional[float] = None,
    ) -> None: ...
    @property
    def nominal_radius(self) -> float: ...
    def _contacts(self, y: _F64, roll: _F64) -> Dict[str, Dict[str, _F64]]: ...
    def _rigid(self, y: _F64) -> Dict[str, Any]: ...
    def _conicity(self, amplitudes: _F64, with_roll: bool = False) -> _F64: ...
    def rolling_radius_difference(self, y_max: float = 0.01, dy: float = 1e-4, with_roll: bool = False) -> Tuple[_F64, _F64]: ...

def hertz_contact(curv_a: _F64, curv_b: _F64, n: _F64, e: _F64, nu: _F64) -> Dict[str, _F64]:
    """Hertz contacts over equal-length arrays (use ``railmbs.contact.hertz``)."""

def creep_forces_flat(
    law: str, a: _F64, b: _F64, g: _F64, nu: _F64, mu: _F64, n: _F64, xi: _F64, eta: _F64, phi: _F64,
    speed: Optional[_F64] = None,
) -> Tuple[_F64, _F64, _F64]:
    """Creep forces over equal-length arrays (use ``railmbs.contact.creep_forces``)."""

def creep_law_name(law: str) -> str: ...

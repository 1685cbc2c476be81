"""Type stubs of the extension module railmbs._railmbs (Rust, PyO3).

Units are SI throughout; see the docstrings (``help(railmbs.Scenario)``).
"""

from os import PathLike
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

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

"""Exceptions of railmbs.

Every error the package raises for bad input or a failed run derives from
:class:`RailmbsError`. A problem in a model, scenario or train file is a
:class:`ModelError` carrying what ``umsim`` prints: the file, the element
(e.g. ``body "link2"``), the line and the column (1-based, where known).
"""

from __future__ import annotations

from typing import Any, Optional, Sequence, Tuple

Problem = Tuple[str, Optional[str], str, Optional[int], Optional[int]]


class RailmbsError(Exception):
    """Base class of the errors of railmbs."""


class ModelError(RailmbsError, ValueError):
    """A model, scenario or train file (or text) has a problem.

    Attributes:
        file: the file at fault (the path given with a string).
        element: the element, e.g. ``body "link2"``; ``None`` for the file as a whole.
        line, column: 1-based position in the file, ``None`` where unknown.
        problems: every problem found, as ``(file, element, message, line, column)``;
            the attributes above are the first one's.
    """

    def __init__(
        self,
        message: str,
        file: Optional[str] = None,
        element: Optional[str] = None,
        line: Optional[int] = None,
        column: Optional[int] = None,
        problems: Sequence[Problem] = (),
    ) -> None:
        super().__init__(message)
        self.message = message
        self.file = file
        self.element = element
        self.line = line
        self.column = column
        self.problems = list(problems)


class SimulationError(RailmbsError, RuntimeError):
    """The simulation failed (diverged, a non-finite value, no progress).

    Attributes:
        time: simulated time reached, s.
        result: the :class:`railmbs.RunResult` of the rows written up to the
            failure (``None`` when it failed before the first row).
    """

    def __init__(self, message: str, time: float = 0.0, result: Any = None) -> None:
        super().__init__(message)
        self.time = time
        self.result = result


class AnalysisError(RailmbsError, RuntimeError):
    """An analysis (equilibrium, modes, critical speed, curving) found no
    result: no equilibrium within the iterations (the message names the
    residual and the coordinates carrying it), a failed linearization or
    eigendecomposition, no steady curving state, or a scenario the analysis
    cannot use (no track for curving, say). The message is the one ``umsim``
    prints.

    Attributes:
        file: the scenario file the message names (``None`` if none).
    """

    def __init__(self, message: str, file: Optional[str] = None) -> None:
        super().__init__(message)
        self.message = message
        self.file = file


class PluginError(RailmbsError, RuntimeError):
    """The symbolic plugin could not be generated, compiled or loaded."""


class ContactError(RailmbsError, ValueError):
    """Bad input to a contact function (profile file, geometry, creep case)."""


class StudyError(RailmbsError, RuntimeError):
    """A study cannot go on: its result table is unusable (written by another
    study, or the study file changed since), a file cannot be written, or a
    reduction fits no output column of the run (a fault of the study file,
    the same for every case). A case that fails is not an error: it is a row
    of the table with status ``failed`` and its message."""

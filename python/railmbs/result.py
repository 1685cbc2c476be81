"""The result of a run: every output column as a numpy array by its name."""

from __future__ import annotations

from typing import Any, Dict, Iterator, List, Optional

import numpy as np


class RunResult:
    """Output columns of a run, its summary and its assessment table.

    ``result["time"]``, ``result["Bogie1.WS1.contact.L.Q [N]"]``: a column by
    its CSV header name (units in brackets, as ``umsim run`` writes them);
    ``result.columns``: the names in CSV order. The arrays hold exactly the
    numbers ``umsim run`` writes to its CSV.
    """

    def __init__(
        self,
        names: List[str],
        columns: List[np.ndarray],
        summary: Dict[str, Any],
        assessment: List[Dict[str, Any]],
    ) -> None:
        self._names = list(names)
        self._columns = dict(zip(names, columns))
        self._summary = summary
        self._assessment = assessment

    @property
    def columns(self) -> List[str]:
        """Column names in CSV order, the first ``time``."""
        return list(self._names)

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self._columns[name]
        except KeyError:
            import difflib

            close = difflib.get_close_matches(name, self._names, n=3)
            hint = f"; did you mean {', '.join(map(repr, close))}?" if close else ""
            raise KeyError(f"no output column {name!r}{hint}") from None

    def __contains__(self, name: object) -> bool:
        return name in self._columns

    def __iter__(self) -> Iterator[str]:
        return iter(self._names)

    def __len__(self) -> int:
        """Number of rows."""
        return len(self._columns["time"]) if self._names else 0

    @property
    def summary(self) -> Dict[str, Any]:
        """The run summary ``umsim run`` prints: ``engine``, ``t_end`` (s),
        ``steps``, ``rejected_steps``, ``newton_iterations``,
        ``jacobian_evaluations``, ``dynamics_evaluations``, ``cpu_time`` (s),
        ``realtime_factor``, ``rows`` and ``error`` (``None`` or the message)."""
        return dict(self._summary)

    def assessment(self) -> Any:
        """The EN 14363 table ``umsim run`` prints at the end, as a pandas
        DataFrame: one row per wheelset and quantity (Y/Q left/right against
        Nadal, ΣY against Prud'homme as 2 m sliding means, Q max/min) with
        columns ``element``, ``quantity``, ``unit``, ``max``, ``time`` (s),
        ``limit``, ``limit_name``, ``ratio`` (max/limit). Empty for models
        without wheel–rail contacts."""
        import pandas as pd

        cols = ["element", "quantity", "unit", "max", "time", "limit", "limit_name", "ratio"]
        return pd.DataFrame(self._assessment, columns=cols)

    def assessment_rows(self) -> List[Dict[str, Any]]:
        """The assessment table as a list of dicts (no pandas needed)."""
        return [dict(r) for r in self._assessment]

    def to_pandas(self, index: Optional[str] = None) -> Any:
        """All columns as a pandas DataFrame (``index``: a column to index by,
        e.g. ``"time"`` or ``"s[m]"``)."""
        import pandas as pd

        df = pd.DataFrame({n: self._columns[n] for n in self._names}, columns=self._names)
        return df.set_index(index) if index is not None else df

    def __repr__(self) -> str:
        s = self._summary
        return (
            f"RunResult({len(self)} rows × {len(self._names)} columns, "
            f"engine={s.get('engine')!r}, t_end={s.get('t_end')} s, steps={s.get('steps')})"
        )

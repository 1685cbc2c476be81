"""Results of the analyses of a scenario: :meth:`railmbs.Scenario.equilibrium`,
:meth:`~railmbs.Scenario.modes`, :meth:`~railmbs.Scenario.critical_speed` and
:meth:`~railmbs.Scenario.curving` (the Rust functions of ``umsim
equilibrium``, ``umsim modes``, ``umsim critical-speed`` and ``umsim
curving``; the numbers are theirs).

Arrays are numpy arrays; the tables are pandas DataFrames (pandas is needed
only for the methods that return one). Units are SI: m, rad, s, N, Hz; a
damping ratio is dimensionless (negative: unstable)::

    import railmbs
    sc = railmbs.Scenario.load("models/scenarios/vehicle1_equilibrium_straight.ron")
    eq = sc.equilibrium()
    eq.wheel_loads()                       # element, side, Q[N], Y[N]
    m = sc.modes()                         # at the scenario's speed
    m.table()                              # frequency[Hz], damping_ratio, name, …
    locus = sc.modes(speed=range(10, 80, 2))
    locus.critical_speed                   # m/s, or None
    c = sc.curving(radius=600.0, cant=0.1, speed=[20.0, 25.0])
    c.wheels()                             # speed, element, side, Q, Y, Y/Q
"""

from __future__ import annotations

from typing import Any, Dict, List, Optional

import numpy as np

from .result import RunResult


class Equilibrium:
    """A static (steady) equilibrium: the state and, from
    :meth:`Scenario.equilibrium`, the wheel loads.

    Attributes:
        t: time, s.
        coordinates: system coordinate names (the model's, then the force
            elements' first-order states), in order.
        units, rate_units: the unit of each coordinate and of its rate
            (``m``/``rad``, ``m/s``/``rad/s``).
        roles: what the solve did with each: ``solved`` (position solved,
            at rest), ``rate solved`` (a rolling wheel's spin rate), ``held``.
        q, v: the coordinates (m, rad) and their rates (m/s, rad/s).
        q_start, v_start: the starting guess.
        iterations: Newton iterations; residual, tolerance: the largest
            residual force at the solution and the one accepted (N or N m);
        seconds: wall-clock time of the solve, s.
    """

    def __init__(self, d: Dict[str, Any]) -> None:
        self.t: float = d["t"]
        self.coordinates: List[str] = list(d["coordinates"])
        self.units: List[str] = list(d["units"])
        self.rate_units: List[str] = list(d["rate_units"])
        self.roles: List[str] = list(d["roles"])
        self.q: np.ndarray = d["q"]
        self.v: np.ndarray = d["v"]
        self.q_start: np.ndarray = d["q_start"]
        self.v_start: np.ndarray = d["v_start"]
        self.iterations: int = d["iterations"]
        self.residual: float = d["residual"]
        self.tolerance: float = d["tolerance"]
        self.seconds: float = d["seconds"]
        self._loads: List[Dict[str, Any]] = list(d.get("wheel_loads", []))

    def __getitem__(self, coordinate: str) -> float:
        """The value of ``coordinate`` (m or rad)."""
        try:
            return float(self.q[self.coordinates.index(coordinate)])
        except ValueError:
            raise KeyError(f"no coordinate {coordinate!r}") from None

    def state(self) -> Any:
        """One row per coordinate: ``coordinate``, ``role``, ``value``,
        ``rate``, ``change`` (from the starting guess; of the rate for a
        solved rate), ``unit``, ``rate_unit`` (a DataFrame)."""
        import pandas as pd

        change = [
            (self.v[i] - self.v_start[i]) if r == "rate solved" else (self.q[i] - self.q_start[i])
            for i, r in enumerate(self.roles)
        ]
        return pd.DataFrame(
            {
                "coordinate": self.coordinates,
                "role": self.roles,
                "value": self.q,
                "rate": self.v,
                "change": change,
                "unit": self.units,
                "rate_unit": self.rate_units,
            }
        )

    def wheel_loads(self) -> Any:
        """One row per wheel: ``element`` (the wheel–rail element), ``side``
        (``left``/``right``), ``Q[N]`` (vertical load) and ``Y[N]`` (lateral
        force on the rail, positive towards the field side), a DataFrame.
        Empty without wheel–rail contacts."""
        import pandas as pd

        return pd.DataFrame(self._loads, columns=["element", "side", "Q[N]", "Y[N]"])

    @property
    def total_wheel_load(self) -> float:
        """The sum of the wheel loads Q, N (the weight on the rails)."""
        return float(sum(r["Q[N]"] for r in self._loads))

    def __repr__(self) -> str:
        return (
            f"Equilibrium({len(self.coordinates)} coordinates, {self.iterations} iterations, "
            f"residual {self.residual:.2e}, {len(self._loads)} wheels)"
        )


class Modes:
    """The linear modes at one speed.

    Attributes:
        speed: running speed, m/s (0 off a track).
        coordinates: the system coordinates the shapes are given in.
        shapes: complex mode shapes, one row per mode (in :meth:`table`
            order), one column per coordinate (m or rad per unit of the
            dominant coordinate, which is 1 + 0j).
        zero_modes: the zero eigenvalues (coordinates nothing depends on,
            such as spin angles), named.
        equilibrium: the steady state linearized about
            (:class:`Equilibrium`, without wheel loads).
        a: the state matrix A of d/dt δx = A δx (1/s); states: its state
            names (positions, then ``.v`` rates, then element states).
        seconds: wall-clock seconds of the equilibrium (with the set-up),
            the linearization and the eigendecomposition.
    """

    def __init__(self, d: Dict[str, Any]) -> None:
        self.speed: float = d["speed"]
        self.coordinates: List[str] = list(d["coordinates"])
        self._rows: List[Dict[str, Any]] = list(d["modes"])
        n, m = len(self._rows), len(self.coordinates)
        self.shapes: np.ndarray = (
            np.asarray(d["shape_re"]).reshape(n, m) + 1j * np.asarray(d["shape_im"]).reshape(n, m)
        )
        self.zero_modes: List[str] = list(d["zero_modes"])
        self.equilibrium = Equilibrium(d["equilibrium"])
        k = len(d["states"])
        self.a: np.ndarray = np.asarray(d["a"]).reshape(k, k)
        self.states: List[str] = list(d["states"])
        self.seconds: List[float] = list(d["seconds"])

    def __len__(self) -> int:
        return len(self._rows)

    def rows(self) -> List[Dict[str, Any]]:
        """The modes as dicts (no pandas needed), sorted by natural frequency."""
        return [dict(r) for r in self._rows]

    def table(self) -> Any:
        """One row per mode (of each complex pair the one with ω > 0),
        sorted by natural frequency: ``frequency[Hz]`` (damped, ω/2π),
        ``natural_frequency[Hz]`` (|λ|/2π), ``damping_ratio`` (−σ/|λ|),
        ``re[1/s]`` (σ), ``im[rad/s]`` (ω), ``lateral_share`` (share of
        the kinetic energy in lateral and yaw coordinates), ``lateral``
        (a hunting candidate) and ``name`` (the dominant coordinates), a
        DataFrame."""
        import pandas as pd

        cols = [
            "frequency[Hz]",
            "natural_frequency[Hz]",
            "damping_ratio",
            "re[1/s]",
            "im[rad/s]",
            "lateral_share",
            "lateral",
            "name",
        ]
        return pd.DataFrame(self._rows, columns=cols)

    @property
    def eigenvalues(self) -> np.ndarray:
        """The eigenvalues σ + iω (1/s) of the modes, in table order."""
        return np.array([complex(r["re[1/s]"], r["im[rad/s]"]) for r in self._rows])

    def least_damped_lateral(self) -> Optional[Dict[str, Any]]:
        """The least damped lateral (hunting candidate) mode as a dict of
        :meth:`table`'s columns, ``None`` without one."""
        lateral = [r for r in self._rows if r["lateral"]]
        return dict(min(lateral, key=lambda r: r["damping_ratio"])) if lateral else None

    def __repr__(self) -> str:
        return f"Modes({len(self._rows)} modes at {self.speed} m/s, {len(self.zero_modes)} zero)"


class Locus:
    """Modes over speed (the root locus) or over a model parameter.

    Attributes:
        axis: ``speed[m/s]`` or the parameter's name.
        values: its value at each point.
        modes: the :class:`Modes` at each point.
        critical: where the least damped lateral mode's damping ratio first
            crosses zero (interpolated linearly), ``None`` if it does not.
    """

    def __init__(self, d: Dict[str, Any]) -> None:
        self.axis: str = d["axis"]
        self.values: np.ndarray = d["values"]
        self.modes: List[Modes] = list(d["modes"])
        self.critical: Optional[float] = d["critical"]

    @property
    def critical_speed(self) -> Optional[float]:
        """The linear critical speed, m/s, of a root locus (``None`` if the
        hunting mode's damping ratio does not cross zero in the range)."""
        if self.axis != "speed[m/s]":
            raise ValueError(f"a locus over {self.axis!r} has no critical speed; see .critical")
        return self.critical

    def table(self) -> Any:
        """One row per point and mode: the axis column, then
        :meth:`Modes.table`'s columns, a DataFrame."""
        import pandas as pd

        frames = []
        for x, m in zip(self.values, self.modes):
            t = m.table()
            t.insert(0, self.axis, x)
            frames.append(t)
        return pd.concat(frames, ignore_index=True)

    def least_damped(self) -> Any:
        """One row per point: the axis, then the least damped lateral
        mode's ``frequency[Hz]``, ``damping_ratio`` and ``name`` (NaN/None
        without one), a DataFrame."""
        import pandas as pd

        rows = []
        for x, m in zip(self.values, self.modes):
            r = m.least_damped_lateral() or {}
            rows.append(
                {
                    self.axis: x,
                    "frequency[Hz]": r.get("frequency[Hz]", np.nan),
                    "damping_ratio": r.get("damping_ratio", np.nan),
                    "name": r.get("name"),
                }
            )
        return pd.DataFrame(rows)

    def __len__(self) -> int:
        return len(self.modes)

    def __repr__(self) -> str:
        return f"Locus({len(self.modes)} points over {self.axis}, critical={self.critical})"


class _Run:
    """What both nonlinear critical-speed results hold."""

    def __init__(self, d: Dict[str, Any]) -> None:
        self.signals: List[str] = list(d["signals"])
        self.result: RunResult = d["result"]
        self.error: Optional[str] = d["error"]
        self.window: float = d["window"]
        self.threshold: float = d["threshold"]
        self.on: float = d["on"]
        self.relative: float = d["relative"]


class CriticalSpeed(_Run):
    """The nonlinear critical speed of a decelerating run.

    Attributes:
        speed: the running speed where the lateral limit cycle died out
            (at its last extreme), m/s; ``None`` if none died out.
        detection: ``collapsed``, ``still_hunting`` (the cycle goes on at the
            end of the run: decelerate further) or ``no_limit_cycle``.
        t: time of the collapse, s; position: arc position there, m
            (``None`` off a track or without a collapse).
        amplitude: the collapsed cycle's largest amplitude (or the one at
            the end, or the largest seen), in the signals' unit (m).
        signals: the coordinates watched; result: the run's rows
            (:class:`railmbs.RunResult`); error: the run's error if it
            stopped early.
        window, threshold, on, relative: the detection's settings.
    """

    def __init__(self, d: Dict[str, Any]) -> None:
        super().__init__(d)
        self.detection: str = d["detection"]
        self.speed: Optional[float] = d["speed"]
        self.t: Optional[float] = d["t"]
        self.position: Optional[float] = d["position"]
        self.amplitude: float = d["amplitude"]
        self.end_speed: Optional[float] = d.get("end_speed")

    def __repr__(self) -> str:
        return f"CriticalSpeed({self.detection}, speed={self.speed})"


class Bifurcation(_Run):
    """A bifurcation diagram: the limit-cycle amplitude on each constant-speed
    plateau of one continuation run.

    Attributes:
        signals, result, error, window, threshold, on, relative: as for
            :class:`CriticalSpeed`.
    """

    def __init__(self, d: Dict[str, Any]) -> None:
        super().__init__(d)
        self._points: List[Dict[str, Any]] = list(d["points"])

    def table(self) -> Any:
        """One row per plateau reached, highest speed first: ``speed[m/s]``,
        ``amplitude`` (half the range over the measuring window, largest over
        the signals, m), ``early`` and ``late`` (over its two halves) and
        ``settled`` (the halves agree within 5 %, or are below the
        threshold), a DataFrame."""
        import pandas as pd

        cols = ["speed[m/s]", "amplitude", "early", "late", "settled"]
        return pd.DataFrame(self._points, columns=cols)

    @property
    def speeds(self) -> np.ndarray:
        """Plateau speeds, m/s."""
        return np.array([p["speed[m/s]"] for p in self._points])

    @property
    def amplitudes(self) -> np.ndarray:
        """Amplitude per plateau, m."""
        return np.array([p["amplitude"] for p in self._points])

    def __repr__(self) -> str:
        return f"Bifurcation({len(self._points)} plateaus)"


class Curving:
    """Quasi-static curving solutions, one per speed.

    Attributes:
        solutions: per speed a dict: ``radius`` (m), ``cant`` (m),
            ``speed`` (m/s), ``cant_deficiency_acceleration`` (m/s²),
            ``equilibrium`` (:class:`Equilibrium`), ``wheelsets`` (per
            wheel–rail element: ``element``, ``wheelset``, ``lateral`` (m),
            ``yaw`` (rad), ``outputs``: every output column of the element
            by its CSV name, ``L.Q [N]``, ``SumY [N]``, …) and ``seconds``.
    """

    def __init__(self, d: Dict[str, Any]) -> None:
        self.solutions: List[Dict[str, Any]] = []
        for s in d["solutions"]:
            s = dict(s)
            s["equilibrium"] = Equilibrium(s["equilibrium"])
            self.solutions.append(s)

    @property
    def speeds(self) -> np.ndarray:
        """The speeds, m/s."""
        return np.array([s["speed"] for s in self.solutions])

    def wheelsets(self) -> Any:
        """One row per speed and wheelset: ``speed[m/s]``, ``radius[m]``,
        ``cant[m]``, ``element``, ``wheelset``, ``y[m]`` (lateral position
        relative to the track centre line, positive left), ``yaw[rad]``
        (angle of attack), then every output column of the element (``L.Q
        [N]``, ``R.Y [N]``, ``L.Fx [N]``, ``L.Tgamma [N]``, ``SumY [N]``, …),
        a DataFrame."""
        import pandas as pd

        rows = []
        for s in self.solutions:
            for w in s["wheelsets"]:
                row = {
                    "speed[m/s]": s["speed"],
                    "radius[m]": s["radius"],
                    "cant[m]": s["cant"],
                    "element": w["element"],
                    "wheelset": w["wheelset"],
                    "y[m]": np.nan if w["lateral"] is None else w["lateral"],
                    "yaw[rad]": np.nan if w["yaw"] is None else w["yaw"],
                }
                row.update(w["outputs"])
                rows.append(row)
        return pd.DataFrame(rows)

    def wheels(self) -> Any:
        """One row per speed and wheel: ``speed[m/s]``, ``element``,
        ``side`` (``left``/``right``), ``Q[N]``, ``Y[N]``, ``Y/Q`` and
        ``Tgamma[N]`` (wear number), a DataFrame."""
        import pandas as pd

        rows = []
        for s in self.solutions:
            for w in s["wheelsets"]:
                o = w["outputs"]
                for key, side in (("L", "left"), ("R", "right")):
                    rows.append(
                        {
                            "speed[m/s]": s["speed"],
                            "element": w["element"],
                            "side": side,
                            "Q[N]": o[f"{key}.Q [N]"],
                            "Y[N]": o[f"{key}.Y [N]"],
                            "Y/Q": o[f"{key}.Y/Q [-]"],
                            "Tgamma[N]": o[f"{key}.Tgamma [N]"],
                        }
                    )
        return pd.DataFrame(rows)

    def __len__(self) -> int:
        return len(self.solutions)

    def __repr__(self) -> str:
        return f"Curving({len(self.solutions)} speeds)"

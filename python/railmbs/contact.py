"""The wheel–rail contact library over numpy arrays (SI units throughout).

Array arguments broadcast against each other as in numpy, and the results
have the broadcast shape. The functions are those behind ``umsim conicity``
and ``umsim creep``; creep laws are written as ``umsim creep --method``
takes them (:data:`railmbs.CREEP_LAW_SYNTAX`).
"""

from __future__ import annotations

from typing import Any, Dict, Optional, Tuple, Union

import numpy as np

from . import _railmbs

ArrayLike = Union[float, "np.ndarray", Any]

#: Amplitudes ``umsim conicity`` reports: 0.5 to 10 mm in steps of 0.5 mm, m.
CONICITY_AMPLITUDES = np.arange(1, 21) * 0.5e-3


def _flat(*arrays: ArrayLike) -> Tuple[Tuple[int, ...], list]:
    """The broadcast shape and each array flattened to contiguous float64."""
    b = np.broadcast_arrays(*[np.asarray(a, dtype=np.float64) for a in arrays])
    shape = b[0].shape if b else ()
    return shape, [np.ascontiguousarray(x.ravel()) for x in b]


def _shaped(d: Dict[str, Any], shape: Tuple[int, ...]) -> Dict[str, Any]:
    return {k: (_shaped(v, shape) if isinstance(v, dict) else v.reshape(shape)) for k, v in d.items()}


class Profile:
    """A wheel or rail profile, smoothed by a spline.

    Library convention: lateral coordinate ``u`` (m) and height ``h`` (m, up);
    see the ``railmbs_wheelrail::profile`` docs for the file formats.
    """

    def __init__(self, inner: Any) -> None:
        self._inner = inner

    @classmethod
    def read(
        cls,
        path: Any,
        kind: Optional[str] = None,
        smoothing: float = 1e-4,
        rail_inclination: float = 0.0,
    ) -> "Profile":
        """Reads a profile file: ``.prw``/``.whl`` wheels and ``.prr``/``.ban``
        rails (SIMPACK, MiniProf); any other extension is two columns ``y z`` in
        mm and needs ``kind`` (``"wheel"`` or ``"rail"``). ``smoothing``: length
        of the smoothing spline, m (default 0.1 mm, 0 interpolates).
        ``rail_inclination``: rotation applied to a rail as read, rad
        (``atan(1/40)`` for 1:40; 0 for profiles inclined in their files)."""
        return cls(_railmbs.Profile.read(str(path), kind, smoothing, rail_inclination))

    @property
    def name(self) -> str:
        """The file it was read from."""
        return self._inner.name

    @property
    def kind(self) -> str:
        """``"wheel"`` or ``"rail"``."""
        return self._inner.kind

    @property
    def range(self) -> Tuple[float, float]:
        """Lateral range ``(u_min, u_max)`` of the profile, m."""
        return self._inner.range

    def evaluate(self, u: ArrayLike) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Height ``h`` (m), slope ``dh/du`` (–) and ``d²h/du²`` (1/m) at ``u``
        (m, inside :attr:`range`; outside raises ``ContactError``)."""
        shape, (uf,) = _flat(u)
        h, s, c = self._inner._evaluate(uf)
        return h.reshape(shape), s.reshape(shape), c.reshape(shape)

    def __repr__(self) -> str:
        return repr(self._inner)


def read_profile(
    path: Any, kind: Optional[str] = None, smoothing: float = 1e-4, rail_inclination: float = 0.0
) -> Profile:
    """Reads a profile file (see :meth:`Profile.read`)."""
    return Profile.read(path, kind, smoothing, rail_inclination)


class Wheelset:
    """A wheelset on a track, prepared for contact searches.

    ``wheel`` and ``rail`` are the left profiles and, unless ``wheel_right`` /
    ``rail_right`` are given, the right ones too. ``gauge`` (m, measured 14 mm
    below the rail tops), ``flange_back`` distance (m), nominal rolling
    ``radius`` at the taping line (m; ``radius_right`` if different). The
    defaults are EN 15302's standard set-up with 920 mm wheels.
    """

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
    ) -> None:
        self._inner = _railmbs.WheelsetGeometry(
            wheel._inner,
            rail._inner,
            wheel_right=None if wheel_right is None else wheel_right._inner,
            rail_right=None if rail_right is None else rail_right._inner,
            gauge=gauge,
            flange_back=flange_back,
            radius=radius,
            radius_right=radius_right,
        )

    @property
    def nominal_radius(self) -> float:
        """Mean nominal rolling radius, m."""
        return self._inner.nominal_radius

    def contacts(self, y: ArrayLike, roll: ArrayLike = 0.0) -> Dict[str, Any]:
        """Contact geometry at lateral shifts ``y`` (m, to the left) and rolls
        ``roll`` (rad), wheelset height 0 (each wheel at its smallest vertical
        distance to its rail).

        Returns ``{"left": {...}, "right": {...}, "delta_r": Δr}``; each side
        has arrays of the deepest contact: ``rolling_radius`` (m),
        ``contact_angle`` (rad, positive towards the flange), ``wheel_y``,
        ``wheel_z`` (m, wheelset frame), ``rail_y``, ``rail_z`` (m, track
        frame), ``wheel_u``, ``rail_u`` (m, profile coordinates), ``gap`` (m),
        curvatures (1/m), ``yaw_lead`` (m/rad), ``distance_slope`` (–) and
        ``count`` (1 or 2 contact points). ``delta_r`` = r_left − r_right (m).
        """
        shape, (yf, rf) = _flat(y, roll)
        d = _shaped(self._inner._contacts(yf, rf), shape)
        d["delta_r"] = d["left"]["rolling_radius"] - d["right"]["rolling_radius"]
        return d

    def rigid(self, y: ArrayLike) -> Dict[str, Any]:
        """The rigid wheelset at lateral shifts ``y`` (m): ``roll`` (rad) and
        ``z`` (m, axle height above nominal) at which both wheels touch, and
        the contacts there as in :meth:`contacts` (with ``delta_r``)."""
        shape, (yf,) = _flat(y)
        d = _shaped(self._inner._rigid(yf), shape)
        d["delta_r"] = d["left"]["rolling_radius"] - d["right"]["rolling_radius"]
        return d

    def equivalent_conicity(self, amplitudes: ArrayLike = CONICITY_AMPLITUDES, with_roll: bool = False) -> np.ndarray:
        """Equivalent conicity tan γe (–) by EN 15302 Annex B for wheelset
        amplitudes ``amplitudes`` (m; default 0.5…10 mm as ``umsim
        conicity``): Δr sampled every 0.1 mm, the roll neglected (as the
        standard's reference calculation) unless ``with_roll``."""
        shape, (af,) = _flat(amplitudes)
        return self._inner._conicity(af, with_roll).reshape(shape)

    def rolling_radius_difference(
        self, y_max: float = 0.01, dy: float = 1e-4, with_roll: bool = False
    ) -> Tuple[np.ndarray, np.ndarray]:
        """The Δr function the conicity integrates: ``(y, Δr)`` (m, m) at
        ``-y_max..=y_max`` in steps of ``dy`` (m)."""
        return self._inner.rolling_radius_difference(y_max, dy, with_roll)


def equivalent_conicity(
    wheel: Profile,
    rail: Profile,
    amplitudes: ArrayLike = CONICITY_AMPLITUDES,
    *,
    with_roll: bool = False,
    **wheelset: Any,
) -> np.ndarray:
    """Equivalent conicity (EN 15302) of a wheelset of ``wheel`` profiles on
    ``rail`` profiles; ``wheelset`` keywords as :class:`Wheelset`."""
    return Wheelset(wheel, rail, **wheelset).equivalent_conicity(amplitudes, with_roll)


def hertz(
    curv_a: ArrayLike,
    curv_b: ArrayLike,
    normal_force: ArrayLike,
    youngs_modulus: ArrayLike = 2.1e11,
    poisson_ratio: ArrayLike = 0.3,
) -> Dict[str, np.ndarray]:
    """Hertz contact of two bodies of one material: relative curvatures
    ``curv_a`` (rolling direction) and ``curv_b`` (transverse), 1/m, both
    positive (for a wheel of radius r on a rail crown of radius R with a
    straight tread: A = 1/(2r), B = 1/(2R)); ``normal_force`` N ≥ 0;
    ``youngs_modulus`` Pa; ``poisson_ratio`` –.

    Returns arrays ``a`` (semi-axis in the rolling direction, m), ``b``
    (transverse, m), ``approach`` (m) and ``p_max`` (peak pressure, Pa).
    """
    shape, flat = _flat(curv_a, curv_b, normal_force, youngs_modulus, poisson_ratio)
    return _shaped(_railmbs.hertz_contact(*flat), shape)


def creep_forces(
    law: str,
    a: ArrayLike,
    b: ArrayLike,
    normal_force: ArrayLike,
    xi: ArrayLike,
    eta: ArrayLike,
    phi: ArrayLike,
    *,
    shear_modulus: ArrayLike = 8.0e10,
    poisson_ratio: ArrayLike = 0.28,
    friction: ArrayLike = 0.3,
    speed: Optional[ArrayLike] = None,
) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Creep forces on the wheel by ``law`` (``"kalker"``, ``"mueller:3"``,
    ``"fastsim:10"``, ``"fastsim-a:20,sliding=integrated"``, ``"polach"``, …:
    the syntax of ``umsim creep --method``, see :data:`railmbs.CREEP_LAW_SYNTAX`).

    Contact ellipse semi-axes ``a`` (rolling direction) and ``b`` (m), normal
    force (N), longitudinal and lateral creepages ``xi``, ``eta`` (–), spin
    ``phi`` (1/m); ``shear_modulus`` G (Pa), ``poisson_ratio`` ν, coefficient
    of ``friction`` μ; ``speed`` (m/s) for laws with slip-velocity-dependent
    friction (Polach's friction decrease).

    Returns ``(Fx, Fy, Mz)`` in N, N, N·m with the input's broadcast shape, in
    the contact frame with CONTACT's sign convention (``Fx < 0`` for ``xi > 0``),
    as ``umsim creep`` writes them.
    """
    args = [a, b, shear_modulus, poisson_ratio, friction, normal_force, xi, eta, phi]
    if speed is not None:
        args.append(speed)
    shape, flat = _flat(*args)
    sp = flat[9] if speed is not None else None
    fx, fy, mz = _railmbs.creep_forces_flat(law, *flat[:9], speed=sp)
    return fx.reshape(shape), fy.reshape(shape), mz.reshape(shape)


def creep_law_name(law: str) -> str:
    """The creep law ``law`` with all its settings spelled out (its canonical
    text); raises ``ValueError`` with the syntax for a bad one."""
    return _railmbs.creep_law_name(law)

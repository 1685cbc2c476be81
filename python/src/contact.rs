//! The wheel–rail contact library over numpy arrays (`railmbs.contact`
//! wraps these with numpy broadcasting): profiles, contact geometry of a
//! wheelset on a track over lateral shift, EN 15302 equivalent conicity
//! (what `umsim conicity` computes), Hertz patches and creep forces by every
//! law in the syntax of `umsim creep --method` ([`CreepLawSpec`]'s
//! `FromStr`). All in SI units. The loops run with the GIL released.

use crate::errors;
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use railmbs_wheelrail::conicity::{RollTreatment, RollingRadiusDifference, conicity_curve};
use railmbs_wheelrail::creep::{ContactPatch, CreepLawSpec, Creepages};
use railmbs_wheelrail::geometry::{
    Contact, ContactGeometry, ContactSet, SearchSettings, Track, Wheelset,
};
use railmbs_wheelrail::hertz::HertzShape;
use railmbs_wheelrail::profile::{self, ProfileFormat, ProfileKind, ProfileSettings};
use std::path::PathBuf;

/// A `ContactError` with `message`.
fn contact_error(py: Python<'_>, message: impl std::fmt::Display) -> PyErr {
    errors::plain(py, "ContactError", message)
}

/// The slice of a contiguous float64 array (the Python side makes them so).
fn slice<'a>(a: &'a PyReadonlyArray1<'_, f64>, name: &str) -> PyResult<&'a [f64]> {
    a.as_slice().map_err(|_| {
        pyo3::exceptions::PyValueError::new_err(format!("{name}: expected a contiguous array"))
    })
}

/// Checks that all arrays have the length of the first.
fn same_length(arrays: &[(&str, &[f64])]) -> PyResult<usize> {
    let n = arrays.first().map_or(0, |a| a.1.len());
    for (name, a) in arrays {
        if a.len() != n {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "{name} has {} values, expected {n}",
                a.len()
            )));
        }
    }
    Ok(n)
}

/// A wheel or rail profile, smoothed (library convention: lateral `u`
/// outwards from the flange back or gauge side, height `h` up; m).
#[pyclass(module = "railmbs._railmbs", frozen)]
#[derive(Clone)]
pub struct Profile {
    inner: profile::Profile,
}

#[pymethods]
impl Profile {
    /// Reads a profile file: `.prw`/`.whl` wheels, `.prr`/`.ban` rails
    /// (SIMPACK, MiniProf), anything else two columns `y z` in mm with
    /// `kind` ("wheel" or "rail") given. `smoothing` is the smoothing
    /// spline's length (m, 0 interpolates; `umsim conicity --smoothing` in
    /// mm), `rail_inclination` a rotation applied to a rail as read (rad;
    /// 0 for profiles inclined in their files).
    #[staticmethod]
    #[pyo3(signature = (path, kind = None, smoothing = 1e-4, rail_inclination = 0.0))]
    fn read(
        py: Python<'_>,
        path: PathBuf,
        kind: Option<&str>,
        smoothing: f64,
        rail_inclination: f64,
    ) -> PyResult<Self> {
        let kind = match kind {
            Some("wheel") => ProfileKind::Wheel,
            Some("rail") => ProfileKind::Rail,
            Some(other) => {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "kind must be \"wheel\" or \"rail\", got {other:?}"
                )));
            }
            None => ProfileFormat::from_path(&path).1.ok_or_else(|| {
                contact_error(
                    py,
                    format!(
                        "{}: the extension does not tell a wheel from a rail; give kind=\"wheel\" or kind=\"rail\"",
                        path.display()
                    ),
                )
            })?,
        };
        if !(smoothing.is_finite() && smoothing >= 0.0) {
            return Err(contact_error(
                py,
                format!("smoothing must be ≥ 0 m, got {smoothing}"),
            ));
        }
        let settings = ProfileSettings {
            smoothing_length: smoothing,
            rail_inclination: if kind == ProfileKind::Rail {
                rail_inclination
            } else {
                0.0
            },
            ..Default::default()
        };
        profile::Profile::read(&path, kind, &settings)
            .map(|inner| Self { inner })
            .map_err(|e| contact_error(py, e))
    }

    /// The file it was read from.
    #[getter]
    fn name(&self) -> &str {
        self.inner.name()
    }

    /// "wheel" or "rail".
    #[getter]
    fn kind(&self) -> String {
        self.inner.kind().to_string()
    }

    /// Lateral range (u_min, u_max) where the profile is defined, m.
    #[getter]
    fn range(&self) -> (f64, f64) {
        self.inner.range()
    }

    /// Height (m), slope (–) and second derivative (1/m) at the lateral
    /// positions `u` (m, inside `range`).
    #[allow(clippy::type_complexity)]
    fn _evaluate<'py>(
        &self,
        py: Python<'py>,
        u: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<(
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
    )> {
        let u = slice(&u, "u")?;
        let (mut h, mut s, mut c) = (Vec::new(), Vec::new(), Vec::new());
        for &x in u {
            let v = self.inner.eval(x).ok_or_else(|| {
                let (a, b) = self.inner.range();
                contact_error(
                    py,
                    format!(
                        "{}: u = {x} m is outside the profile's range [{a}, {b}] m",
                        self.inner.name()
                    ),
                )
            })?;
            h.push(v.h);
            s.push(v.slope);
            c.push(v.second);
        }
        Ok((
            PyArray1::from_vec(py, h),
            PyArray1::from_vec(py, s),
            PyArray1::from_vec(py, c),
        ))
    }

    fn __repr__(&self) -> String {
        let (a, b) = self.inner.range();
        format!(
            "Profile({:?}, {}, u in [{a}, {b}] m)",
            self.inner.name(),
            self.inner.kind()
        )
    }
}

/// The contact quantities of one wheel, one vector per field.
#[derive(Default)]
struct SideColumns {
    count: Vec<f64>,
    fields: [Vec<f64>; FIELDS.len()],
}

/// Names of the fields of [`Contact`] returned per wheel (units in
/// [`Contact::values`]).
const FIELDS: [&str; 14] = Contact::FIELDS;

impl SideColumns {
    fn push(&mut self, set: &ContactSet) {
        self.count.push(set.count as f64);
        for (col, v) in self.fields.iter_mut().zip(set.deepest().values()) {
            col.push(v);
        }
    }

    fn into_dict<'py>(self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("count", PyArray1::from_vec(py, self.count))?;
        for (name, col) in FIELDS.iter().zip(self.fields) {
            d.set_item(*name, PyArray1::from_vec(py, col))?;
        }
        Ok(d)
    }
}

/// A wheelset on a track, prepared for contact searches (EN 15302's
/// set-up when the defaults are kept: taping lines 70 mm from the flange
/// backs, gauge measured 14 mm below the rail tops).
#[pyclass(module = "railmbs._railmbs", frozen)]
pub struct WheelsetGeometry {
    inner: ContactGeometry,
}

#[pymethods]
impl WheelsetGeometry {
    /// `wheel` and `rail` are the left profiles, and the right ones unless
    /// `wheel_right`/`rail_right` are given (same convention, mirrored when
    /// placed). `gauge` (m, 1.435), `flange_back` distance (m, 1.360),
    /// nominal rolling `radius` at the taping line (m, 0.46; `radius_right`
    /// if different).
    #[new]
    #[pyo3(signature = (wheel, rail, *, wheel_right = None, rail_right = None, gauge = 1.435, flange_back = 1.360, radius = 0.46, radius_right = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        wheel: &Profile,
        rail: &Profile,
        wheel_right: Option<&Profile>,
        rail_right: Option<&Profile>,
        gauge: f64,
        flange_back: f64,
        radius: f64,
        radius_right: Option<f64>,
    ) -> PyResult<Self> {
        let wr = wheel_right.unwrap_or(wheel);
        let rr = rail_right.unwrap_or(rail);
        let mut wheelset =
            Wheelset::new(wheel.inner.clone(), wr.inner.clone(), radius, flange_back);
        if let Some(r) = radius_right {
            wheelset.radius_right = r;
        }
        let track = Track::new(rail.inner.clone(), rr.inner.clone(), gauge);
        ContactGeometry::new(&wheelset, &track, SearchSettings::default())
            .map(|inner| Self { inner })
            .map_err(|e| contact_error(py, e))
    }

    /// Mean nominal rolling radius, m.
    #[getter]
    fn nominal_radius(&self) -> f64 {
        self.inner.nominal_radius()
    }

    /// Contacts of both wheels at lateral shifts `y` (m, to the left) and
    /// rolls `roll` (rad), wheelset height 0 (equal-length arrays).
    fn _contacts<'py>(
        &self,
        py: Python<'py>,
        y: PyReadonlyArray1<'py, f64>,
        roll: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (y, roll) = (slice(&y, "y")?, slice(&roll, "roll")?);
        same_length(&[("y", y), ("roll", roll)])?;
        let sides = py
            .detach(|| {
                let mut sides = [SideColumns::default(), SideColumns::default()];
                for (&y, &r) in y.iter().zip(roll) {
                    let c = self.inner.contacts(y, r)?;
                    sides[0].push(&c[0]);
                    sides[1].push(&c[1]);
                }
                Ok::<_, railmbs_wheelrail::geometry::GeometryError>(sides)
            })
            .map_err(|e| contact_error(py, e))?;
        let [left, right] = sides;
        let d = PyDict::new(py);
        d.set_item("left", left.into_dict(py)?)?;
        d.set_item("right", right.into_dict(py)?)?;
        Ok(d)
    }

    /// The rigid wheelset at lateral shifts `y` (m): roll (rad) and height
    /// (m) at which both wheels touch, and the contacts there.
    fn _rigid<'py>(
        &self,
        py: Python<'py>,
        y: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let y = slice(&y, "y")?;
        let rigid = py
            .detach(|| self.inner.rigid_functions(y))
            .map_err(|e| contact_error(py, e))?;
        let mut sides = [SideColumns::default(), SideColumns::default()];
        let (mut roll, mut z) = (Vec::new(), Vec::new());
        for r in &rigid {
            roll.push(r.roll);
            z.push(r.z);
            sides[0].push(&r.sides[0]);
            sides[1].push(&r.sides[1]);
        }
        let [left, right] = sides;
        let d = PyDict::new(py);
        d.set_item("roll", PyArray1::from_vec(py, roll))?;
        d.set_item("z", PyArray1::from_vec(py, z))?;
        d.set_item("left", left.into_dict(py)?)?;
        d.set_item("right", right.into_dict(py)?)?;
        Ok(d)
    }

    /// Equivalent conicity tan γe (–) by EN 15302 Annex B for the
    /// wheelset amplitudes `amplitudes` (m), as `umsim conicity` computes
    /// it: Δr sampled every 0.1 mm, the roll neglected unless `with_roll`.
    #[pyo3(signature = (amplitudes, with_roll = false))]
    fn _conicity<'py>(
        &self,
        py: Python<'py>,
        amplitudes: PyReadonlyArray1<'py, f64>,
        with_roll: bool,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let a = slice(&amplitudes, "amplitudes")?;
        let curve = py
            .detach(|| conicity_curve(&self.inner, a, roll_treatment(with_roll)))
            .map_err(|e| contact_error(py, e))?;
        Ok(PyArray1::from_vec(
            py,
            curve.into_iter().map(|(_, t)| t).collect(),
        ))
    }

    /// The rolling radius difference function Δr = r_left − r_right (m)
    /// sampled at `−y_max..=y_max` step `dy` (m), as the conicity uses it:
    /// returns (y, Δr).
    #[pyo3(signature = (y_max = 0.01, dy = 1e-4, with_roll = false))]
    #[allow(clippy::type_complexity)]
    fn rolling_radius_difference<'py>(
        &self,
        py: Python<'py>,
        y_max: f64,
        dy: f64,
        with_roll: bool,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
        let f = py
            .detach(|| {
                RollingRadiusDifference::from_geometry(
                    &self.inner,
                    y_max,
                    dy,
                    roll_treatment(with_roll),
                )
            })
            .map_err(|e| contact_error(py, e))?;
        Ok((
            PyArray1::from_slice(py, f.y()),
            PyArray1::from_slice(py, f.delta_r()),
        ))
    }
}

fn roll_treatment(with_roll: bool) -> RollTreatment {
    if with_roll {
        RollTreatment::Rigid
    } else {
        RollTreatment::Neglected
    }
}

/// Hertz contacts (equal-length arrays): relative curvatures `curv_a`
/// (rolling direction) and `curv_b` (transverse), 1/m, normal force `n`
/// (N), Young's modulus `e` (Pa) and Poisson ratio `nu` of wheel and rail.
/// Returns a dict of arrays `a`, `b` (semi-axes, m), `approach` (m),
/// `p_max` (Pa).
#[pyfunction]
pub fn hertz_contact<'py>(
    py: Python<'py>,
    curv_a: PyReadonlyArray1<'py, f64>,
    curv_b: PyReadonlyArray1<'py, f64>,
    n: PyReadonlyArray1<'py, f64>,
    e: PyReadonlyArray1<'py, f64>,
    nu: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let cols = [
        ("curv_a", slice(&curv_a, "curv_a")?),
        ("curv_b", slice(&curv_b, "curv_b")?),
        ("n", slice(&n, "n")?),
        ("e", slice(&e, "e")?),
        ("nu", slice(&nu, "nu")?),
    ];
    let len = same_length(&cols)?;
    let out = py
        .detach(|| {
            let mut out: [Vec<f64>; 4] = Default::default();
            for k in 0..len {
                let [ca, cb, n, e, nu] = cols.map(|c| c.1[k]);
                let c = HertzShape::new(ca, cb, e, nu)
                    .and_then(|s| s.contact(n))
                    .map_err(|err| format!("entry {k}: {err}"))?;
                for (col, v) in out.iter_mut().zip([c.a, c.b, c.approach, c.p_max]) {
                    col.push(v);
                }
            }
            Ok::<_, String>(out)
        })
        .map_err(|e| contact_error(py, e))?;
    let d = PyDict::new(py);
    for (name, col) in ["a", "b", "approach", "p_max"].into_iter().zip(out) {
        d.set_item(name, PyArray1::from_vec(py, col))?;
    }
    Ok(d)
}

/// The law `law` in the syntax of `umsim creep --method`, or a
/// `ValueError` with the syntax.
fn creep_law(law: &str) -> PyResult<CreepLawSpec> {
    law.parse()
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("{e}")))
}

/// The canonical text of the creep law `law` (its settings spelled out).
#[pyfunction]
pub fn creep_law_name(law: &str) -> PyResult<String> {
    Ok(creep_law(law)?.to_string())
}

/// Creep forces on the wheel by `law` (equal-length arrays, CONTACT's sign
/// convention as `umsim creep`): patch semi-axes `a`, `b` (m), shear
/// modulus `g` (Pa), Poisson ratio `nu`, friction `mu`, normal force `n`
/// (N), creepages `xi`, `eta` (–), spin `phi` (1/m), and the rolling speed
/// `speed` (m/s, for Polach's friction decrease; `None` ignores it).
/// Returns (Fx N, Fy N, Mz N·m).
#[pyfunction]
#[pyo3(signature = (law, a, b, g, nu, mu, n, xi, eta, phi, speed = None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub fn creep_forces_flat<'py>(
    py: Python<'py>,
    law: &str,
    a: PyReadonlyArray1<'py, f64>,
    b: PyReadonlyArray1<'py, f64>,
    g: PyReadonlyArray1<'py, f64>,
    nu: PyReadonlyArray1<'py, f64>,
    mu: PyReadonlyArray1<'py, f64>,
    n: PyReadonlyArray1<'py, f64>,
    xi: PyReadonlyArray1<'py, f64>,
    eta: PyReadonlyArray1<'py, f64>,
    phi: PyReadonlyArray1<'py, f64>,
    speed: Option<PyReadonlyArray1<'py, f64>>,
) -> PyResult<(
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
)> {
    let law = creep_law(law)?.build().map_err(|e| contact_error(py, e))?;
    let cols = [
        ("a", slice(&a, "a")?),
        ("b", slice(&b, "b")?),
        ("G", slice(&g, "G")?),
        ("nu", slice(&nu, "nu")?),
        ("mu", slice(&mu, "mu")?),
        ("N", slice(&n, "N")?),
        ("xi", slice(&xi, "xi")?),
        ("eta", slice(&eta, "eta")?),
        ("phi", slice(&phi, "phi")?),
    ];
    let len = same_length(&cols)?;
    let speed = match &speed {
        Some(s) => {
            let s = slice(s, "speed")?;
            same_length(&[("a", cols[0].1), ("speed", s)])?;
            Some(s)
        }
        None => None,
    };
    let out = py
        .detach(|| {
            let mut out: [Vec<f64>; 3] = Default::default();
            for k in 0..len {
                let [a, b, g, nu, mu, n, xi, eta, phi] = cols.map(|c| c.1[k]);
                let patch = ContactPatch { a, b, g, nu, mu, n };
                let c = Creepages { xi, eta, phi };
                let f = match speed {
                    Some(s) => law.forces_at_speed(&patch, &c, s[k]),
                    None => law.forces(&patch, &c),
                }
                .map_err(|e| format!("entry {k}: {e}"))?;
                if !(f.fx.is_finite() && f.fy.is_finite() && f.mz.is_finite()) {
                    return Err(format!(
                        "entry {k}: {} gives a non-finite result ({}, {}, {})",
                        law.name(),
                        f.fx,
                        f.fy,
                        f.mz
                    ));
                }
                for (col, v) in out.iter_mut().zip([f.fx, f.fy, f.mz]) {
                    col.push(v);
                }
            }
            Ok(out)
        })
        .map_err(|e| contact_error(py, e))?;
    let [fx, fy, mz] = out;
    Ok((
        PyArray1::from_vec(py, fx),
        PyArray1::from_vec(py, fy),
        PyArray1::from_vec(py, mz),
    ))
}

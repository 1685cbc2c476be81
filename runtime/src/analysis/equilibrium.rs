//! Static (steady) equilibrium: the state at which nothing accelerates.
//!
//! With M(q) q̈ = f(t, q, q̇) + Gᵀλ and g(q) = 0, an equilibrium at time t
//! has q̈ = 0, i.e. f + Gᵀλ = 0 and g = 0. Which coordinates are unknown
//! follows from the model at the starting guess (q₀, q̇₀), by the columns of
//! the difference Jacobians of f:
//!
//! - a coordinate on which some force depends (a column of ∂f/∂q above the
//!   rounding noise: a spring, a contact, gravity on a pendulum) is a
//!   **position** unknown, at rest relative to its frame (q̇ = 0);
//! - a coordinate without stiffness that moves (q̇₀ ≠ 0) and on whose rate
//!   some force depends (a wheelset's spin: the creep forces) is a **rate**
//!   unknown: it keeps its position and rolls at the rate that balances it
//!   ("without stiffness" for a moving coordinate: below 1e-6 of the
//!   stiffest column, as an elastic rail's inner iteration leaves a few
//!   N/rad of noise in a spin's column against contact stiffnesses of
//!   1e8 N/m);
//! - any other coordinate is **held** as given (position and rate: a free
//!   longitudinal coordinate, a spin angle without creep). Its equation must
//!   hold by itself; if it does not (a body without support falls), there is
//!   no equilibrium and the error says which held coordinates carry the
//!   unbalanced force.
//!
//! Vehicle coordinates are relative to track-following frames that move at
//! the running speed, so "at rest relative to its frame" is steady motion at
//! that speed. Newton's method on the unknowns (forward-difference Jacobian
//! of the full model, solved by a column-equilibrated SVD that names an
//! unconstrained direction instead of dividing by zero), with a backtracking
//! line search on |r|₂ and a cap on the size of a step.

use super::{CoordinateInfo, ForceEvaluator, noise_level, position_step, rate_step};
use crate::system::{MechanicalSystem, SimError};
use nalgebra::{DMatrix, DVector};

/// What the solve does with a coordinate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// Its position is unknown; its rate is zero (at rest in its frame).
    Position,
    /// Its rate is unknown (rolling without stiffness); its position stays.
    Rate,
    /// Position and rate stay as given (no stiffness, nothing depends on it).
    Held,
}

impl Role {
    /// A word for tables: `solved`, `rate solved`, `held`.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Position => "solved",
            Self::Rate => "rate solved",
            Self::Held => "held",
        }
    }
}

/// Settings of the equilibrium solve.
#[derive(Debug, Clone, PartialEq)]
pub struct EquilibriumSettings {
    /// Newton iterations before giving up.
    pub max_iterations: usize,
    /// Largest |f + Gᵀλ| accepted, N (N m for rotations); `None`: 1e-9 of
    /// max(1, max Mᵢᵢ g) with g = 9.81 m/s² and Mᵢᵢ in kg or kg m² (0.019
    /// for Vehicle 1, whose car body's pitch inertia is 1.97e6 kg m²: on a
    /// 1813 kg wheelset an acceleration of 1e-5 m/s², a drift of 5e-8 m in
    /// 0.1 s).
    pub force_tolerance: Option<f64>,
    /// Largest change of a position in one Newton step, m or rad (the
    /// line search starts from a step shortened to it).
    pub max_step: f64,
    /// Largest relative change of a rate in one Newton step.
    pub max_rate_change: f64,
    /// Smaller limits than `max_step` for particular positions: (system
    /// coordinate index, largest change in one Newton step, m or rad). A
    /// wheelset's lateral shift, say, kept from crossing its flangeway in
    /// one step while the car body moves freely.
    pub step_limits: Vec<(usize, f64)>,
    /// Chord steps: after a full Newton step that at least halved |r|₂,
    /// the next step reuses that step's Jacobian instead of a fresh
    /// difference Jacobian (one evaluation of the model instead of one per
    /// unknown); a chord step that does not decrease |r|₂ by the line
    /// search's criterion at full length is dropped and taken again with
    /// a fresh Jacobian. Off by default (the steady states of runs and
    /// analyses are found with fresh Jacobians only).
    pub chord_steps: bool,
}

impl Default for EquilibriumSettings {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            force_tolerance: None,
            max_step: 0.1,
            max_rate_change: 0.1,
            step_limits: Vec::new(),
            chord_steps: false,
        }
    }
}

/// An equilibrium found.
#[derive(Debug, Clone, PartialEq)]
pub struct Equilibrium {
    /// Time, s.
    pub t: f64,
    /// System coordinates (coordinates, then element states), m or rad.
    pub q: Vec<f64>,
    /// Their rates (zero except for rolling and held coordinates).
    pub v: Vec<f64>,
    /// The starting guess q₀.
    pub q_start: Vec<f64>,
    /// The starting guess q̇₀.
    pub v_start: Vec<f64>,
    /// Lagrange multipliers of the closed loops' constraints.
    pub lambda: Vec<f64>,
    /// What the solve did with each coordinate.
    pub roles: Vec<Role>,
    /// Newton iterations taken.
    pub iterations: usize,
    /// Largest |f + Gᵀλ| at the solution, over all coordinates, N or N m.
    pub residual: f64,
    /// The tolerance it met, N or N m.
    pub tolerance: f64,
    /// Wall-clock time of the solve, s (a benchmark figure).
    pub seconds: f64,
}

/// Why no equilibrium was found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EquilibriumError {
    /// Newton's method did not reach the tolerance.
    #[error(
        "no equilibrium within {iterations} iterations: the largest residual force is {residual:.3e} \
         (tolerance {tolerance:.1e}), carried by {}",
        list(carriers, "")
    )]
    NotConverged {
        /// Iterations taken.
        iterations: usize,
        /// Largest |f + Gᵀλ| at the last iterate, N or N m.
        residual: f64,
        /// The tolerance, N or N m.
        tolerance: f64,
        /// The coordinates with the largest residuals, with them (N or N m).
        carriers: Vec<(String, f64)>,
    },
    /// The coordinates without stiffness that are held carry forces that
    /// nothing balances.
    #[error(
        "no static equilibrium: coordinates without stiffness (held as given) carry unbalanced \
         forces: {}; support them or give them stiffness",
        list(carriers, "")
    )]
    Unbalanced {
        /// The held coordinates and their residual forces, N or N m.
        carriers: Vec<(String, f64)>,
    },
    /// The Jacobian of the unknowns is singular: a direction that no force
    /// resists.
    #[error(
        "the equilibrium is not unique: no force resists the motion {} (a free or \
         unconstrained direction; hold it by a spring or fix the coordinate)",
        list(direction, " ×")
    )]
    Unconstrained {
        /// The coordinates of the direction, with their components
        /// (largest 1).
        direction: Vec<(String, f64)>,
    },
    /// The vehicle is free along its track (a coasting vehicle: nothing
    /// holds its longitudinal position) and a net longitudinal force (the
    /// creep forces' rolling resistance) pushes it: no steady state.
    #[error(
        "no steady state: the vehicle is free along the track (no force holds a common shift of \
         {}: a coasting vehicle, stiffness {stiffness:.2e} N/m) and a net longitudinal force of \
         {force:.3e} N (the creep forces' rolling resistance) pushes it; hold it by a speed \
         hold, a longitudinal spring and damper from the car body to its track frame (as \
         Vehicle 1's `k_traction`, `c_traction`)",
        coordinates.join(", ")
    )]
    Coasting {
        /// The longitudinal coordinates shifted together.
        coordinates: Vec<String>,
        /// Stiffness against the common shift, N/m (|Δr|∞ / shift).
        stiffness: f64,
        /// Net longitudinal force on them, N.
        force: f64,
    },
    /// The model could not be evaluated.
    #[error(transparent)]
    Sim(#[from] SimError),
}

/// `name value, name value…` for the errors.
fn list(items: &[(String, f64)], separator: &str) -> String {
    items
        .iter()
        .map(|(n, x)| format!("{n}{separator} {x:.3e}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The unknown vector of the solve and how it maps onto (q, q̇, λ).
struct Unknowns {
    /// (coordinate, role) of each unknown that is not a multiplier.
    map: Vec<(usize, Role)>,
    /// The rows of f that are equations (position and rate coordinates).
    rows: Vec<usize>,
    nc: usize,
}

impl Unknowns {
    fn len(&self) -> usize {
        self.map.len() + self.nc
    }

    /// Writes the unknowns `x` into q, q̇ and λ.
    fn scatter(&self, x: &[f64], q: &mut [f64], v: &mut [f64], lambda: &mut [f64]) {
        for (k, &(i, role)) in self.map.iter().enumerate() {
            match role {
                Role::Position => q[i] = x[k],
                Role::Rate => v[i] = x[k],
                Role::Held => {}
            }
        }
        lambda.copy_from_slice(&x[self.map.len()..]);
    }
}

/// The residual r = [f + Gᵀλ over the equation rows; g] and the full
/// f + Gᵀλ (all coordinates).
fn residual<S: MechanicalSystem + ?Sized>(
    system: &mut S,
    eval: &mut ForceEvaluator,
    unknowns: &Unknowns,
    (q, v, lambda): (&[f64], &[f64], &[f64]),
) -> Result<(DVector<f64>, DVector<f64>), SimError> {
    let mut full = eval.force(system, q, v)?.clone();
    let mut r = DVector::zeros(unknowns.len());
    if unknowns.nc > 0 {
        let g = eval.constraints(system, q)?.clone();
        full += eval.g_jacobian.transpose() * DVector::from_column_slice(lambda);
        r.rows_mut(unknowns.rows.len(), unknowns.nc).copy_from(&g);
    }
    for (k, &i) in unknowns.rows.iter().enumerate() {
        r[k] = full[i];
    }
    Ok((r, full))
}

/// The coasting vehicle's error, when the unknowns that are longitudinal
/// translations (x) can shift together with (almost) no restoring force
/// and a net force pushes them: the stiffness against the common shift
/// below a thousandth of the heaviest body's weight per metre (about
/// 300 N/m for Vehicle 1, whose speed hold has 1e6 N/m; coasting, its
/// shift has 1e-5 N/m) and the net force above the tolerance. A body nested in another's x
/// would shift twice and stiffen the shift: no false message, only the
/// general one.
fn coasting<S: MechanicalSystem + ?Sized>(
    system: &mut S,
    eval: &mut ForceEvaluator,
    unknowns: &Unknowns,
    names: &[CoordinateInfo],
    (q, v, lambda): (&[f64], &[f64], &[f64]),
    r: &DVector<f64>,
) -> Result<Option<EquilibriumError>, SimError> {
    use super::CoordinateKind;
    let along: Vec<usize> = unknowns
        .map
        .iter()
        .filter(|&&(i, role)| {
            role == Role::Position
                && names[i].kind == CoordinateKind::Translation(railmbs_models::Axis::X)
        })
        .map(|&(i, _)| i)
        .collect();
    if along.is_empty() {
        return Ok(None);
    }
    let n = q.len();
    let heaviest = (0..n).map(|i| eval.mass()[(i, i)]).fold(0.0, f64::max);
    let force: f64 = unknowns
        .rows
        .iter()
        .enumerate()
        .filter(|(_, i)| along.contains(i))
        .map(|(k, _)| r[k])
        .sum();
    // A shift of 0.1 mm: far above the rounding of x (~1e-13 m at 1 km)
    // and small against every length of the model.
    let h = 1e-4;
    let mut shifted = q.to_vec();
    for &i in &along {
        shifted[i] += h;
    }
    let (rs, _) = residual(system, eval, unknowns, (&shifted, v, lambda))?;
    let stiffness = (rs - r).amax() / h;
    let tolerance = 1e-9 * (heaviest * 9.81).max(1.0);
    Ok(
        (stiffness < 1e-3 * heaviest * 9.81 && force.abs() > tolerance).then(|| {
            EquilibriumError::Coasting {
                coordinates: along.iter().map(|&i| names[i].name.clone()).collect(),
                stiffness,
                force,
            }
        }),
    )
}

/// The largest |r| entries of `full` over `which`, named (at most five).
fn carriers(full: &DVector<f64>, which: &[usize], names: &[CoordinateInfo]) -> Vec<(String, f64)> {
    let mut idx: Vec<usize> = which.to_vec();
    idx.sort_by(|&a, &b| full[b].abs().total_cmp(&full[a].abs()));
    idx.into_iter()
        .take(5)
        .map(|i| (names[i].name.clone(), full[i]))
        .collect()
}

/// Finds the equilibrium of `system` at time `t` from the guess (q₀, q̇₀)
/// (system coordinates; `names` in system order, see
/// [`super::coordinates`]). The roles of the coordinates are decided at the
/// guess (module docs).
///
/// # Errors
/// [`EquilibriumError`]: not converged (with the residual and the
/// coordinates that carry it), unbalanced held coordinates, an
/// unconstrained direction (named), or the model's own evaluation error.
pub fn solve<S: MechanicalSystem + ?Sized>(
    system: &mut S,
    names: &[CoordinateInfo],
    t: f64,
    q0: &[f64],
    v0: &[f64],
    settings: &EquilibriumSettings,
) -> Result<Equilibrium, EquilibriumError> {
    let start = std::time::Instant::now();
    let (mut q, mut v) = (q0.to_vec(), v0.to_vec());
    let mut iterations = 0;
    let mut previous_roles = None;
    loop {
        let (mut eq, unbalanced) = solve_with_roles_at(system, names, t, &q, &v, settings)?;
        iterations += eq.iterations;
        // Held coordinates left unbalanced may have found their forces at
        // the new state (a wheel that reached its rail now rolls on it):
        // decide the roles there and solve again, until they settle.
        if unbalanced.is_empty() || previous_roles.as_ref() == Some(&eq.roles) {
            if !unbalanced.is_empty() {
                return Err(EquilibriumError::Unbalanced {
                    carriers: unbalanced,
                });
            }
            eq.iterations = iterations;
            eq.q_start = q0.to_vec();
            eq.v_start = v0.to_vec();
            eq.seconds = start.elapsed().as_secs_f64();
            return Ok(eq);
        }
        previous_roles = Some(eq.roles.clone());
        q.clone_from(&eq.q);
        // Held rates stay as given; positions rest.
        for ((vi, &role), &solved) in v.iter_mut().zip(&eq.roles).zip(&eq.v) {
            if role != Role::Held {
                *vi = solved;
            }
        }
    }
}

/// One solve with the roles decided at (q₀, q̇₀); the held coordinates left
/// unbalanced are returned with the state reached.
fn solve_with_roles_at<S: MechanicalSystem + ?Sized>(
    system: &mut S,
    names: &[CoordinateInfo],
    t: f64,
    q0: &[f64],
    v0: &[f64],
    settings: &EquilibriumSettings,
) -> Result<(Equilibrium, Vec<(String, f64)>), EquilibriumError> {
    let (n, nc) = (system.dof(), system.n_constraints());
    if q0.len() != n || v0.len() != n || names.len() != n {
        return Err(SimError::Other(format!(
            "equilibrium of a system of {n} coordinates from a state of {} and {} with {} names",
            q0.len(),
            v0.len(),
            names.len()
        ))
        .into());
    }
    let mut eval = ForceEvaluator::new(system, t);
    let (mut q, mut v) = (q0.to_vec(), v0.to_vec());
    let f0 = eval.force(system, &q, &v)?.clone();
    let heaviest = (0..n).map(|i| eval.mass()[(i, i)]).fold(0.0, f64::max);
    let tolerance = settings
        .force_tolerance
        .unwrap_or(1e-9 * (heaviest * 9.81).max(1.0));
    let scale = f0.amax().max(heaviest * 9.81).max(1.0);

    // Roles from the difference columns at the guess.
    let mut stiffness = vec![0.0; n];
    for i in 0..n {
        let h = position_step(q[i]);
        let x = q[i];
        q[i] = x + h;
        let df = eval.force(system, &q, &v)? - &f0;
        q[i] = x;
        stiffness[i] = df.amax() / h;
    }
    let stiffest = stiffness.iter().fold(0.0f64, |a, &k| a.max(k));
    let mut roles = vec![Role::Held; n];
    for i in 0..n {
        let h = position_step(q[i]);
        let stiff = stiffness[i] > noise_level(scale, h);
        // A moving coordinate whose stiffness is a millionth of the
        // stiffest rolls (a wheel's spin: on elastic rails the inner
        // iteration leaves a few N/rad of noise in its column).
        let rolling = v[i] != 0.0 && stiffness[i] < 1e-6 * stiffest;
        if stiff && !rolling {
            roles[i] = Role::Position;
        } else if v[i] != 0.0 {
            let h = rate_step(v[i]);
            let x = v[i];
            v[i] = x + h;
            let df = eval.force(system, &q, &v)? - &f0;
            v[i] = x;
            if df.amax() / h > noise_level(scale, h) {
                roles[i] = Role::Rate;
            } else if stiff {
                roles[i] = Role::Position;
            }
        }
    }
    for i in 0..n {
        if roles[i] == Role::Position {
            v[i] = 0.0;
        }
    }
    let map: Vec<(usize, Role)> = (0..n)
        .filter(|&i| roles[i] != Role::Held)
        .map(|i| (i, roles[i]))
        .collect();
    let unknowns = Unknowns {
        rows: map.iter().map(|&(i, _)| i).collect(),
        map,
        nc,
    };
    let held: Vec<usize> = (0..n).filter(|&i| roles[i] == Role::Held).collect();
    let nu = unknowns.map.len();
    let mut x: Vec<f64> = unknowns
        .map
        .iter()
        .map(|&(i, role)| if role == Role::Rate { v[i] } else { q[i] })
        .chain(std::iter::repeat_n(0.0, nc))
        .collect();
    let mut lambda = vec![0.0; nc];
    unknowns.scatter(&x, &mut q, &mut v, &mut lambda);
    let (mut r, mut full) = residual(system, &mut eval, &unknowns, (&q, &v, &lambda))?;
    let converged = |r: &DVector<f64>| {
        let forces = r.rows(0, unknowns.rows.len()).amax();
        let gaps = if nc > 0 { r.rows(nu, nc).amax() } else { 0.0 };
        forces <= tolerance && gaps <= 1e-12
    };
    let mut iterations = 0;
    // The last fresh Jacobian, when the step taken with it was full and at
    // least halved |r|₂ (chord steps).
    let mut chord: Option<DMatrix<f64>> = None;
    while !converged(&r) {
        if iterations == settings.max_iterations {
            if let Some(e) = coasting(system, &mut eval, &unknowns, names, (&q, &v, &lambda), &r)? {
                return Err(e);
            }
            return Err(EquilibriumError::NotConverged {
                iterations,
                residual: unknowns
                    .rows
                    .iter()
                    .map(|&i| full[i].abs())
                    .fold(0.0, f64::max),
                tolerance,
                carriers: carriers(&full, &unknowns.rows, names),
            });
        }
        iterations += 1;
        let chord_step = chord.is_some();
        // Forward-difference Jacobian of r over the unknowns; the
        // multipliers' columns are Gᵀ exactly.
        let m = unknowns.len();
        let mut jac = chord.take().unwrap_or_else(|| DMatrix::zeros(m, m));
        for (k, &(i, role)) in unknowns.map.iter().enumerate() {
            if chord_step {
                break;
            }
            let slot = match role {
                Role::Position => &mut q[i],
                _ => &mut v[i],
            };
            let x0 = *slot;
            let h = match role {
                Role::Position => position_step(x0),
                _ => rate_step(x0),
            };
            *slot = x0 + h;
            let (rp, _) = residual(system, &mut eval, &unknowns, (&q, &v, &lambda))?;
            match role {
                Role::Position => q[i] = x0,
                _ => v[i] = x0,
            }
            jac.set_column(k, &((rp - &r) / h));
        }
        if nc > 0 && !chord_step {
            eval.constraints(system, &q)?;
            for c in 0..nc {
                for (k, &i) in unknowns.rows.iter().enumerate() {
                    jac[(k, nu + c)] = eval.g_jacobian[(c, i)];
                }
            }
        }
        // A direction without stiffness that a force pushes along (a wheel
        // above its rail, gravity on it): a step of damped motion under the
        // forces, (J − M/τ²) δx = −r, instead (pseudo-transient
        // continuation; τ = 0.01 s moves a body by at most g τ² ≈ 1 mm).
        let regularized_step = || {
            let tau: f64 = 0.01;
            let mut regularized = jac.clone();
            for (a, &(i, _)) in unknowns.map.iter().enumerate() {
                for (b, &(j, role)) in unknowns.map.iter().enumerate() {
                    let scale = if role == Role::Rate { tau } else { tau * tau };
                    regularized[(a, b)] -= eval.mass()[(i, j)] / scale;
                }
            }
            solve_equilibrated(&regularized, &r, names, &unknowns, false)
        };
        let mut dx = match solve_equilibrated(&jac, &r, names, &unknowns, true) {
            Err(Singular::Loaded) => regularized_step(),
            // A direction without stiffness at the guess is a free one
            // (named); one that appears on the way (a wheel lifted by a
            // long step loses its creep forces, and its spin's column
            // vanishes) is stepped through as a loaded one.
            Err(Singular::Free(_)) if iterations > 1 => regularized_step(),
            other => other,
        }
        .map_err(|e| match e {
            Singular::Free(direction) => EquilibriumError::Unconstrained { direction },
            Singular::Loaded => unreachable!("only returned when asked"),
            Singular::Sim(e) => e.into(),
        })?;
        dx.neg_mut();
        // Cap the step: positions by max_step, rates relatively.
        let mut cap: f64 = 1.0;
        for (k, &(i, role)) in unknowns.map.iter().enumerate() {
            let limit = match role {
                Role::Position => settings
                    .step_limits
                    .iter()
                    .filter(|&&(j, _)| j == i)
                    .fold(settings.max_step, |a, &(_, l)| a.min(l)),
                _ => settings.max_rate_change * v[i].abs().max(1.0),
            };
            if dx[k].abs() > limit {
                cap = cap.min(limit / dx[k].abs());
            }
        }
        // Backtracking line search on |r|₂.
        let norm = r.norm();
        let mut alpha = cap;
        if chord_step {
            // Full length or not at all.
            let xt: Vec<f64> = x.iter().zip(dx.iter()).map(|(a, d)| a + cap * d).collect();
            unknowns.scatter(&xt, &mut q, &mut v, &mut lambda);
            if let Ok((rt, ft)) = residual(system, &mut eval, &unknowns, (&q, &v, &lambda))
                && rt.norm() <= (1.0 - 1e-4 * cap) * norm
            {
                if cap == 1.0 && rt.norm() <= 0.5 * norm {
                    chord = Some(jac);
                }
                (x, r, full) = (xt, rt, ft);
                continue;
            }
            unknowns.scatter(&x, &mut q, &mut v, &mut lambda);
            continue;
        }
        let trial = loop {
            let xt: Vec<f64> = x
                .iter()
                .zip(dx.iter())
                .map(|(a, d)| a + alpha * d)
                .collect();
            unknowns.scatter(&xt, &mut q, &mut v, &mut lambda);
            let candidate = residual(system, &mut eval, &unknowns, (&q, &v, &lambda));
            if let Ok((rt, ft)) = candidate {
                if rt.norm() <= (1.0 - 1e-4 * alpha) * norm || alpha < 1e-3 * cap {
                    break (xt, rt, ft);
                }
            } else if alpha < 1e-3 * cap {
                candidate?;
            }
            alpha *= 0.5;
        };
        if settings.chord_steps && alpha == 1.0 && trial.1.norm() <= 0.5 * norm {
            chord = Some(jac);
        }
        (x, r, full) = trial;
    }
    unknowns.scatter(&x, &mut q, &mut v, &mut lambda);
    let unbalanced: Vec<usize> = held
        .iter()
        .copied()
        .filter(|&i| full[i].abs() > tolerance)
        .collect();
    let eq = Equilibrium {
        t,
        q,
        v,
        q_start: q0.to_vec(),
        v_start: v0.to_vec(),
        lambda,
        roles,
        iterations,
        residual: full.amax(),
        tolerance,
        seconds: 0.0,
    };
    Ok((eq, carriers(&full, &unbalanced, names)))
}

/// Why [`solve_equilibrated`] found no step.
enum Singular {
    /// A singular direction along which the residual has no component: the
    /// equilibrium is not unique (the direction, named).
    Free(Vec<(String, f64)>),
    /// A singular direction that the residual pushes along.
    Loaded,
    /// The SVD failed.
    Sim(SimError),
}

/// Solves `jac dx = r` with the columns scaled to unit norm (so that metres,
/// radians, rates and multipliers weigh alike) by SVD; a singular value
/// below 1e-12 of the largest is a direction without stiffness: free
/// (named by its right singular vector) when the residual has no component
/// along it (below 1e-9 of |r|) or when `loaded_ok` is false, else loaded.
fn solve_equilibrated(
    jac: &DMatrix<f64>,
    r: &DVector<f64>,
    names: &[CoordinateInfo],
    unknowns: &Unknowns,
    loaded_ok: bool,
) -> Result<DVector<f64>, Singular> {
    let m = jac.ncols();
    let scales: Vec<f64> = (0..m)
        .map(|k| {
            let s = jac.column(k).norm();
            if s > 0.0 { 1.0 / s } else { 1.0 }
        })
        .collect();
    let mut scaled = jac.clone();
    for (k, s) in scales.iter().enumerate() {
        scaled.column_mut(k).scale_mut(*s);
    }
    let svd = scaled.svd(true, true);
    let (smax, kmin) = svd
        .singular_values
        .iter()
        .enumerate()
        .fold((0.0f64, (f64::INFINITY, 0)), |(mx, mn), (k, &s)| {
            (mx.max(s), if s < mn.0 { (s, k) } else { mn })
        });
    let v_t = svd.v_t.as_ref().expect("SVD computed with V");
    if kmin.0.is_nan() || kmin.0 <= 1e-12 * smax {
        let u = svd.u.as_ref().expect("SVD computed with U");
        let along = u.column(kmin.1).dot(r).abs();
        if loaded_ok && along > 1e-9 * r.norm() {
            return Err(Singular::Loaded);
        }
        let row = v_t.row(kmin.1);
        let direction: Vec<f64> = (0..m).map(|k| row[k] * scales[k]).collect();
        let big = direction.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let mut named: Vec<(String, f64)> = direction
            .iter()
            .enumerate()
            .filter(|(_, x)| x.abs() >= 0.1 * big)
            .map(|(k, x)| {
                let name = match unknowns.map.get(k) {
                    Some(&(i, Role::Rate)) => format!("{} (rate)", names[i].name),
                    Some(&(i, _)) => names[i].name.clone(),
                    None => format!("constraint multiplier {}", k - unknowns.map.len()),
                };
                (name, x / big)
            })
            .collect();
        named.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        return Err(Singular::Free(named));
    }
    let mut dx = svd
        .solve(r, 0.0)
        .map_err(|e| Singular::Sim(SimError::Other(format!("equilibrium: {e}"))))?;
    for (k, s) in scales.iter().enumerate() {
        dx[k] *= s;
    }
    Ok(dx)
}

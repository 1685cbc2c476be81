//! Trains: several vehicles, each a model with its own engine (numeric, or
//! the compiled plugin of its model file), running on one track at arc
//! offsets from the train's reference point, coupled by coupler force
//! elements between bodies of different vehicles (external subsystems,
//! Pogorelov 2005, Sect. 5). A train runs on the same runner as a single
//! vehicle ([`crate::run`]), with its own output columns.
//!
//! The assembled system ([`TrainSystem`]) stacks the vehicles' coordinates in
//! vehicle order: its mass matrix is block-diagonal (one block per vehicle),
//! its generalized forces are the vehicles' own plus the couplers' wrenches
//! projected by the body Jacobians Γ of each side. For Park's Newton
//! iteration the couplers' local stiffness and damping are mapped by the same
//! Jacobians into the diagonal blocks and the off-diagonal (vehicle–vehicle)
//! blocks of ∂f/∂q and ∂f/∂q̇.
//!
//! Each vehicle's track-following frames follow the train's speed law shifted
//! by the vehicle's offset ([`TrainScenario::vehicle_scenario`]), so a vehicle
//! of the train sees exactly the track a single-vehicle scenario starting at
//! `start + offset` would, and a train of one vehicle without couplers runs
//! the same trajectory as the plain scenario.

use crate::analysis::CoordinateInfo;
use crate::analysis::equilibrium::{Equilibrium, EquilibriumSettings};
use crate::equations::{BodyKinematics, Equations, Parts};
use crate::forces::{
    Characteristic, ForceContext, ForceElement, ForceJacobian, JacobianScratch, Linear6, Wrench,
    add_generalized_force, build_element,
};
use crate::model_system::ModelSystem;
use crate::run::CpuClock;
use crate::run::assessment::LoadSample;
use crate::run::columns::{ARC_COLUMNS, Columns, arc_motion, columns};
use crate::run::grid::Row;
use crate::run::scenario::{
    check_integrator, continuous_velocities, drive_track_frames, scenario_state,
};
use crate::run::{OutputSink, RowColumns, RunError, RunSummary, RunSystem, Runner};
use crate::system::{MechanicalSystem, SimError};
use crate::track_inputs::RunningSpeed;
use nalgebra::{DMatrix, DVector};
use railmbs_integrate::{BlockMatrix, BlockPattern};
use railmbs_models::{
    BodyRef, Expr, Frame, InitialStateKind, Model, TrainCoupler, TrainForce, TrainScenario,
};
use rayon::prelude::*;
use std::ops::Range;
use std::path::Path;
use std::sync::Arc;

/// A coupler: a force element of the model language between bodies of
/// different vehicles (the runtime element of its spec, one home for each
/// element), evaluated with a context whose body `i` is body `bodies[i].1`
/// of vehicle `bodies[i].0`. The `Coupler(...)` of train files is a
/// [`Linear6`] between two bodies.
#[derive(Debug)]
pub struct Coupler {
    name: String,
    /// (vehicle, body in that vehicle's model) of the element's body `i`.
    bodies: Vec<(usize, usize)>,
    /// The distinct vehicles of `bodies`, in order of first appearance.
    vehicles: Vec<usize>,
    element: Box<dyn ForceElement>,
}

impl Coupler {
    /// The coupler `spec` between body `body1` of its vehicle 1 and `body2` of
    /// its vehicle 2 (body indices in the vehicles' models).
    pub fn new(spec: &TrainCoupler, body1: usize, body2: usize) -> Result<Self, SimError> {
        let num3 = |p: [f64; 3]| p.map(Expr::num);
        let frame = |p: [f64; 3]| Frame {
            origin: num3(p),
            rotation_xyz: num3([0.0; 3]),
        };
        let diag = |lin: [f64; 3], ang: [f64; 3]| {
            let mut m: [Expr; 36] = std::array::from_fn(|_| Expr::num(0.0));
            for k in 0..3 {
                m[7 * k] = Expr::num(lin[k]);
                m[7 * (k + 3)] = Expr::num(ang[k]);
            }
            Box::new(m)
        };
        let p = spec.preload;
        let kind = railmbs_models::forces::Linear6 {
            body1: BodyRef::Body(0),
            frame1: frame(spec.point1),
            body2: BodyRef::Body(1),
            frame2: frame(spec.point2),
            stiffness: diag(spec.stiffness, spec.angular_stiffness),
            damping: diag(spec.damping, spec.angular_damping),
            preload: [p[0], p[1], p[2], 0.0, 0.0, 0.0].map(Expr::num),
        };
        let mut element = Linear6::new(spec.name.clone(), &kind);
        element.set_parameters(&[])?;
        if let Some((rows, interpolation)) = &spec.longitudinal {
            let f = Characteristic::new(rows, *interpolation).map_err(|e| {
                SimError::Other(format!("coupler \"{}\": longitudinal: {e}", spec.name))
            })?;
            element = element.with_longitudinal(f);
        }
        Ok(Self::with_element(
            spec.name.clone(),
            vec![(spec.vehicle1, body1), (spec.vehicle2, body2)],
            Box::new(element),
        ))
    }

    /// The coupler of a force element of the train file, resolved against
    /// the vehicles' models ([`TrainScenario::resolve_elements`]). Elements
    /// with first-order states (`SeriesSpring`) are not supported between
    /// vehicles: the train has no coordinates of its own for them (put such
    /// an element inside a vehicle's model, e.g. a coupler vehicle's).
    pub fn from_element(spec: &TrainForce) -> Result<Self, SimError> {
        let mut element = build_element(spec.name.clone(), &spec.kind);
        element.set_parameters(&[])?;
        if element.state_count() > 0 {
            return Err(SimError::Other(format!(
                "coupler \"{}\": a {} element has first-order states, which couplers between \
                 vehicles do not support; put it in a vehicle's model",
                spec.name,
                spec.kind.constructor()
            )));
        }
        if element.needs_track() {
            return Err(SimError::Other(format!(
                "coupler \"{}\": an element that needs the track cannot be a coupler",
                spec.name
            )));
        }
        Ok(Self::with_element(
            spec.name.clone(),
            spec.bodies.clone(),
            element,
        ))
    }

    fn with_element(
        name: String,
        bodies: Vec<(usize, usize)>,
        element: Box<dyn ForceElement>,
    ) -> Self {
        let mut vehicles: Vec<usize> = Vec::new();
        for &(k, _) in &bodies {
            if !vehicles.contains(&k) {
                vehicles.push(k);
            }
        }
        Self {
            name,
            bodies,
            vehicles,
            element,
        }
    }

    /// Long name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Output names (without the coupler's name): the force and moment body
    /// 1 exerts on body 2, in body 1's axes.
    pub fn output_names(&self) -> Vec<String> {
        self.element.output_names()
    }
}

/// Several vehicles coupled: a [`MechanicalSystem`] with the vehicles'
/// coordinates stacked in vehicle order.
pub struct TrainSystem {
    names: Vec<String>,
    vehicles: Vec<ModelSystem>,
    /// Coordinate range of each vehicle in the train's q.
    ranges: Vec<Range<usize>>,
    /// Constraint range of each vehicle.
    constraint_ranges: Vec<Range<usize>>,
    couplers: Vec<Coupler>,
    mass: Vec<DMatrix<f64>>,
    force: Vec<DVector<f64>>,
    dq: Vec<DMatrix<f64>>,
    dv: Vec<DMatrix<f64>>,
    g: Vec<DVector<f64>>,
    gq: Vec<DMatrix<f64>>,
    scratch: JacobianScratch,
    /// Threads evaluating the vehicles in parallel; `None`: sequentially.
    pool: Option<rayon::ThreadPool>,
    /// Whether the couplers' element states (stick anchors) have been set
    /// from an accepted state (the first evaluation sets them).
    couplers_initialized: bool,
    /// The vehicles as diagonal blocks, the coordinates of the coupled
    /// bodies as the border ([`MechanicalSystem::block_pattern`]); `None`
    /// for a single vehicle or a vehicle without coordinates.
    pattern: Option<Arc<BlockPattern>>,
}

/// Runs `f` on every item (vehicle `k` and its buffers), in vehicle order in
/// the calling thread or in parallel on `pool`; the items are independent,
/// so the results are the same either way. The first error in vehicle
/// order is returned.
fn each_vehicle<T: Send>(
    pool: Option<&rayon::ThreadPool>,
    items: &mut [T],
    f: impl Fn(usize, &mut T) -> Result<(), SimError> + Sync,
) -> Result<(), SimError> {
    match pool {
        None => items.iter_mut().enumerate().try_for_each(|(k, x)| f(k, x)),
        Some(pool) => {
            let results: Vec<Result<(), SimError>> = pool.install(|| {
                items
                    .par_iter_mut()
                    .enumerate()
                    .map(|(k, x)| f(k, x))
                    .collect()
            });
            results.into_iter().collect()
        }
    }
}

impl std::fmt::Debug for TrainSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TrainSystem")
            .field("vehicles", &self.names)
            .field("dof", &self.dof())
            .field("couplers", &self.couplers.len())
            .finish()
    }
}

impl TrainSystem {
    /// Vehicles (name, system) in train order and the couplers between them.
    pub fn new(
        vehicles: Vec<(String, ModelSystem)>,
        couplers: Vec<Coupler>,
    ) -> Result<Self, SimError> {
        let (names, mut systems): (Vec<String>, Vec<ModelSystem>) = vehicles.into_iter().unzip();
        for c in &couplers {
            for &(k, b) in &c.bodies {
                let Some(s) = systems.get_mut(k) else {
                    return Err(SimError::Other(format!(
                        "coupler \"{}\": no vehicle {k} in a train of {}",
                        c.name,
                        names.len()
                    )));
                };
                if b >= s.equations().body_count() {
                    return Err(SimError::Other(format!(
                        "coupler \"{}\": vehicle \"{}\" has no body {b}",
                        c.name, names[k]
                    )));
                }
                s.require_body_jacobians();
            }
        }
        let mut ranges = Vec::new();
        let mut constraint_ranges = Vec::new();
        let (mut n, mut nc) = (0, 0);
        for s in &systems {
            ranges.push(n..n + s.dof());
            constraint_ranges.push(nc..nc + s.n_constraints());
            n += s.dof();
            nc += s.n_constraints();
        }
        // The border: every coordinate a coupler's body depends on (the
        // columns of its Γ that can be nonzero); couplers couple vehicles
        // through these alone.
        let mut border = Vec::new();
        for c in &couplers {
            for &(k, b) in &c.bodies {
                let start = ranges[k].start;
                border.extend(systems[k].body_coordinates(b).iter().map(|&i| start + i));
            }
        }
        let pattern = if ranges.len() > 1 && ranges.iter().all(|r| !r.is_empty()) {
            Some(Arc::new(BlockPattern::new(ranges.clone(), border)?))
        } else {
            None
        };
        let square = |s: &ModelSystem| DMatrix::zeros(s.dof(), s.dof());
        Ok(Self {
            pattern,
            mass: systems.iter().map(square).collect(),
            force: systems.iter().map(|s| DVector::zeros(s.dof())).collect(),
            dq: systems.iter().map(square).collect(),
            dv: systems.iter().map(square).collect(),
            g: systems
                .iter()
                .map(|s| DVector::zeros(s.n_constraints()))
                .collect(),
            gq: systems
                .iter()
                .map(|s| DMatrix::zeros(s.n_constraints(), s.dof()))
                .collect(),
            scratch: JacobianScratch::new(n),
            pool: None,
            couplers_initialized: false,
            names,
            vehicles: systems,
            ranges,
            constraint_ranges,
            couplers,
        })
    }

    /// Every vehicle keeps its force elements' states as built until the
    /// next accepted step ([`ModelSystem::keep_initial_force_states`]): the
    /// train's static equilibrium is the frictionless one, as a vehicle's.
    pub fn keep_initial_force_states(&mut self) {
        for vehicle in &mut self.vehicles {
            vehicle.keep_initial_force_states();
        }
    }

    /// Evaluates the vehicles in `threads` threads (1: sequentially in the
    /// calling thread, the default); results are identical either way (the
    /// vehicles are independent between coupler evaluations: Pogorelov
    /// 2005, Sect. 5).
    pub fn set_threads(&mut self, threads: usize) -> Result<(), SimError> {
        self.pool = if threads > 1 {
            Some(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .map_err(|e| SimError::Other(format!("cannot start {threads} threads: {e}")))?,
            )
        } else {
            None
        };
        Ok(())
    }

    /// Number of vehicles.
    pub fn vehicle_count(&self) -> usize {
        self.vehicles.len()
    }

    /// Vehicle `k`'s name.
    pub fn vehicle_name(&self, k: usize) -> &str {
        &self.names[k]
    }

    /// Vehicle `k`'s system.
    pub fn vehicle(&self, k: usize) -> &ModelSystem {
        &self.vehicles[k]
    }

    /// Vehicle `k`'s system, mutable (to evaluate it at a state).
    pub fn vehicle_mut(&mut self, k: usize) -> &mut ModelSystem {
        &mut self.vehicles[k]
    }

    /// Vehicle `k`'s coordinates in the train's q.
    pub fn range(&self, k: usize) -> Range<usize> {
        self.ranges[k].clone()
    }

    /// The couplers.
    pub fn couplers(&self) -> &[Coupler] {
        &self.couplers
    }

    /// Moves the wheel loads of the last accepted step of every vehicle to
    /// `out`, keyed by the element's place in the train (vehicle by
    /// vehicle, element by element; see [`TrainSystem::assessment_name`]).
    pub fn take_assessment_loads(&mut self, out: &mut Vec<LoadSample>) {
        let mut offset = 0;
        for s in &mut self.vehicles {
            let start = out.len();
            s.take_assessment_loads(out);
            for sample in &mut out[start..] {
                sample.key += offset;
            }
            offset += s.forces().len();
        }
    }

    /// The wheel loads of every wheel–rail element of the train at the
    /// state (t, q, q̇), named `<vehicle>.<element>`, as
    /// [`crate::analysis::wheel_loads`] for one vehicle (the state is
    /// accepted).
    pub fn wheel_loads(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<Vec<(String, crate::forces::WheelLoads)>, SimError> {
        self.accept_step(t, q, v)?;
        let mut samples = Vec::new();
        self.take_assessment_loads(&mut samples);
        Ok(samples
            .into_iter()
            .map(|s| (self.assessment_name(s.key), s.loads))
            .collect())
    }

    /// Every coupler's outputs at the state (t, q, q̇), named
    /// `<coupler>.<output>` (`C12.Fx[N]`).
    pub fn named_coupler_outputs(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<Vec<(String, f64)>, SimError> {
        let mut values = Vec::new();
        self.coupler_outputs(t, q, v, &mut values)?;
        let names = self.couplers.iter().flat_map(|c| {
            c.output_names()
                .into_iter()
                .map(|o| format!("{}.{o}", c.name))
        });
        Ok(names.zip(values).collect())
    }

    /// Long name of the element with assessment key `key`, prefixed by its
    /// vehicle's name.
    pub fn assessment_name(&self, mut key: usize) -> String {
        for (s, name) in self.vehicles.iter().zip(&self.names) {
            if key < s.forces().len() {
                return format!("{name}.{}", s.forces()[key].name());
            }
            key -= s.forces().len();
        }
        String::new()
    }

    /// Kinematics of the bodies of coupler `c` from the vehicles' last
    /// evaluations.
    fn coupler_bodies(&self, c: &Coupler) -> Vec<BodyKinematics> {
        c.bodies
            .iter()
            .map(|&(k, b)| self.vehicles[k].last_evaluation().bodies[b])
            .collect()
    }

    /// Tells the couplers whose elements keep state (stick anchors) that the
    /// vehicles' last evaluations are at an accepted state.
    fn accept_couplers(&mut self, t: f64) -> Result<(), SimError> {
        self.couplers_initialized = true;
        for ci in 0..self.couplers.len() {
            if !self.couplers[ci].element.remembers_accepted_steps() {
                continue;
            }
            let bodies = self.coupler_bodies(&self.couplers[ci]);
            let ctx = ForceContext {
                t,
                bodies: &bodies,
                params: &[],
                states: &[],
                state_rates: &[],
            };
            self.couplers[ci].element.accept_step(&ctx)?;
        }
        Ok(())
    }

    /// Coupler outputs at a state (evaluates the coupled vehicles'
    /// kinematics), appended to `out` in coupler order.
    pub fn coupler_outputs(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        out: &mut Vec<f64>,
    ) -> Result<(), SimError> {
        for ci in 0..self.couplers.len() {
            let bodies = self.coupler_bodies_at(ci, t, q, v)?;
            let ctx = ForceContext {
                t,
                bodies: &bodies,
                params: &[],
                states: &[],
                state_rates: &[],
            };
            self.couplers[ci].element.outputs(&ctx, out);
        }
        Ok(())
    }

    /// The wrenches of every coupler on its bodies at a state (evaluates
    /// the coupled vehicles' kinematics), in coupler order: per body its
    /// kinematics and the wrench on it (force, N, and moment about its
    /// centre of mass, N m, both in SC0). The forces a run applies, for
    /// checks such as Newton's third law across a coupler.
    #[allow(clippy::type_complexity)]
    pub fn coupler_wrenches(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<Vec<Vec<(BodyKinematics, Wrench)>>, SimError> {
        let mut all = Vec::with_capacity(self.couplers.len());
        for ci in 0..self.couplers.len() {
            let bodies = self.coupler_bodies_at(ci, t, q, v)?;
            let ctx = ForceContext {
                t,
                bodies: &bodies,
                params: &[],
                states: &[],
                state_rates: &[],
            };
            let mut w = vec![Wrench::default(); bodies.len()];
            self.couplers[ci].element.apply(&ctx, &mut w)?;
            all.push(bodies.into_iter().zip(w).collect());
        }
        Ok(all)
    }

    /// Kinematics of the bodies of coupler `ci` at a state (evaluates their
    /// vehicles).
    fn coupler_bodies_at(
        &mut self,
        ci: usize,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<Vec<BodyKinematics>, SimError> {
        let mut bodies = vec![BodyKinematics::default(); self.couplers[ci].bodies.len()];
        for (i, body) in bodies.iter_mut().enumerate() {
            let (k, b) = self.couplers[ci].bodies[i];
            let r = self.ranges[k].clone();
            let e = self.vehicles[k].evaluate(t, &q[r.clone()], &v[r], Parts::KINEMATICS)?;
            *body = e.bodies[b];
        }
        Ok(bodies)
    }
}

impl TrainSystem {
    /// The vehicle of a train of one vehicle without couplers: it is then
    /// solved with its own block pattern.
    fn lone_vehicle(&self) -> Option<&ModelSystem> {
        match &self.vehicles[..] {
            [vehicle] if self.couplers.is_empty() => Some(vehicle),
            _ => None,
        }
    }

    /// Adds the couplers' generalized forces to `force` (the vehicles' last
    /// evaluations give the bodies' kinematics and Jacobians).
    fn add_coupler_forces(&mut self, t: f64, force: &mut DVector<f64>) -> Result<(), SimError> {
        if !self.couplers_initialized {
            self.accept_couplers(t)?;
        }
        for c in &self.couplers {
            let bodies = self.coupler_bodies(c);
            let ctx = ForceContext {
                t,
                bodies: &bodies,
                params: &[],
                states: &[],
                state_rates: &[],
            };
            let mut w = vec![Wrench::default(); bodies.len()];
            c.element.apply(&ctx, &mut w)?;
            for (&(k, b), w) in c.bodies.iter().zip(&w) {
                let r = self.ranges[k].clone();
                add_generalized_force(
                    &self.vehicles[k].last_evaluation().jacobians,
                    b,
                    w,
                    &mut force.as_mut_slice()[r],
                );
            }
        }
        Ok(())
    }

    /// Adds the couplers' Jacobians (local stiffness and damping mapped by
    /// the Jacobians of both attachment points) through `add(i, j, ∂f_i/∂q_j,
    /// ∂f_i/∂q̇_j)`, which returns `false` for an entry it has no place for.
    fn add_coupler_jacobians(
        &mut self,
        t: f64,
        mut add: impl FnMut(usize, usize, f64, f64) -> bool,
    ) -> Result<(), SimError> {
        for c in &self.couplers {
            let bodies = self.coupler_bodies(c);
            let ranges: Vec<Range<usize>> =
                c.vehicles.iter().map(|&k| self.ranges[k].clone()).collect();
            // Column offset of each of the coupler's vehicles.
            let mut col0 = Vec::with_capacity(ranges.len());
            let mut width = 0;
            for r in &ranges {
                col0.push(width);
                width += r.len();
            }
            // Γ of the bodies stacked: rows 6i..6i+6 body i over its
            // vehicle's columns.
            let mut gamma = DMatrix::zeros(6 * c.bodies.len(), width);
            for (i, &(k, b)) in c.bodies.iter().enumerate() {
                let j = c.vehicles.iter().position(|&x| x == k).unwrap_or(0);
                let src = &self.vehicles[k].last_evaluation().jacobians;
                // The coordinates' columns; element states after them stay zero.
                let n = ranges[j].len().min(src.ncols());
                gamma
                    .view_mut((6 * i, col0[j]), (6, n))
                    .copy_from(&src.view((6 * b, 0), (6, n)));
            }
            let mut dq = DMatrix::zeros(width, width);
            let mut dv = DMatrix::zeros(width, width);
            let ctx = ForceContext {
                t,
                bodies: &bodies,
                params: &[],
                states: &[],
                state_rates: &[],
            };
            let mut jac = ForceJacobian::new(&gamma, &bodies, &mut dq, &mut dv, &mut self.scratch);
            c.element.add_jacobian(&ctx, &mut jac)?;
            let global = |i: usize| {
                let j = col0.iter().rposition(|&c0| c0 <= i).unwrap_or(0);
                ranges[j].start + i - col0[j]
            };
            for a in 0..width {
                for b in 0..width {
                    let (x, y) = (dq[(a, b)], dv[(a, b)]);
                    if (x != 0.0 || y != 0.0) && !add(global(a), global(b), x, y) {
                        return Err(SimError::Other(format!(
                            "coupler \"{}\": its Jacobian couples coordinates {} and {} \
                             outside the train's block pattern",
                            c.name,
                            global(a),
                            global(b)
                        )));
                    }
                }
            }
        }
        Ok(())
    }

    /// Evaluates the vehicles' approximate Jacobians into `dq[k]`, `dv[k]`
    /// (one pair per vehicle); `false` if a vehicle has none (see
    /// [`MechanicalSystem::force_jacobian`] of the train).
    fn vehicle_jacobians(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        dq: &mut [DMatrix<f64>],
        dv: &mut [DMatrix<f64>],
    ) -> Result<bool, SimError> {
        // A vehicle without force elements of its own (a coupler vehicle,
        // moved by the couplers only) has a zero approximate Jacobian
        // (Eq. 31 neglects the inertia and gravity terms); any other vehicle
        // without one makes the integrator differentiate the train.
        let coupled: Vec<bool> = (0..self.vehicles.len())
            .map(|k| self.couplers.iter().any(|c| c.vehicles.contains(&k)))
            .collect();
        let ranges = &self.ranges;
        let mut items: Vec<_> = self
            .vehicles
            .iter_mut()
            .zip(dq.iter_mut().zip(dv.iter_mut()))
            .map(|x| (x, true))
            .collect();
        each_vehicle(self.pool.as_ref(), &mut items, |k, ((s, (dq, dv)), ok)| {
            let r = ranges[k].clone();
            *ok = s.force_jacobian(t, &q[r.clone()], &v[r.clone()], dq, dv)?;
            if !*ok && coupled[k] && s.forces().is_empty() {
                // Its body Jacobians at this state, for the couplers.
                let parts = Parts {
                    kinematics: true,
                    jacobians: true,
                    ..Parts::KINEMATICS
                };
                s.evaluate(t, &q[r.clone()], &v[r], parts)?;
                dq.as_mut_slice().fill(0.0);
                dv.as_mut_slice().fill(0.0);
                *ok = true;
            }
            Ok(())
        })?;
        Ok(items.iter().all(|x| x.1))
    }
}

impl MechanicalSystem for TrainSystem {
    fn dof(&self) -> usize {
        self.ranges.last().map_or(0, |r| r.end)
    }

    fn is_first_order(&self, i: usize) -> bool {
        self.ranges
            .iter()
            .position(|r| r.contains(&i))
            .is_some_and(|k| self.vehicles[k].is_first_order(i - self.ranges[k].start))
    }

    fn n_constraints(&self) -> usize {
        self.constraint_ranges.last().map_or(0, |r| r.end)
    }

    fn dynamics(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        mass: &mut DMatrix<f64>,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        mass.as_mut_slice().fill(0.0);
        {
            let ranges = &self.ranges;
            let mut items: Vec<_> = self
                .vehicles
                .iter_mut()
                .zip(self.mass.iter_mut().zip(self.force.iter_mut()))
                .collect();
            each_vehicle(self.pool.as_ref(), &mut items, |k, (s, (m, f))| {
                let r = ranges[k].clone();
                s.dynamics(t, &q[r.clone()], &v[r], m, f)
            })?;
        }
        for (k, r) in self.ranges.iter().enumerate() {
            mass.view_mut((r.start, r.start), (r.len(), r.len()))
                .copy_from(&self.mass[k]);
            force.rows_mut(r.start, r.len()).copy_from(&self.force[k]);
        }
        self.add_coupler_forces(t, force)
    }

    fn constraints(
        &mut self,
        t: f64,
        q: &[f64],
        g: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), SimError> {
        jacobian.as_mut_slice().fill(0.0);
        for (k, s) in self.vehicles.iter_mut().enumerate() {
            let (r, c) = (self.ranges[k].clone(), self.constraint_ranges[k].clone());
            if c.is_empty() {
                continue;
            }
            s.constraints(t, &q[r.clone()], &mut self.g[k], &mut self.gq[k])?;
            g.rows_mut(c.start, c.len()).copy_from(&self.g[k]);
            jacobian
                .view_mut((c.start, r.start), (c.len(), r.len()))
                .copy_from(&self.gq[k]);
        }
        Ok(())
    }

    /// The vehicles' approximate Jacobians in the diagonal blocks plus the
    /// couplers' (local stiffness and damping mapped by the Jacobians of both
    /// attachment points, which fills the blocks between coupled vehicles).
    /// If a vehicle has none (no force elements), the integrator
    /// differentiates the whole train numerically.
    fn force_jacobian(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        dfdq: &mut DMatrix<f64>,
        dfdv: &mut DMatrix<f64>,
    ) -> Result<bool, SimError> {
        dfdq.as_mut_slice().fill(0.0);
        dfdv.as_mut_slice().fill(0.0);
        let (mut dq, mut dv) = (std::mem::take(&mut self.dq), std::mem::take(&mut self.dv));
        let ok = self.vehicle_jacobians(t, q, v, &mut dq, &mut dv);
        (self.dq, self.dv) = (dq, dv);
        if !ok? {
            return Ok(false);
        }
        for (k, r) in self.ranges.iter().enumerate() {
            dfdq.view_mut((r.start, r.start), (r.len(), r.len()))
                .copy_from(&self.dq[k]);
            dfdv.view_mut((r.start, r.start), (r.len(), r.len()))
                .copy_from(&self.dv[k]);
        }
        self.add_coupler_jacobians(t, |i, j, x, y| {
            dfdq[(i, j)] += x;
            dfdv[(i, j)] += y;
            true
        })?;
        Ok(true)
    }

    /// The vehicles as diagonal blocks, the coordinates of the bodies that
    /// couplers join as the border (from the model tree: a body's pose
    /// depends on its own and its ancestors' coordinates); `None` when the
    /// border is so large that the bordered factorization would not save
    /// half of the dense work. A train of one vehicle and no couplers has
    /// that vehicle's own pattern (its bogies as blocks, [`ModelSystem`]'s),
    /// so that it runs exactly as the vehicle's plain scenario.
    fn block_pattern(&self) -> Option<Arc<BlockPattern>> {
        if let Some(vehicle) = self.lone_vehicle() {
            return vehicle.block_pattern();
        }
        self.pattern.clone().filter(|p| p.pays())
    }

    /// [`MechanicalSystem::dynamics`] with each vehicle's M written straight
    /// into its diagonal block (no n × n matrix cleared or copied).
    fn dynamics_blocks(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        mass: &mut BlockMatrix,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        if self.lone_vehicle().is_some() {
            return self.vehicles[0].dynamics_blocks(t, q, v, mass, force);
        }
        {
            let ranges = &self.ranges;
            let mut items: Vec<_> = self
                .vehicles
                .iter_mut()
                .zip(mass.blocks_mut().iter_mut().zip(self.force.iter_mut()))
                .collect();
            each_vehicle(self.pool.as_ref(), &mut items, |k, (s, (m, f))| {
                let r = ranges[k].clone();
                s.dynamics(t, &q[r.clone()], &v[r], m, f)
            })?;
        }
        for (k, r) in self.ranges.iter().enumerate() {
            force.rows_mut(r.start, r.len()).copy_from(&self.force[k]);
        }
        self.add_coupler_forces(t, force)
    }

    /// [`MechanicalSystem::force_jacobian`] with each vehicle's Jacobians
    /// written straight into its diagonal blocks and the couplers' entries
    /// between vehicles into the border.
    fn force_jacobian_blocks(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        dfdq: &mut BlockMatrix,
        dfdv: &mut BlockMatrix,
    ) -> Result<bool, SimError> {
        if self.lone_vehicle().is_some() {
            return self.vehicles[0].force_jacobian_blocks(t, q, v, dfdq, dfdv);
        }
        if !self.vehicle_jacobians(t, q, v, dfdq.blocks_mut(), dfdv.blocks_mut())? {
            return Ok(false);
        }
        dfdq.clear_coupling();
        dfdv.clear_coupling();
        self.add_coupler_jacobians(t, |i, j, x, y| dfdq.add(i, j, x) && dfdv.add(i, j, y))?;
        Ok(true)
    }

    fn accept_step(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<(), SimError> {
        // The coupled vehicles' kinematics at the accepted state, if a
        // coupler keeps state.
        let needed: Vec<bool> = (0..self.vehicles.len())
            .map(|k| {
                self.couplers
                    .iter()
                    .any(|c| c.element.remembers_accepted_steps() && c.vehicles.contains(&k))
            })
            .collect();
        let ranges = &self.ranges;
        each_vehicle(self.pool.as_ref(), &mut self.vehicles, |k, s| {
            let r = ranges[k].clone();
            s.accept_step(t, &q[r.clone()], &v[r.clone()])?;
            if needed[k] {
                s.evaluate(t, &q[r.clone()], &v[r], Parts::KINEMATICS)?;
            }
            Ok(())
        })?;
        self.accept_couplers(t)
    }

    fn remembers_accepted_steps(&self) -> bool {
        self.vehicles.iter().any(|s| s.remembers_accepted_steps())
            || self
                .couplers
                .iter()
                .any(|c| c.element.remembers_accepted_steps())
    }
}

impl RunSystem for TrainSystem {
    fn take_assessment_loads(&mut self, out: &mut Vec<LoadSample>) {
        TrainSystem::take_assessment_loads(self, out);
    }

    fn assessment_name(&self, key: usize) -> String {
        TrainSystem::assessment_name(self, key)
    }
}

/// The output columns of a train: `time`, `s[m]` (the train's reference
/// point), each vehicle's columns prefixed by its name, the couplers'.
struct TrainColumns {
    header: Vec<String>,
    /// The reference point's speed law and the offset of the vehicle it
    /// belongs to (the column `s[m]` is the train's reference arc position).
    arc: Option<(RunningSpeed, f64)>,
    vehicles: Vec<Columns>,
}

impl RowColumns<TrainSystem> for TrainColumns {
    fn header(&self) -> &[String] {
        &self.header
    }

    fn values(
        &self,
        train: &mut TrainSystem,
        row: &Row,
        values: &mut Vec<f64>,
    ) -> Result<(), RunError> {
        if let Some((arc, offset)) = &self.arc {
            let [s, v] = arc_motion(arc, row.t)?;
            values.extend([s - offset, v]);
        }
        for (k, cols) in self.vehicles.iter().enumerate() {
            let vehicle_row = row.slice(train.range(k));
            cols.values(train.vehicle_mut(k), vehicle_row, values)?;
        }
        Ok(train.coupler_outputs(row.t, &row.q, &row.v, values)?)
    }
}

/// A train ready to run: the assembled system, its initial state, the times
/// at which any vehicle's frames pass a kink of the track, and the output
/// header.
pub struct TrainSetup {
    /// The assembled system.
    pub system: TrainSystem,
    /// Initial coordinates, stacked in vehicle order.
    pub q0: Vec<f64>,
    /// Initial velocities.
    pub v0: Vec<f64>,
    /// Times at which a vehicle's frames pass a kink of the track, s.
    pub breakpoints: Vec<f64>,
    /// The output header.
    pub header: Vec<String>,
    /// The train's coordinates in system order, each named
    /// `<vehicle>.<coordinate>` (`Coach2.Bogie1.WS1.ws.y`).
    pub coordinates: Vec<CoordinateInfo>,
    /// The equilibrium the run starts from (`initial_state: Equilibrium`):
    /// all vehicles and couplers solved together.
    pub equilibrium: Option<Equilibrium>,
    columns: TrainColumns,
}

/// Builds the train of `train` from its vehicles' models (`models`, in
/// vehicle order) and engines (one per vehicle, built for its model). Errors
/// name the train file.
pub fn build_train(
    train: &TrainScenario,
    models: &[&Model],
    engines: Vec<Box<dyn Equations>>,
) -> Result<TrainSetup, RunError> {
    build_train_with(
        train,
        models,
        engines,
        &crate::forces::ContactTableCache::new(),
    )
}

/// [`build_train`] taking the wheel–rail contact tables from `tables` and
/// leaving the ones it builds there (the vehicles of the train share them,
/// and so do the trains given the same cache: the cases of a study).
pub fn build_train_with(
    train: &TrainScenario,
    models: &[&Model],
    engines: Vec<Box<dyn Equations>>,
    tables: &crate::forces::ContactTableCache,
) -> Result<TrainSetup, RunError> {
    let setup = |message: String| RunError::Setup {
        file: train.source.clone(),
        message,
    };
    if models.len() != train.vehicles.len() || engines.len() != train.vehicles.len() {
        return Err(setup(format!(
            "a train of {} vehicles needs as many models and engines (got {} and {})",
            train.vehicles.len(),
            models.len(),
            engines.len()
        )));
    }
    train.check_names(models)?;
    let mut vehicles = Vec::new();
    let mut columns_all = Vec::new();
    let mut header = vec!["time".to_string()];
    header.extend(ARC_COLUMNS.map(String::from));
    let (mut q0, mut v0, mut breakpoints) = (Vec::new(), Vec::new(), Vec::new());
    let mut coordinates = Vec::new();
    let mut arc = None;
    // Contact tables built for one vehicle serve the others.
    for (k, (model, engine)) in models.iter().zip(engines).enumerate() {
        let name = &train.vehicles[k].name;
        let scenario = train.vehicle_scenario(k, model);
        let state = scenario_state(&scenario, model)?;
        let (equations, times, binding) =
            drive_track_frames(&scenario, model, &state.params, engine, tables)?;
        let mut system = ModelSystem::new(model, equations, state.params)?;
        match binding {
            Some(b) => {
                system.bind_track(&b)?;
                if arc.is_none() {
                    arc = Some((b.speed.clone(), train.vehicles[k].offset));
                }
            }
            None => {
                if let Some(f) = system.forces().iter().find(|f| f.needs_track()) {
                    return Err(setup(format!(
                        "vehicle \"{name}\": force element \"{}\" needs a track: put its \
                         wheelset on a track-following frame",
                        f.name()
                    )));
                }
            }
        }
        let cols = columns(model, &system, &scenario.output, &train.source, None)?;
        header.extend(cols.header.iter().skip(1).map(|h| format!("{name}.{h}")));
        columns_all.push(cols);
        check_integrator(&system, &train.integrator)
            .map_err(|m| setup(format!("vehicle \"{name}\": {m}")))?;
        let (q, v) = system.initial_state(0.0, &state.q, &state.v)?;
        q0.extend(q);
        v0.extend(v);
        coordinates.extend(
            crate::analysis::coordinates(model, &system)
                .into_iter()
                .map(|c| CoordinateInfo {
                    name: format!("{name}.{}", c.name),
                    owner: format!("{name}.{}", c.owner),
                    kind: c.kind,
                }),
        );
        breakpoints.extend(times);
        vehicles.push((name.clone(), system));
    }
    breakpoints.sort_by(f64::total_cmp);
    breakpoints.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let mut couplers = Vec::new();
    for c in &train.couplers {
        let (b1, b2) = train
            .resolve_coupler(c, models)
            .map_err(|e| setup(e.to_string()))?;
        let coupler = Coupler::new(c, b1, b2)?;
        header.extend(
            coupler
                .output_names()
                .iter()
                .map(|s| format!("{}.{s}", c.name)),
        );
        couplers.push(coupler);
    }
    for f in train.resolve_elements(models)? {
        let coupler = Coupler::from_element(&f).map_err(|e| setup(e.to_string()))?;
        header.extend(
            coupler
                .output_names()
                .iter()
                .map(|s| format!("{}.{s}", f.name)),
        );
        couplers.push(coupler);
    }
    let mut system = TrainSystem::new(vehicles, couplers)?;
    system.set_threads(train.threads)?;
    if arc.is_none() {
        header.remove(1);
    }
    let equilibrium = match train.initial_kind {
        InitialStateKind::Given => None,
        InitialStateKind::Equilibrium => {
            // Frictionless, as a vehicle's (run::scenario_system_with).
            system.keep_initial_force_states();
            let eq = crate::analysis::equilibrium::solve(
                &mut system,
                &coordinates,
                0.0,
                &q0,
                &v0,
                &EquilibriumSettings::default(),
            )
            .map_err(|e| setup(format!("initial_state: Equilibrium: {e}")))?;
            // The force elements' states (anchors, modes) start there.
            system.accept_step(eq.t, &eq.q, &eq.v)?;
            q0.clone_from(&eq.q);
            v0.clone_from(&eq.v);
            Some(eq)
        }
    };
    Ok(TrainSetup {
        system,
        q0,
        v0,
        breakpoints,
        coordinates,
        equilibrium,
        header: header.clone(),
        columns: TrainColumns {
            header,
            arc,
            vehicles: columns_all,
        },
    })
}

/// Runs the train scenario `train` (vehicles' models and engines in vehicle
/// order) and writes the output CSV to `output` (if given): columns `time`,
/// `s[m]` (the train's reference point), then each vehicle's columns prefixed
/// by its name (`Coach2.Bogie1.WS1.contact.L.Q[N]`), then the couplers'
/// forces (`C12.Fx[N]` …). As [`crate::run::run_scenario`] otherwise.
pub fn run_train(
    train: &TrainScenario,
    models: &[&Model],
    engines: Vec<Box<dyn Equations>>,
    output: Option<&Path>,
    progress: impl FnMut(f64),
) -> Result<RunSummary, RunError> {
    let mut sink = crate::run::output_sink(output, &train.input_files())?;
    run_train_into(train, models, engines, &mut *sink, progress)
}

/// [`run_train`] writing the rows to `sink`.
pub fn run_train_into(
    train: &TrainScenario,
    models: &[&Model],
    engines: Vec<Box<dyn Equations>>,
    sink: &mut dyn OutputSink,
    progress: impl FnMut(f64),
) -> Result<RunSummary, RunError> {
    let tables = crate::forces::ContactTableCache::new();
    run_train_with(train, models, engines, sink, progress, &tables)
}

/// [`run_train_into`] taking the wheel–rail contact tables from `tables`
/// and leaving the ones it builds there, as
/// [`run_scenario_with`](crate::run::run_scenario_with) does for one
/// vehicle: the runs of a study of one train build each table once (a table
/// is the same whoever builds it, so the results are too).
pub fn run_train_with(
    train: &TrainScenario,
    models: &[&Model],
    engines: Vec<Box<dyn Equations>>,
    sink: &mut dyn OutputSink,
    mut progress: impl FnMut(f64),
    tables: &crate::forces::ContactTableCache,
) -> Result<RunSummary, RunError> {
    let mut names: Vec<String> = Vec::new();
    for e in &engines {
        if !names.iter().any(|n| n == e.engine_name()) {
            names.push(e.engine_name().to_string());
        }
    }
    let TrainSetup {
        mut system,
        q0,
        v0,
        breakpoints,
        columns,
        ..
    } = build_train_with(train, models, engines, tables)?;
    let runner = Runner {
        integrator: &train.integrator,
        breakpoints: &breakpoints,
        t_end: train.end_time,
        interval: train.output.interval,
    };
    let mut summary = RunSummary::new(names.join("+"));
    let start = CpuClock::start();
    // Each vehicle keeps its bodies' absolute velocities across a kink.
    let (rows, last_step, assessment) = runner.run(
        &mut system,
        (&q0, &v0),
        &columns,
        sink,
        &mut summary,
        &mut progress,
        |system: &mut TrainSystem, t_prev, t0, q, v| {
            let mut out = v.to_vec();
            for kv in 0..system.vehicle_count() {
                let r = system.range(kv);
                let vn = continuous_velocities(
                    system.vehicle_mut(kv),
                    t_prev,
                    t0,
                    &q[r.clone()],
                    &v[r.clone()],
                )?;
                out[r].copy_from_slice(&vn);
            }
            Ok(out)
        },
    )?;
    let cpu_time = start.seconds();
    summary.finish(cpu_time, rows, last_step, assessment);
    Ok(summary)
}

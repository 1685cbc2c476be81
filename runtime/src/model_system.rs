//! A model ready to integrate: an [`Equations`] engine, the runtime force
//! elements and the parameter values, seen by the integrators as a
//! [`MechanicalSystem`].

use crate::equations::{Equations, Evaluation, Parts};
use crate::forces::{self, ForceContext, ForceElement, ForceJacobian, JacobianScratch, Wrench};
use crate::run::assessment::LoadSample;
use crate::system::{MechanicalSystem, SimError};
use nalgebra::{DMatrix, DVector};
use railmbs_integrate::{BlockMatrix, BlockPattern};
use railmbs_models::Model;
use std::sync::Arc;

/// Equations of motion plus force elements with fixed parameter values.
pub struct ModelSystem {
    equations: Box<dyn Equations>,
    forces: Vec<Box<dyn ForceElement>>,
    params: Vec<f64>,
    eval: Evaluation,
    wrenches: Vec<Wrench>,
    dynamics_parts: Parts,
    jacobian_scratch: JacobianScratch,
    /// Whether the force elements' states (friction modes, anchors) have been
    /// set from an accepted state; the first evaluation sets them from the
    /// initial state.
    forces_initialized: bool,
    /// Zeros, the velocity argument of constraint evaluations.
    zero_velocity: Vec<f64>,
    /// The engine's generalized coordinates n; the force elements' first-order
    /// states follow them in the system's q (see [`ForceElement::state_count`]).
    n_coordinates: usize,
    /// Element states z and rates ż at the last evaluation.
    states: Vec<f64>,
    state_rates: Vec<f64>,
    /// Per element with states: (element index, offset into z, count).
    state_owners: Vec<(usize, usize, usize)>,
    /// Wheel loads of the last accepted step, for the run's assessment.
    accepted_loads: Vec<LoadSample>,
    /// Per body: the coordinates its pose depends on (its own joint's and
    /// its ancestors'), sorted: the structurally nonzero columns of its
    /// Jacobian Γ.
    body_coordinates: Vec<Vec<usize>>,
    /// The block structure of M and the force Jacobians by top-level
    /// subsystem, when it pays ([`subsystem_block_pattern`]).
    block_pattern: Option<Arc<BlockPattern>>,
    /// Dense ∂f/∂q and ∂f/∂q̇, the force elements' assembly target when the
    /// integrator asks for the Jacobians in blocks (allocated on first use).
    dense_jacobians: Option<(DMatrix<f64>, DMatrix<f64>)>,
}

impl std::fmt::Debug for ModelSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ModelSystem")
            .field("engine", &self.equations.engine_name())
            .field("dof", &self.equations.dof())
            .field("forces", &self.forces.len())
            .finish()
    }
}

impl ModelSystem {
    /// Combines an engine built for `model` with the model's force elements and
    /// the parameter values `params` (in `model.parameters` order).
    pub fn new(
        model: &Model,
        mut equations: Box<dyn Equations>,
        params: Vec<f64>,
    ) -> Result<Self, SimError> {
        if equations.dof() != model.coordinates.len()
            || equations.body_count() != model.bodies.len()
        {
            return Err(SimError::Other(format!(
                "the {} engine has {} coordinates and {} bodies, the model \"{}\" has {} and {}",
                equations.engine_name(),
                equations.dof(),
                equations.body_count(),
                model.name,
                model.coordinates.len(),
                model.bodies.len()
            )));
        }
        if equations.input_count() > 0 {
            return Err(SimError::Other(format!(
                "model \"{}\" has {} track-following frame(s) whose pose must come from a track: \
                 wrap the engine in DrivenEquations with an input provider",
                model.name,
                model.track_frames.len()
            )));
        }
        equations.set_parameters(&params)?;
        let mut forces = forces::build(model);
        let mut state_owners = Vec::new();
        let mut n_states = 0;
        for (i, f) in forces.iter_mut().enumerate() {
            f.set_parameters(&params)?;
            let count = f.state_count();
            if count > 0 {
                f.set_state_offset(n_states);
                state_owners.push((i, n_states, count));
                n_states += count;
            }
        }
        let eval = Evaluation::for_equations(equations.as_ref());
        let nb = equations.body_count();
        let body_coordinates = body_coordinates(model);
        let block_pattern = if n_states == 0 && equations.constraint_count() == 0 {
            subsystem_block_pattern(model, &body_coordinates)
        } else {
            None
        };
        let dynamics_parts = Parts {
            mass: true,
            bias: true,
            gravity: true,
            // Body kinematics and Jacobians serve the force elements only.
            kinematics: !forces.is_empty(),
            jacobians: !forces.is_empty(),
            constraints: false,
        };
        Ok(Self {
            equations,
            forces,
            params,
            eval,
            wrenches: vec![Wrench::default(); nb],
            dynamics_parts,
            jacobian_scratch: JacobianScratch::new(model.coordinates.len()),
            forces_initialized: false,
            zero_velocity: Vec::new(),
            n_coordinates: model.coordinates.len(),
            states: vec![0.0; n_states],
            state_rates: vec![0.0; n_states],
            state_owners,
            accepted_loads: Vec::new(),
            body_coordinates,
            block_pattern,
            dense_jacobians: None,
        })
    }

    /// The coordinates body `b`'s pose depends on (its own joint's and its
    /// ancestors' in the model tree), sorted: the columns of its Jacobian Γ
    /// that can be nonzero, hence the coordinates a force element on this
    /// body couples.
    pub fn body_coordinates(&self, b: usize) -> &[usize] {
        &self.body_coordinates[b]
    }

    /// Connects the force elements that need the track (wheel–rail contact)
    /// to the scenario's track.
    pub fn bind_track(&mut self, binding: &forces::TrackBinding) -> Result<(), SimError> {
        for f in &mut self.forces {
            f.bind_track(binding)?;
        }
        Ok(())
    }

    /// Moves the wheel loads of the last accepted step (one sample per
    /// wheel–rail element, keyed by element index) to `out`.
    pub fn take_assessment_loads(&mut self, out: &mut Vec<LoadSample>) {
        out.append(&mut self.accepted_loads);
    }

    /// The buffers of the last evaluation (by `dynamics`, `force_jacobian` or
    /// `evaluate`), e.g. for forces applied from outside the model.
    pub fn last_evaluation(&self) -> &Evaluation {
        &self.eval
    }

    /// Makes `dynamics` always evaluate body kinematics and Jacobians (for
    /// forces applied from outside the model: a train's couplers).
    pub fn require_body_jacobians(&mut self) {
        self.dynamics_parts.kinematics = true;
        self.dynamics_parts.jacobians = true;
    }

    /// The engine.
    pub fn equations(&self) -> &dyn Equations {
        self.equations.as_ref()
    }

    /// The force elements.
    pub fn forces(&self) -> &[Box<dyn ForceElement>] {
        &self.forces
    }

    /// Parameter values in use.
    pub fn params(&self) -> &[f64] {
        &self.params
    }

    /// Number of the engine's generalized coordinates (the system's q and q̇
    /// also carry the force elements' first-order states after them).
    pub fn coordinate_count(&self) -> usize {
        self.n_coordinates
    }

    /// Number of first-order element states.
    pub fn state_count(&self) -> usize {
        self.states.len()
    }

    /// Long names of the first-order element states (`<element>.<state>`), in
    /// the order they follow the coordinates.
    pub fn state_names(&self) -> Vec<String> {
        self.state_owners
            .iter()
            .flat_map(|&(i, _, _)| {
                let f = &self.forces[i];
                f.state_names()
                    .into_iter()
                    .map(move |s| format!("{}.{s}", f.name()))
            })
            .collect()
    }

    /// Lets the force elements keep the states they were built with (no
    /// stick anchor, no friction mode, no accepted rail state) until the
    /// next accepted step, instead of accepting the state of the first
    /// evaluation. The static equilibrium is solved so
    /// ([`crate::run::scenario::scenario_system`]): accepted at the initial guess, a
    /// contact or friction element would stick there, and its anchor would
    /// hold whatever force the settling to the equilibrium puts on it (up to
    /// the static limit), an equilibrium the element forgets at the next
    /// accepted step. Never accepted, such an element at rest carries no
    /// friction force: the equilibrium found is the frictionless one (a valid
    /// static state with friction too, zero being inside every friction
    /// cone), and accepting it afterwards sticks every element there with
    /// its force unchanged.
    pub fn keep_initial_force_states(&mut self) {
        self.forces_initialized = true;
    }

    /// The system's initial q and q̇ from the coordinates' (`q`, `v`, n
    /// entries each): appends the element states and rates consistent with
    /// their equations at (t, q, v).
    pub fn initial_state(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), SimError> {
        let (mut qs, mut vs) = (q.to_vec(), v.to_vec());
        if self.state_owners.is_empty() {
            return Ok((qs, vs));
        }
        self.equations
            .evaluate(t, q, v, Parts::KINEMATICS, &mut self.eval)?;
        let n = self.states.len();
        let (mut z, mut zdot) = (vec![0.0; n], vec![0.0; n]);
        let ctx = ForceContext {
            t,
            bodies: &self.eval.bodies,
            params: &self.params,
            states: &self.states,
            state_rates: &self.state_rates,
        };
        for &(i, offset, count) in &self.state_owners {
            self.forces[i].initial_states(
                &ctx,
                &mut z[offset..offset + count],
                &mut zdot[offset..offset + count],
            );
        }
        qs.extend(z);
        vs.extend(zdot);
        Ok((qs, vs))
    }

    /// Splits the system's q, q̇ into the coordinates' part (returned) and the
    /// element states (stored for the force elements).
    fn take_states<'q>(&mut self, q: &'q [f64], v: &'q [f64]) -> (&'q [f64], &'q [f64]) {
        let n = self.n_coordinates;
        if q.len() > n {
            self.states.copy_from_slice(&q[n..]);
            self.state_rates.copy_from_slice(&v[n..]);
        }
        (&q[..n.min(q.len())], &v[..n.min(v.len())])
    }

    /// Evaluates `parts` at a state and returns the buffers (for outputs and
    /// tests). `q`, `v` are the system's (coordinates, then element states) or
    /// the coordinates only (the element states of the last evaluation stay).
    pub fn evaluate(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        parts: Parts,
    ) -> Result<&Evaluation, SimError> {
        let (n, ns) = (self.n_coordinates, self.states.len());
        if (q.len() != n && q.len() != n + ns) || v.len() != q.len() {
            return Err(SimError::Other(format!(
                "state of {} coordinates and {} velocities for a system of {n} coordinates \
                 and {ns} element states",
                q.len(),
                v.len()
            )));
        }
        let (q, v) = self.take_states(q, v);
        self.equations.evaluate(t, q, v, parts, &mut self.eval)?;
        Ok(&self.eval)
    }

    /// Output values of all force elements at a state (after `evaluate` with
    /// kinematics), in element order.
    pub fn force_outputs(&self, t: f64, out: &mut Vec<f64>) {
        let ctx = ForceContext {
            t,
            bodies: &self.eval.bodies,
            params: &self.params,
            states: &self.states,
            state_rates: &self.state_rates,
        };
        for f in &self.forces {
            f.outputs(&ctx, out);
        }
    }

    /// [`Self::force_outputs`] of the elements `elements` (indices into
    /// [`Self::forces`]) only, in that order.
    pub fn force_outputs_of(&self, t: f64, elements: &[usize], out: &mut Vec<f64>) {
        let ctx = ForceContext {
            t,
            bodies: &self.eval.bodies,
            params: &self.params,
            states: &self.states,
            state_rates: &self.state_rates,
        };
        for &e in elements {
            self.forces[e].outputs(&ctx, out);
        }
    }

    /// Generalized applied forces Q = Q_g + Σ_j Γ_jᵀ F_j (needs kinematics and
    /// Jacobians evaluated) in the coordinates' rows of `out`, and the element
    /// state residuals in the rows after them.
    fn applied_forces(&mut self, t: f64, out: &mut DVector<f64>) -> Result<(), SimError> {
        let n = self.n_coordinates;
        out.as_mut_slice()[..n].copy_from_slice(self.eval.gravity.as_slice());
        if self.forces.is_empty() {
            return Ok(());
        }
        self.wrenches.fill(Wrench::default());
        let ctx = ForceContext {
            t,
            bodies: &self.eval.bodies,
            params: &self.params,
            states: &self.states,
            state_rates: &self.state_rates,
        };
        for f in &self.forces {
            f.apply(&ctx, &mut self.wrenches)?;
        }
        for &(i, offset, count) in &self.state_owners {
            let rows = &mut out.as_mut_slice()[n + offset..n + offset + count];
            self.forces[i].state_residuals(&ctx, rows);
        }
        for (j, w) in self.wrenches.iter().enumerate() {
            forces::add_generalized_force(&self.eval.jacobians, j, w, out.as_mut_slice());
        }
        Ok(())
    }
}

impl MechanicalSystem for ModelSystem {
    fn dof(&self) -> usize {
        self.n_coordinates + self.states.len()
    }

    fn is_first_order(&self, i: usize) -> bool {
        i >= self.n_coordinates && i < self.n_coordinates + self.states.len()
    }

    fn n_constraints(&self) -> usize {
        self.equations.constraint_count()
    }

    /// The first call (at the initial state of a run) also initializes the
    /// force elements' states there, as if that state had been accepted
    /// (friction elements start sticking where they are at rest).
    fn dynamics(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        mass: &mut DMatrix<f64>,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        self.evaluate_forces(t, q, v, force)?;
        let n = self.n_coordinates;
        if self.states.is_empty() {
            mass.as_mut_slice()
                .copy_from_slice(self.eval.mass.as_slice());
        } else {
            // Element states have no inertia: zero rows and columns.
            mass.as_mut_slice().fill(0.0);
            mass.view_mut((0, 0), (n, n)).copy_from(&self.eval.mass);
        }
        Ok(())
    }

    /// With equations that solve M x = b themselves (the articulated-body
    /// formalism, [`crate::Equations::solves_mass`]) and no element states:
    /// M is not evaluated, q̈ = M⁻¹ (Q − k) by that solve in O(n).
    fn accelerations(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        accel: &mut DVector<f64>,
    ) -> Result<bool, SimError> {
        if !self.states.is_empty() || self.n_constraints() > 0 || !self.equations.solves_mass() {
            return Ok(false);
        }
        if !self.forces_initialized {
            self.accept_forces(t, q, v)?;
        }
        let (q, v) = self.take_states(q, v);
        let parts = Parts {
            mass: false,
            ..self.dynamics_parts
        };
        self.equations.evaluate(t, q, v, parts, &mut self.eval)?;
        self.applied_forces(t, accel)?;
        *accel -= &self.eval.bias;
        self.equations.solve_mass(accel.as_mut_slice())
    }

    fn constraints(
        &mut self,
        t: f64,
        q: &[f64],
        g: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), SimError> {
        // Constraints depend on q only; reuse a zero velocity vector.
        let q = &q[..self.n_coordinates];
        self.zero_velocity.resize(q.len(), 0.0);
        let parts = Parts {
            mass: false,
            bias: false,
            gravity: false,
            kinematics: false,
            jacobians: false,
            constraints: true,
        };
        self.equations
            .evaluate(t, q, &self.zero_velocity, parts, &mut self.eval)?;
        g.copy_from(&self.eval.constraints);
        if self.states.is_empty() {
            jacobian.copy_from(&self.eval.constraint_jacobian);
        } else {
            jacobian.as_mut_slice().fill(0.0);
            let (nc, n) = self.eval.constraint_jacobian.shape();
            jacobian
                .view_mut((0, 0), (nc, n))
                .copy_from(&self.eval.constraint_jacobian);
        }
        Ok(())
    }

    /// The approximate analytic Jacobian of Pogorelov 2005, Sect. 6 (Eq. 31):
    /// ∂f/∂q ≈ Σ_elements Gᵀ C_loc G and ∂f/∂q̇ ≈ Σ Gᵀ D_loc G from the force
    /// elements' local Jacobians ([`ForceElement::add_jacobian`]); the
    /// derivatives of the inertia, gyroscopic and gravity terms and of the
    /// body Jacobians are neglected. Systems without force elements return
    /// `Ok(false)` (the integrator then differentiates numerically).
    fn force_jacobian(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        dfdq: &mut DMatrix<f64>,
        dfdv: &mut DMatrix<f64>,
    ) -> Result<bool, SimError> {
        if self.forces.is_empty() {
            return Ok(false);
        }
        let parts = Parts {
            mass: false,
            bias: false,
            gravity: false,
            kinematics: true,
            jacobians: true,
            constraints: false,
        };
        let (q, v) = self.take_states(q, v);
        self.equations.evaluate(t, q, v, parts, &mut self.eval)?;
        dfdq.as_mut_slice().fill(0.0);
        dfdv.as_mut_slice().fill(0.0);
        let ctx = ForceContext {
            t,
            bodies: &self.eval.bodies,
            params: &self.params,
            states: &self.states,
            state_rates: &self.state_rates,
        };
        let mut jac = ForceJacobian::new(
            &self.eval.jacobians,
            &self.eval.bodies,
            dfdq,
            dfdv,
            &mut self.jacobian_scratch,
        );
        for f in &self.forces {
            f.add_jacobian(&ctx, &mut jac)?;
        }
        Ok(true)
    }

    fn accept_step(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<(), SimError> {
        self.accept_forces(t, q, v)
    }

    fn remembers_accepted_steps(&self) -> bool {
        self.forces.iter().any(|f| f.remembers_accepted_steps())
    }

    fn block_pattern(&self) -> Option<Arc<BlockPattern>> {
        self.block_pattern.clone()
    }

    /// [`MechanicalSystem::dynamics`] with M copied blockwise from the
    /// engine's dense M (the pattern exists only without element states).
    fn dynamics_blocks(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        mass: &mut BlockMatrix,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        self.evaluate_forces(t, q, v, force)?;
        mass.copy_from_dense(&self.eval.mass);
        Ok(())
    }

    /// [`MechanicalSystem::force_jacobian`] assembled densely into reused
    /// storage, then copied blockwise.
    fn force_jacobian_blocks(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        dfdq: &mut BlockMatrix,
        dfdv: &mut BlockMatrix,
    ) -> Result<bool, SimError> {
        let n = self.dof();
        let (mut dq, mut dv) = self
            .dense_jacobians
            .take()
            .unwrap_or_else(|| (DMatrix::zeros(n, n), DMatrix::zeros(n, n)));
        let result = self.force_jacobian(t, q, v, &mut dq, &mut dv);
        if let Ok(true) = result {
            dfdq.copy_from_dense(&dq);
            dfdv.copy_from_dense(&dv);
        }
        self.dense_jacobians = Some((dq, dv));
        result
    }
}

impl ModelSystem {
    /// The evaluation behind [`MechanicalSystem::dynamics`] and its block
    /// form: the force elements' states set at the first call (as if the
    /// initial state had been accepted), the engine's M, k and Q_g at (t, q,
    /// q̇) in `self.eval`, and `force` = Q − k (element state rates after
    /// the coordinates' rows).
    fn evaluate_forces(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        if !self.forces_initialized {
            self.accept_forces(t, q, v)?;
        }
        let (q, v) = self.take_states(q, v);
        self.equations
            .evaluate(t, q, v, self.dynamics_parts, &mut self.eval)?;
        self.applied_forces(t, force)?;
        let n = self.n_coordinates;
        // Slices, not nalgebra's generic views: a plain loop and a memcpy
        // at any optimization level (this runs once per RK4 stage).
        for (f, b) in force.as_mut_slice()[..n]
            .iter_mut()
            .zip(self.eval.bias.as_slice())
        {
            *f -= b;
        }
        Ok(())
    }

    /// Tells the force elements that (t, q, q̇) is accepted (their states
    /// update); fails when the kinematics there cannot be evaluated.
    fn accept_forces(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<(), SimError> {
        self.forces_initialized = true;
        if self.forces.is_empty() {
            return Ok(());
        }
        let (q, v) = self.take_states(q, v);
        self.equations
            .evaluate(t, q, v, Parts::KINEMATICS, &mut self.eval)?;
        let ctx = ForceContext {
            t,
            bodies: &self.eval.bodies,
            params: &self.params,
            states: &self.states,
            state_rates: &self.state_rates,
        };
        self.accepted_loads.clear();
        for (key, f) in self.forces.iter_mut().enumerate() {
            if let Some(loads) = f.assessment_loads(&ctx) {
                self.accepted_loads.push(LoadSample { key, t, loads });
            }
            f.accept_step(&ctx)?;
        }
        Ok(())
    }
}

/// Per body of `model`: the coordinates of its joint and its ancestors'
/// joints, sorted (parents come before their children in the model).
fn body_coordinates(model: &Model) -> Vec<Vec<usize>> {
    let mut out: Vec<Vec<usize>> = Vec::with_capacity(model.bodies.len());
    for (b, body) in model.bodies.iter().enumerate() {
        let mut set = match body.parent {
            railmbs_models::BodyRef::Body(p) if p < b => out[p].clone(),
            _ => Vec::new(),
        };
        set.extend(
            model
                .coordinates
                .iter()
                .enumerate()
                .filter(|(_, c)| c.body == b)
                .map(|(i, _)| i),
        );
        set.sort_unstable();
        set.dedup();
        out.push(set);
    }
    out
}

/// The bordered block-diagonal pattern of `model`'s matrices by top-level
/// subsystem, when it pays ([`BlockPattern::pays`]): one diagonal block per
/// subsystem included in the top model file (a vehicle's bogies), one for
/// the file's own bodies (its car body), each a contiguous range of
/// coordinates; the border is every coordinate that couples to another
/// block. Two coordinates couple when one body's pose depends on both (M,
/// the inertia terms and a body Jacobian Γ couple a body's coordinates with
/// its ancestors', `body_coordinates`) or when one force element acts on
/// bodies whose poses depend on them (its wrench depends on those bodies'
/// kinematics only: Pogorelov 2005, Sect. 6, Eq. 31, ∂f/∂q = Σ Gᵀ C G). A
/// three-piece freight car (114 coordinates) has two 54-coordinate bogie
/// blocks bordered by the car body and the two bolsters (18 coordinates),
/// a bordered LU of about a fifth of the dense work. `None` for models with
/// one block, with blocks that are not contiguous in the coordinate order,
/// or when the dense LU is as cheap. Callers exclude models with element
/// states or constraints (Park's block path has neither).
fn subsystem_block_pattern(
    model: &Model,
    body_coordinates: &[Vec<usize>],
) -> Option<Arc<BlockPattern>> {
    let n = model.coordinates.len();
    let subsystem = |b: usize| model.bodies[b].name.split_once('.').map(|(s, _)| s);
    // Blocks: runs of coordinates of the same top-level subsystem.
    let mut blocks: Vec<std::ops::Range<usize>> = Vec::new();
    let mut keys: Vec<Option<&str>> = Vec::new();
    let mut block_of = vec![0; n];
    for (i, c) in model.coordinates.iter().enumerate() {
        let key = subsystem(c.body);
        if keys.last() != Some(&key) {
            if keys.contains(&key) {
                return None;
            }
            keys.push(key);
            blocks.push(i..i);
        }
        let k = blocks.len() - 1;
        blocks[k].end = i + 1;
        block_of[i] = k;
    }
    if blocks.len() < 2 {
        return None;
    }
    let mut border = Vec::new();
    let mut mark = |group: &[usize]| {
        if let Some(&first) = group.first()
            && group.iter().any(|&i| block_of[i] != block_of[first])
        {
            border.extend_from_slice(group);
        }
    };
    for set in body_coordinates {
        mark(set);
    }
    for f in &model.forces {
        let mut group: Vec<usize> = f
            .kind
            .bodies()
            .into_iter()
            .flat_map(|b| body_coordinates[b].iter().copied())
            .collect();
        group.sort_unstable();
        group.dedup();
        mark(&group);
    }
    let pattern = BlockPattern::new(blocks, border).ok()?;
    pattern.pays().then(|| Arc::new(pattern))
}

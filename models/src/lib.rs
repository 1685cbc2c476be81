//! # railmbs-models
//!
//! The model description language of railmbs. A vehicle, a mechanism or a
//! scenario is described once in a RON file; this crate reads it, resolves
//! identifiers and expressions, flattens included subsystems into long names
//! (`Bogie1.WS2.axle`), and validates it with errors that name the file, the
//! element and the RON line and column. The result is a [`Model`] (or a
//! [`Scenario`]) that both engines — the numeric-iterative `runtime` and the
//! symbolic `codegen` — consume.
//!
//! ```no_run
//! use std::path::Path;
//! let model = railmbs_models::load_model(Path::new("models/mechanisms/double_pendulum.ron"))
//!     .unwrap_or_else(|errors| panic!("{errors}")); // one located error per line
//! let params = model.parameter_values(&["heavy".to_string()], &[("l1".into(), "2".into())])?;
//! let (q0, v0) = model.initial_state(&params);
//! # Ok::<(), railmbs_models::ModelError>(())
//! ```
//!
//! ## Model files
//!
//! Units are SI (m, kg, s, N, rad). The inertial frame is `ground` (x forward,
//! y left, z up); a body frame has its origin at the body's centre of mass.
//! `//` and `/* */` comments are allowed. A complete example using every construct:
//!
//! ```ron
//! Model(
//!     name: "double_pendulum",
//!     description: "Two links, a slider and a wheelset", // optional
//!     // Parameters (identifiers), in file order. A value is a number, expression
//!     // text over other parameters, or (value: …, doc: "…"). They stay symbolic in
//!     // the resolved model: runtime inputs of compiled plugins.
//!     parameters: {
//!         "l1": 1.0, "m1": 1.0, "l2": "l1", "m2": (value: 2, doc: "kg"), "m3": 0.5,
//!         "g": 9.81, "k": 1000, "d": 5, "L0": 0.5, "WS1.r0": 0.46,
//!     },
//!     // Named sets of assignments (optional), applied by scenarios.
//!     macros: { "heavy": { "m1": 2.0, "m2": "2*m1" } },
//!     gravity: (0, "-g", 0),                   // optional, default (0, 0, -9.81)
//!     bodies: [                                 // any order: sorted parent-first
//!         Body(
//!             name: "link1",
//!             mass: "m1",
//!             // About the centre of mass, body frame; ixy, ixz, iyz default 0.
//!             inertia: (ixx: "m1*l1^2/12", iyy: 1e-4, izz: "m1*l1^2/12"),
//!             joint: Revolute(parent: "ground", at: (0, 0, 0), axis: Z,
//!                             coord: "q0", init: 0.5, vel: 0.0, to_com: (0, "-l1/2", 0)),
//!         ),
//!         Body(
//!             name: "link2", mass: "m2", inertia: (ixx: 0.1, iyy: 0.1, izz: 0.1),
//!             joint: Joint(parent: "link1", transforms: [
//!                 Ty("-l1/2"),                             // fixed
//!                 Rz((coord: "q1", init: 0.0, vel: 0.0)),  // generalized coordinate
//!                 Rx("0.1*sin(2*pi*t)"),                   // function of time
//!                 Ty("-l2/2"),
//!             ]),
//!         ),
//!         Body(
//!             name: "slider", mass: "m3", inertia: (ixx: 1e-3, iyy: 1e-3, izz: 1e-3),
//!             joint: Prismatic(parent: "ground", axis: X, coord: "s", init: "L0"),
//!         ),
//!         Body(
//!             name: "WS1", mass: 1200, inertia: (ixx: 700, iyy: 100, izz: 700),
//!             // Coordinates WS1.x, WS1.y, WS1.z, then WS1.rz, WS1.rx, WS1.ry.
//!             joint: SixDof(parent: "ground", at: (0, 0, "WS1.r0"), order: "zxy",
//!                           vel: (10, 0, 0, 0, "10/WS1.r0", 0)),
//!         ),
//!         Body(
//!             name: "axlebox", mass: 50, inertia: (ixx: 1, iyy: 1, izz: 1),
//!             joint: Rigid(parent: "WS1", at: (0, 1, 0), rotation: (0, 0, 0)),
//!         ),
//!     ],
//!     cut_joints: [                             // optional
//!         CutJoint(name: "closure", body1: "link2", point1: (0, "-l2/2", 0), rotation1: (0, 0, 0),
//!                  body2: "ground", point2: (2.0, 0, 0), constrain: [Tx, Ty]),
//!     ],
//!     forces: [                                 // optional
//!         Spring(name: "k1", body1: "ground", point1: (0, 0, 0), body2: "slider", point2: (0, 0, 0),
//!                c: "k", d: "d", f0: 0, x0: "L0"),
//!         Linear6(name: "bush", body1: "WS1", point1: (0, 1, 0), rotation1: (0, 0, 0),
//!                 body2: "axlebox", point2: (0, 0, 0), rotation2: (0, 0, 0),
//!                 stiffness: Diag((1e6, 1e6, 1e6, 1e3, 1e3, 1e3)),
//!                 damping: Full([1e3, 0, 0, 0, 0, 0,   0, 1e3, 0, 0, 0, 0,   0, 0, 1e3, 0, 0, 0,
//!                                0, 0, 0, 10, 0, 0,    0, 0, 0, 0, 10, 0,    0, 0, 0, 0, 0, 10]),
//!                 preload: (0, 0, 0, 0, 0, 0)),
//!         Applied(name: "push", body: "slider", point: (0, 0, 0), force: ("10*sin(t)", 0, 0),
//!                 torque: (0, 0, 0), frame: Global),
//!     ],
//! )
//! ```
//!
//! ### Friction, contact and nonlinear force elements
//!
//! Besides `Spring`, `Linear6` and `Applied` (above), `forces` accepts the
//! elements of Pogorelov 2005, Sect. 3 (fields with a default may be left out;
//! every number may be an expression over parameters):
//!
//! ```text
//! // Point–plane contact: points of `body` against the plane of `plane_body`
//! // through `origin` with outward `normal` (that body's frame). Normal force
//! // N = max(0, c·δ + d·δ̇) per point (no adhesion); tangential Coulomb friction:
//! // sticking to an anchor by ct, dt (default c, d) up to mu0·N, sliding at mu·N.
//! PointPlane(name: "feet", body: "block", points: [(0.1, 0.1, -0.05), (-0.1, 0.1, -0.05)],
//!            plane_body: "ground", origin: (0, 0, 0), normal: (0, 0, 1),   // defaults
//!            c: 1e6, d: 500, ct: 1e6, dt: 500, mu0: 0.3, mu: 0.25),      // mu0 default mu
//! // Point–Z-surface variant: the surface z = f(x, y) (an expression in x, y —
//! // m, in the plane body's frame shifted to `origin` — and parameters), solid
//! // below; each point touches its tangent plane there (normal (−f_x, −f_y, 1)).
//! PointPlane(name: "bowl", body: "ball", points: [(0, 0, -0.05)], surface: "(x^2 + y^2)/(2*2.5)",
//!            c: 1e6, d: 500, mu: 0.1),
//! // Bipolar Coulomb friction: sticking F = f0 + c (x − x0) + d ẋ (f0, x0 stored
//! // when sticking starts) until |F| reaches `limit` (F0); then sliding at
//! // `sliding` (default `limit`) against the relative velocity.
//! Coulomb(name: "wedge", body1: "frame", point1: (0, 0, 0), body2: "bolster", point2: (0, 0, 0),
//!         c: 1e7, d: 1e3, limit: 5000, sliding: 4000),
//! // Load-dependent friction (Fig. 3): spring c1 in series with spring c2 in
//! // parallel with friction mu·|force in c2| (static mu0, default mu; mu0 < 1).
//! LoadFriction(name: "snubber", body1: "a", body2: "b", c1: 2e6, c2: 1e6, mu0: 0.3, mu: 0.2, x0: 0.5),
//! // Tabulated characteristic F(x − x0) (piecewise linear, extended linearly
//! // beyond the end rows; deflection m increasing, force N) plus d·ẋ. A bump stop:
//! Tabulated(name: "stop", body1: "a", body2: "b", table: [(-0.02, -2e4), (-0.01, 0), (0.01, 0), (0.02, 2e4)],
//!           d: 100, x0: 0.5),
//! // `interpolation: Spline` (default `Linear`): monotone piecewise cubic through
//! // the rows (Fritsch–Carlson), continuous slope, no overshoot between rows.
//! Tabulated(name: "stop2", body1: "a", body2: "b", table: [(-0.02, -2e4), (-0.01, 0), (0.01, 0), (0.02, 2e4)],
//!           interpolation: Spline, x0: 0.5),
//! // Linear6 helper for a coil spring (frames at its lower plate): vertical,
//! // shear, bending (N m/rad) and torsion stiffness and the height H; shear and
//! // tilt couple by ±c_s·H/2. Also usable for `damping`.
//! Linear6(name: "coil", body1: "a", body2: "b",
//!         stiffness: VerticalSpring(vertical: 1.2e6, shear: 3e5, bending: 4e4, torsion: 2e4, height: 0.4)),
//! // Stiffness c in series with damping d (a Maxwell element), preload f0 in
//! // parallel: F = c·s + f0 with d·(ẋ − ṡ) = c·s. The spring extension s is a
//! // first-order state `<name>.s` integrated with q (Park's method only; RK4
//! // refuses the model); it starts relaxed, s = 0.
//! // No free length: the damper takes up any static length.
//! SeriesSpring(name: "yaw_damper", body1: "a", body2: "b", c: 5e6, d: 2e5, f0: 0),
//! ```
//!
//! As for `Spring`, x is the distance of the two points and a positive force
//! pulls them together. Checked with the default parameters: stiffnesses (`c`,
//! `ct`, `c1`, `c2`) positive, dampings not negative, 0 ≤ `mu` ≤ `mu0`,
//! 0 ≤ `sliding` ≤ `limit`, a non-zero `normal`, at least one contact point,
//! points and plane on different bodies, at least two table rows with
//! increasing deflections.
//!
//! ### Numbers and expressions
//!
//! Every numeric field accepts an integer, a float or an expression string with
//! `+ - * / ^` (`^` is right-associative and binds tighter than unary minus:
//! `-x^2 = -(x^2)`), parentheses, `sin cos tan sqrt abs exp ln atan`, `pi`,
//! numbers (`1`, `1.5`, `1e-3`) and parameter names (letters, digits, `_` and
//! `.`, e.g. `WS1.r0`). Time `t` (s) is allowed only in the elementary
//! transforms of `Joint(...)` (making them rheonomic, [`Motion::Time`]) and in
//! the `force` and `torque` of `Applied`. See [`parser`].
//!
//! ### Joints
//!
//! A joint is the ordered list of elementary transformations (`Tx Ty Tz Rx Ry
//! Rz`, along or about the axes of the current moving frame) from the parent's
//! body frame to the child's. Shorthands (fixed components that are literally 0
//! are dropped):
//!
//! | shorthand | expands to | coordinate names |
//! |---|---|---|
//! | `Revolute(parent, at, axis, coord, init, vel, to_com)` | `Tx Ty Tz`(at), `R<axis>`(coord), `Tx Ty Tz`(to_com) | `coord`, default `<body>.r<axis>` |
//! | `Prismatic(...)`, same fields | `Tx Ty Tz`(at), `T<axis>`(coord), `Tx Ty Tz`(to_com) | `coord`, default `<body>.t<axis>` |
//! | `SixDof(parent, at, order, init, vel, track)` | `Tx Ty Tz`(at), `Tx Ty Tz` coordinates, rotations in `order` (default `"xyz"`) | `<body>.x .y .z .rx .ry .rz` |
//! | `Rigid(parent, at, rotation)` | `Tx Ty Tz`(at), `Rx Ry Rz`(rotation) | none |
//! | `Joint(parent, transforms: [...])` | as written: `Tx(value)` fixed or with `t`, `Tx((coord: "q", init: …, vel: …))` a coordinate | as given |
//!
//! `at` is the joint point in the parent frame and `to_com` the vector from the
//! joint point to the child's centre of mass in the child frame (both default
//! zero). SixDof `init` and `vel` are `(x, y, z, about x, about y, about z)`.
//! `track: Some(offset)` (m, an expression) puts a track-following frame at arc
//! offset `offset` from the vehicle's reference position in front of the six
//! coordinates: the joint then starts with the frame's pose `x y z` (translations)
//! and yaw, pitch, roll (`rz ry rx`), which are runtime inputs supplied by the
//! track at every evaluation (`Model::track_frames`, `Motion::Input`). The parent
//! must be `ground`.
//! Coordinates are numbered in body order (parents first), then transform order.
//!
//! ### Subsystems and connection points
//!
//! A model file may include other model files as subsystems (Pogorelov 2005,
//! Sect. 5): one wheelset file and one bogie file serve every vehicle that
//! uses them. Two optional top-level fields:
//!
//! ```text
//! subsystems: [
//!     Subsystem(
//!         name: "Bogie1",                 // instance name: prefix "Bogie1." (no '.')
//!         file: "../bogies/bogie.ron",    // a model file, relative to this file
//!         parameters: { "offset": "lb", "WS2.m": 1000 },  // overrides (optional)
//!         parent: "carbody",              // optional, see below
//!     ),
//! ],
//! // Named points fixed to bodies (optional): (body, point in its frame).
//! connections: { "SecondaryLeft": (body: "frame", point: (0, 1.0, 0.4)) },
//! ```
//!
//! Loading flattens everything into one plain [`Model`], so the engines see no
//! subsystems. The included file is a complete model file, valid on its own and
//! loaded recursively (vehicle → bogie → wheelset); its `name` and `gravity`
//! are ignored. Every body, coordinate, cut joint, force element, parameter,
//! macro and connection point of the instance gets the long name
//! `<instance>.<name>`: `Bogie1.frame`, `Bogie1.WS2.axle`, the coordinate
//! `Bogie1.WS2.axle.rz`, the force `Bogie1.Primary1Left`, the parameter
//! `Bogie1.WS2.m`, the macro `Bogie1.WS2.worn`, the connection point
//! `Bogie1.WS2.BoxLeft`. In the flattened model, parameters come in this
//! order: the file's own, then each subsystem's (recursively) in the order of
//! `subsystems`; bodies are sorted parent-first, the file's own first.
//!
//! - **Parameters stay runtime parameters.** An override (`parameters:` of a
//!   `Subsystem`) names a parameter of the subsystem (by its name in the
//!   subsystem, e.g. `"offset"`, or a nested one, `"WS2.m"`); its value is an
//!   expression in the *including* file's namespace, which replaces that
//!   parameter's default. So `Bogie1.offset` defaults to `lb` and follows a
//!   change of `lb` (by a macro or a scenario), while a scenario may still set
//!   `Bogie1.offset` itself. The including file may use the subsystems'
//!   parameters by long name in its own expressions, defaults and macros.
//! - **References by long name.** The including file's forces, cut joints
//!   and joints (`parent`) refer to subsystem bodies by long name
//!   (`body1: "Bogie1.frame"`). Wherever a force or cut joint takes a body and
//!   a point, the body may also be a connection point, of this file or by long
//!   name of a subsystem (`body2: "Bogie1.SecondaryLeft"`): then the point
//!   (`point2`, `origin`, `points`, default zero) is an offset from the
//!   connection point, in the same body frame. A connection point's `body` may
//!   itself be a body or a subsystem's connection point.
//! - **`parent:`** re-attaches the subsystem's bodies whose joint parent is
//!   `ground` to that body of the including file (or to another subsystem's
//!   body, by long name). Bodies on track-following frames must stay on ground
//!   (an error). Forces of the subsystem that act on `ground` stay on ground.
//! - **Track-following frames**: an offset such as `track: Some("offset + a")`
//!   is an expression over the subsystem's parameters, so offsets add up
//!   through the levels (`Bogie1.WS1.offset` = `lb + a`).
//! - **Paths** (subsystem files, `WheelRail` profiles) are relative to the file
//!   they are written in; the resolved model holds canonical (absolute)
//!   profile paths. [`Model::source`] is the top file.
//! - **Profiles** are read, parsed and validated when the model loads (a
//!   missing or malformed file is a load error at the profile's field, naming
//!   the file and its line); the model holds their points ([`ProfileFile`]),
//!   and only the track's rail inclination is applied later, when a run
//!   places them on the scenario's track.
//!
//! `models/mechanisms/subsystems/vehicle.ron` is a complete example (a car body,
//! two bogies with two wheelsets each, and an absorber re-attached to the car
//! body); `vehicle_flat.ron` beside it is the same mechanism written out flat.
//!
//! ### Validation
//!
//! All problems are reported together ([`ModelErrors`]), each as
//! `file:line:column: element: message`, e.g.
//! `models/mechanisms/x.ron:12:9: body "link2": mass must be positive, got -1`:
//! RON syntax, unknown fields, unknown identifiers and bodies, duplicate names
//! (bodies, coordinates, forces, cut joints, parameters, macros, subsystems,
//! connection points), loops in the body tree, cycles among parameter
//! defaults, `t` where not allowed, values that are not finite with the
//! default parameters, non-positive masses, inertia tensors that are not
//! positive definite or whose principal moments violate the triangle
//! inequality, cut joints constraining nothing. Unknown names list close
//! matches (`unknown body "Bogie1.fram" in body2; close matches:
//! "Bogie1.frame"`).
//!
//! Subsystems add: unreadable subsystem files, include cycles (with the chain
//! of files, `include cycle: vehicle.ron -> bogie.ron -> vehicle.ron`),
//! overrides of parameters the subsystem does not have (naming the subsystem,
//! its file and the parameter, at the override), re-attaching a body on a
//! track-following frame, a connection point where a body is needed (a
//! joint's `parent`, a `WheelRail` wheelset), and values made invalid by an
//! instance's overrides (masses, inertias, the range checks of force elements,
//! values that are not finite; reported at the `Subsystem`). An error inside
//! an included file names that file, its line and column, and how it was
//! included:
//!
//! ```text
//! bogies/wheelset.ron:18:19: body "axle": unknown identifier "q" in mass ("m + q") (included as "Bogie1.WS1" from vehicles/vehicle.ron:18:9 via bogies/bogie.ron:17:9)
//! ```
//!
//! A file included several times is loaded once, and its errors are reported
//! once (with its first inclusion). When a subsystem cannot be loaded, the
//! including file is still checked, without errors about that instance's names.
//!
//! ### Wheel–rail contact
//!
//! A wheelset body on a track-following frame (`SixDof(..., track: Some(x))`)
//! gets its wheel–rail forces from one element (see
//! `models/vehicles/components/wheelset_s1002.ron`):
//!
//! ```text
//! WheelRail(name: "contact", wheelset: "ws",
//!           wheel_profile: "../../profiles/MBench_S1002_v3.prw",   // relative to the model file
//!           rail_profile: "../../profiles/MBench_UIC60_v3.ban",
//!           wheel_profile_right: None, rail_profile_right: None,   // default: mirrored left
//!           rail_profile_inclined: true,      // the file is drawn inclined (else the track's 1:40 is applied)
//!           radius: "r0", flange_back_distance: 1.360, taping_offset: 0.070,   // m
//!           mu: 0.4, young: 2.1e11, poisson: 0.28, normal_damping: 0,        // -, Pa, -, N s/m
//!           creep: FastsimA(strips: 20, sliding: Continuation),   // default
//!           // or FastsimA(strips: 20, sliding: Integrated(nodes: 8))   accurate at flange spin
//!           // or Fastsim(nx: 10, ny: 10) | Kalker
//!           // or Mueller(exponent: 2)   Pogorelov 2005, Sect. 4.2 (load-dependent slope, sliding flange)
//!           // or MuellerKalkerSaturated(exponent: 2)   Kalker's linear force saturated towards μN
//!           // or Polach(ka: 1.0, ks: 1.0, friction_decrease: (0.4, 0.6))   (A, B s/m), optional
//!           // (railmbs_wheelrail::creep::CreepLawSpec; its real settings may be expressions)
//!           contact: Hertz,                   // default: elliptic patches, forces by `creep`
//!           // or KikPiotrowski(penetration_reduction: 0.55, strip_width: 1e-4)   (–, m) non-elliptic
//!           //     patches, several per wheel, tangential forces by strips (then no `creep`)
//!           rail: Rigid,                      // or Elastic(ky: .., cy: .., kz: .., cz: ..)  N/m, N s/m
//!           // Elastic(.., lateral_damping: Always)   cy in every contact mode (default), or
//!           //     TwoPointContact: in two-point contact only (Pogorelov 2005, Sect. 4.2)
//!           wheels: None,                     // independently rotating wheels: Some(("WheelL", "WheelR"))
//!           table: (y_max: 0.025, dy: 1e-4, roll_max: 0.03, droll: 2e-3)),
//! ```
//!
//! ## Scenario files
//!
//! ```ron
//! Scenario(
//!     model: "../mechanisms/double_pendulum.ron",   // relative to this file
//!     macros: ["heavy"],                            // optional
//!     parameters: { "l1": 2.0, "k": "2*g" },        // optional overrides
//!     initial: [(coord: "q0", value: 0.3), (coord: "q1", velocity: 1.0)],   // optional
//!     end_time: 10.0,
//!     integrator: Park(rtol: 1e-6, atol: 1e-8, max_step: 0.01, initial_step: 1e-4,
//!                      jacobian: FiniteDifference),  // or Rk4(step: 0.001)
//!     output: (interval: 0.01, coordinates: true, velocities: false, bodies: [], forces: [],
//!              // optional: points (body frame, m) whose kinematic acceleration,
//!              // in the body's frame, is written as <name>.ax[m/s2], .ay, .az
//!              accelerometers: { "tip": ("link2", (0, -0.5, 0)) }),
//!     output_file: "double_pendulum.csv",           // optional, relative to this file
//! )
//! ```
//!
//! [`load_scenario`] checks the numbers; [`Scenario::parameter_values`] and
//! [`Scenario::initial_state`] check macro, parameter and coordinate names
//! against the model, with errors located in the scenario file.

mod error;
pub mod expr;
pub mod forces;
mod load;
mod locate;
mod methods;
pub mod model;
pub mod parser;
mod raw;
pub mod scenario;
mod visit;

pub use error::{ModelError, ModelErrors};

/// Building blocks of the model files' RON syntax for other file formats
/// (study descriptions): a number-or-expression value, a map in file order,
/// the source locator that gives errors found after parsing a line and
/// column, and RON's parse errors as located errors.
pub mod syntax {
    pub use crate::load::ron_error;
    pub use crate::locate::{Locator, Span};
    pub use crate::raw::{OrderedMap, Value};
}
pub use expr::{Expr, Func, VAR_NAMES};
pub use load::{load_model, parse_model};
pub use model::*;
pub use parser::{ParseError, ParseErrorKind, parse_expr, parse_expr_vars, parse_expr_with};
pub use scenario::*;
pub use scenario::{load_scenario, parse_scenario};

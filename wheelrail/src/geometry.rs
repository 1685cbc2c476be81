//! Contact geometry of a wheelset on a track (Pogorelov 2005, Sect. 4.1).
//!
//! # Frames and conventions
//!
//! - **Track frame**: `y` to the left, `z` up, origin on the track centre line at the level of
//!   the rail tops (the highest points of both rail heads, which are at the same height).
//! - **Wheelset frame**: origin at the axle centre, `y` along the axle to the left, `z`
//!   perpendicular to it, upwards; it is shifted by `(y, r_nom + z)` from the track frame and
//!   rolled by `φ` about the longitudinal axis (positive `φ` lifts the left wheel), `r_nom` being
//!   the mean nominal rolling radius.
//! - Profiles follow [`crate::profile`]: lateral coordinate `u` positive towards the field side,
//!   height up; a right wheel or rail is the mirror image of its profile.
//! - Wheel taping lines are at `±(flange_back_distance/2 + taping_line_offset)` in the wheelset
//!   frame; each rail is placed laterally so that the gauge, measured between the gauge faces
//!   `gauge_depth` below the rail tops, equals `gauge`. Rail inclination is a property of the rail
//!   profile (applied when it is prepared, see [`crate::profile::ProfileSettings`]).
//!
//! # Method
//!
//! Yaw being neglected in the search, every circular cross-section of a wheel has its lowest
//! point in the vertical plane through the axle, so the contact problem is planar: for each
//! wheel the vertical distance `d(u)` between the rolled wheel profile and the rail profile is
//! scanned on a grid and refined by golden-section search at every local minimum (the minimum
//! vertical distance, or "direct iteration", of the paper). The deepest minimum is the contact;
//! a second, separate minimum (separated by a hump, typically the flange contact while the tread
//! still touches) is kept when its gap is within [`SearchSettings::two_point_window`] of the
//! first: this is two-point contact. All gaps are for the wheelset height `z = 0`; at height `z`
//! the gap of every contact is `gap + z` exactly, so an elastic contact model gets its vertical
//! penetration as `−(gap + z)`.
//!
//! For a given lateral shift the rigid wheelset's roll and height follow from the condition that
//! both wheels touch (equal smallest gaps): [`ContactGeometry::rigid`]. The lateral shift at which
//! the contact of a wheel jumps from the tread to the flange is the critical shift `y*` of
//! two-point contact ([`ContactGeometry::two_point_shift`], the jump criterion); beyond it the
//! contact runs up the flange (flange climbing) and the same search continues.
//!
//! With a yaw angle `ψ`, the contact on a surface inclined by the contact angle `δ` moves
//! ahead of the axle plane by `x_c = r tan δ sin ψ ≈ k ψ` (minimising the vertical distance
//! between a yawed cone of slope `tan δ` and a plane of the same slope gives
//! `tan θ = tan δ sin ψ` for the angular position `θ` of the contact on the wheel circle);
//! [`Contact::yaw_lead`] stores `k` with the sign for its side, so `x_c = k ψ` (m) in the
//! wheelset's longitudinal direction. This "overswing" matters on the flange (δ ≈ 70°).

use crate::profile::{Profile, ProfileKind};

/// Errors of the contact geometry.
#[derive(Debug, thiserror::Error)]
pub enum GeometryError {
    /// An invalid input value.
    #[error("invalid {what}: {message}")]
    Invalid {
        /// Which input.
        what: &'static str,
        /// What is wrong.
        message: String,
    },
    /// No contact found (profiles do not overlap laterally).
    #[error(
        "no contact between {side} wheel and rail at lateral shift {y:.6} m, roll {roll:.6} rad: profiles do not overlap"
    )]
    NoContact {
        /// "left" or "right".
        side: &'static str,
        /// Lateral shift (m).
        y: f64,
        /// Roll (rad).
        roll: f64,
    },
    /// Lookup outside the table.
    #[error("{what} = {value} outside the contact table range [{min}, {max}]")]
    OutOfRange {
        /// "lateral shift" or "roll".
        what: &'static str,
        /// Requested value.
        value: f64,
        /// Table minimum.
        min: f64,
        /// Table maximum.
        max: f64,
    },
    /// The rigid roll iteration did not converge.
    #[error("rigid wheelset roll did not converge at lateral shift {y} m")]
    NoConvergence {
        /// Lateral shift (m).
        y: f64,
    },
}

fn invalid(what: &'static str, message: impl Into<String>) -> GeometryError {
    GeometryError::Invalid {
        what,
        message: message.into(),
    }
}

fn check_positive(what: &'static str, v: f64) -> Result<(), GeometryError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(invalid(
            what,
            format!("must be finite and positive, got {v}"),
        ))
    }
}

/// A wheelset: two wheel profiles on an axle.
#[derive(Debug, Clone)]
pub struct Wheelset {
    /// Left wheel profile (library convention, see [`crate::profile`]).
    pub wheel_left: Profile,
    /// Right wheel profile (same convention: mirrored when placed).
    pub wheel_right: Profile,
    /// Nominal rolling radius of the left wheel at its taping line (m), e.g. 0.46.
    pub radius_left: f64,
    /// Nominal rolling radius of the right wheel (m).
    pub radius_right: f64,
    /// Distance between the flange backs (back-to-back) (m), e.g. 1.360.
    pub flange_back_distance: f64,
    /// Distance from a wheel's flange back to its taping line (m), 0.070 for S1002 and EN 15302.
    pub taping_line_offset: f64,
}

impl Wheelset {
    /// A wheelset with equal radius `radius` (m), back-to-back `flange_back_distance` (m) and the
    /// taping line 70 mm from the flange back.
    pub fn new(
        wheel_left: Profile,
        wheel_right: Profile,
        radius: f64,
        flange_back_distance: f64,
    ) -> Wheelset {
        Wheelset {
            wheel_left,
            wheel_right,
            radius_left: radius,
            radius_right: radius,
            flange_back_distance,
            taping_line_offset: 0.070,
        }
    }

    /// Half the distance between the taping lines (m).
    pub fn taping_half_distance(&self) -> f64 {
        0.5 * self.flange_back_distance + self.taping_line_offset
    }

    fn validate(&self) -> Result<(), GeometryError> {
        check_positive("left wheel radius", self.radius_left)?;
        check_positive("right wheel radius", self.radius_right)?;
        check_positive("flange back distance", self.flange_back_distance)?;
        if !(self.taping_line_offset.is_finite() && self.taping_line_offset >= 0.0) {
            return Err(invalid(
                "taping line offset",
                format!("must be finite and ≥ 0, got {}", self.taping_line_offset),
            ));
        }
        for (w, side) in [(&self.wheel_left, "left"), (&self.wheel_right, "right")] {
            if w.kind() != ProfileKind::Wheel {
                return Err(invalid(
                    "wheel profile",
                    format!("{side} wheel profile `{}` is a rail profile", w.name()),
                ));
            }
        }
        Ok(())
    }
}

/// A straight track: two rail profiles at a gauge.
#[derive(Debug, Clone)]
pub struct Track {
    /// Left rail profile (library convention; inclination already applied).
    pub rail_left: Profile,
    /// Right rail profile (same convention: mirrored when placed).
    pub rail_right: Profile,
    /// Track gauge (m), e.g. 1.435.
    pub gauge: f64,
    /// Depth below the rail top at which the gauge is measured (m), 0.014 by EN 13848-1.
    pub gauge_depth: f64,
}

impl Track {
    /// A track with the gauge measured 14 mm below the rail tops.
    pub fn new(rail_left: Profile, rail_right: Profile, gauge: f64) -> Track {
        Track {
            rail_left,
            rail_right,
            gauge,
            gauge_depth: 0.014,
        }
    }

    fn validate(&self) -> Result<(), GeometryError> {
        check_positive("gauge", self.gauge)?;
        check_positive("gauge depth", self.gauge_depth)?;
        for (r, side) in [(&self.rail_left, "left"), (&self.rail_right, "right")] {
            if r.kind() != ProfileKind::Rail {
                return Err(invalid(
                    "rail profile",
                    format!("{side} rail profile `{}` is a wheel profile", r.name()),
                ));
            }
        }
        Ok(())
    }
}

/// Settings of the contact search.
#[derive(Debug, Clone, Copy)]
pub struct SearchSettings {
    /// Grid step (m) of the scan along the wheel profile before refinement.
    pub scan_step: f64,
    /// A second local minimum counts as a second contact when its gap exceeds the smallest
    /// gap by less than this (m). It should exceed the largest elastic penetration expected.
    pub two_point_window: f64,
    /// Minimum hump (m) of the distance function between two minima for them to be distinct
    /// contacts (filters ripples of nearly conformal profiles).
    pub min_hump: f64,
}

impl Default for SearchSettings {
    fn default() -> Self {
        SearchSettings {
            scan_step: 0.25e-3,
            two_point_window: 1.0e-3,
            min_hump: 1e-6,
        }
    }
}

/// One contact point of a wheel with its rail.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Contact {
    /// Vertical gap (m) between wheel and rail at the contact for wheelset height `z = 0`
    /// (negative: virtual penetration). At height `z` the gap is `gap + z`.
    pub gap: f64,
    /// Contact point on the wheel profile, profile coordinate `u` (m).
    pub wheel_u: f64,
    /// Contact point on the rail profile, profile coordinate `u` (m).
    pub rail_u: f64,
    /// Contact point on the wheel in the wheelset frame: lateral `y` (m, left positive).
    pub wheel_y: f64,
    /// Contact point on the wheel in the wheelset frame: vertical `z` (m, from the axle centre).
    pub wheel_z: f64,
    /// Contact point on the rail in the track frame: lateral `y` (m).
    pub rail_y: f64,
    /// Contact point on the rail in the track frame: vertical `z` (m).
    pub rail_z: f64,
    /// Contact angle `δ` (rad): inclination of the common tangent to the track's lateral axis,
    /// positive when the normal force on the wheel points towards the track centre (flange
    /// contact: large positive), on both sides.
    pub contact_angle: f64,
    /// Rolling radius at the contact (m).
    pub rolling_radius: f64,
    /// Wheel curvature in the rolling direction (1/m): `cos γ_w / r`, `γ_w` the angle between
    /// the wheel profile's normal and the wheel's radial direction (Meusnier; `1/r` on a flat tread).
    pub wheel_longitudinal_curvature: f64,
    /// Wheel profile curvature across the rolling direction (1/m), positive when convex.
    pub wheel_transverse_curvature: f64,
    /// Rail profile curvature (1/m), positive when convex (a crowned head).
    pub rail_transverse_curvature: f64,
    /// Longitudinal lead per unit yaw (m/rad): the contact lies at `x_c = yaw_lead · ψ` ahead
    /// of the axle plane in the wheelset frame (small `ψ`).
    pub yaw_lead: f64,
    /// Slope `dd/du` of the vertical distance along the wheel profile at this point (–): zero at
    /// a true contact (a minimum of the distance), nonzero where a region's deepest point lies
    /// on the region's boundary with the surface still falling into the next region
    /// ([`ContactGeometry::region_contacts`]).
    pub distance_slope: f64,
}

impl Contact {
    /// Names of the fields, in the order of [`Contact::values`].
    pub const FIELDS: [&'static str; 14] = [
        "gap",
        "wheel_u",
        "rail_u",
        "wheel_y",
        "wheel_z",
        "rail_y",
        "rail_z",
        "contact_angle",
        "rolling_radius",
        "wheel_longitudinal_curvature",
        "wheel_transverse_curvature",
        "rail_transverse_curvature",
        "yaw_lead",
        "distance_slope",
    ];

    /// The fields in the order of [`Contact::FIELDS`]: gap, wheel_u, rail_u,
    /// wheel_y, wheel_z, rail_y, rail_z (m), contact angle (rad), rolling
    /// radius (m), the three curvatures (1/m), yaw lead (m/rad), distance
    /// slope (–).
    pub fn values(&self) -> [f64; 14] {
        [
            self.gap,
            self.wheel_u,
            self.rail_u,
            self.wheel_y,
            self.wheel_z,
            self.rail_y,
            self.rail_z,
            self.contact_angle,
            self.rolling_radius,
            self.wheel_longitudinal_curvature,
            self.wheel_transverse_curvature,
            self.rail_transverse_curvature,
            self.yaw_lead,
            self.distance_slope,
        ]
    }

    /// The contact of [`Contact::values`]' array `a`.
    pub fn from_values(a: [f64; 14]) -> Contact {
        Contact {
            gap: a[0],
            wheel_u: a[1],
            rail_u: a[2],
            wheel_y: a[3],
            wheel_z: a[4],
            rail_y: a[5],
            rail_z: a[6],
            contact_angle: a[7],
            rolling_radius: a[8],
            wheel_longitudinal_curvature: a[9],
            wheel_transverse_curvature: a[10],
            rail_transverse_curvature: a[11],
            yaw_lead: a[12],
            distance_slope: a[13],
        }
    }

    /// Longitudinal position (m) of the contact in the wheelset frame for yaw `psi` (rad).
    pub fn longitudinal_offset(&self, psi: f64) -> f64 {
        self.yaw_lead * psi
    }
}

/// One sample of the undeformed gap between a wheel and its rail
/// ([`ContactGeometry::gap_samples`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GapSample {
    /// Wheel profile coordinate `u` (m).
    pub wheel_u: f64,
    /// Lateral position of the rail point below it in the track frame (m, left positive).
    pub rail_y: f64,
    /// Height of that rail point (m, rail profile convention, as [`Contact::rail_z`]).
    pub rail_z: f64,
    /// Vertical gap (m) at wheelset height `z = 0` (negative: interpenetration).
    pub gap: f64,
    /// Rolling radius of the wheel at this point (m).
    pub rolling_radius: f64,
    /// Inclination of the rail surface there (rad), the contact angle of a
    /// contact at this point, same sign convention as [`Contact::contact_angle`].
    pub contact_angle: f64,
}

/// The contacts of one wheel: one, or two in two-point contact (ordered from the field side
/// to the flange, i.e. the tread contact first).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactSet {
    /// Number of contacts (1 or 2).
    pub count: usize,
    /// The contacts; only the first `count` are meaningful.
    pub contacts: [Contact; 2],
}

impl ContactSet {
    /// The contacts as a slice.
    pub fn as_slice(&self) -> &[Contact] {
        &self.contacts[..self.count]
    }

    /// The contact with the smallest gap.
    pub fn deepest(&self) -> &Contact {
        let s = self.as_slice();
        if s.len() == 2 && s[1].gap < s[0].gap {
            &s[1]
        } else {
            &s[0]
        }
    }
}

/// Placement of one side (wheel and rail), in side-local coordinates: lateral outwards.
#[derive(Debug, Clone)]
struct Side {
    wheel: Profile,
    rail: Profile,
    /// Lateral position of the taping line from the wheelset centre (m, outward).
    taping: f64,
    /// Nominal radius of this wheel (m).
    radius: f64,
    /// Lateral position of the rail profile origin from the track centre (m, outward).
    rail_origin: f64,
    /// Scan grid on the wheel profile: (u, h).
    samples: Vec<(f64, f64)>,
    /// +1 left, −1 right.
    sign: f64,
}

/// Stride (in samples) of the coarse pass of
/// [`ContactGeometry::gap_samples_below`].
pub const GAP_SCAN_STRIDE: usize = 4;

/// Margin (m) above the largest gap with which a coarse point of
/// [`ContactGeometry::gap_samples_below`] counts as near a patch.
pub const GAP_SCAN_MARGIN: f64 = 1.25e-5;

/// The grid of the gap samples of one wheel at one position.
struct SampleGrid {
    k: usize,
    /// Side-local lateral shift (m), sine and cosine of the side-local roll.
    ys: f64,
    ss: f64,
    cs: f64,
    /// Wheel coordinate range (m), step (m) and last index.
    u0: f64,
    u1: f64,
    step: f64,
    n: usize,
}

/// Prepared contact geometry of a wheelset on a track.
#[derive(Debug, Clone)]
pub struct ContactGeometry {
    sides: [Side; 2],
    nominal_radius: f64,
    settings: SearchSettings,
}

/// Rigid wheelset position where both wheels touch their rails.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidContact {
    /// Lateral shift (m).
    pub y: f64,
    /// Roll (rad).
    pub roll: f64,
    /// Height of the axle above its nominal height (m).
    pub z: f64,
    /// Contacts of the left and right wheel at this position (gaps are for `z = 0`).
    pub sides: [ContactSet; 2],
}

impl RigidContact {
    /// Rolling radius difference `r_left − r_right` (m) at the deepest contacts.
    pub fn rolling_radius_difference(&self) -> f64 {
        self.sides[0].deepest().rolling_radius - self.sides[1].deepest().rolling_radius
    }
}

const INV_PHI: f64 = 0.618_033_988_749_894_9;

impl ContactGeometry {
    /// Prepares the geometry: validates the inputs and places the rails by the gauge.
    pub fn new(
        wheelset: &Wheelset,
        track: &Track,
        settings: SearchSettings,
    ) -> Result<ContactGeometry, GeometryError> {
        wheelset.validate()?;
        track.validate()?;
        check_positive("scan step", settings.scan_step)?;
        check_positive("two-point window", settings.two_point_window)?;
        if !(settings.min_hump.is_finite() && settings.min_hump >= 0.0) {
            return Err(invalid("minimum hump", "must be finite and ≥ 0"));
        }
        let taping = wheelset.taping_half_distance();
        let mk = |wheel: &Profile, rail: &Profile, radius: f64, sign: f64, name: &'static str| {
            let ug = rail.gauge_point(track.gauge_depth).ok_or_else(|| {
                invalid(
                    "rail profile",
                    format!(
                        "{name} rail `{}` has no gauge face {} mm below its top",
                        rail.name(),
                        track.gauge_depth * 1e3
                    ),
                )
            })?;
            let (u0, u1) = wheel.range();
            let n = ((u1 - u0) / settings.scan_step).ceil() as usize;
            let samples = (0..=n)
                .map(|k| {
                    let u = (u0 + k as f64 * (u1 - u0) / n as f64).min(u1);
                    let v = wheel.eval(u).expect("inside range");
                    (u, v.h)
                })
                .collect();
            Ok::<Side, GeometryError>(Side {
                wheel: wheel.clone(),
                rail: rail.clone(),
                taping,
                radius,
                rail_origin: 0.5 * track.gauge - ug,
                samples,
                sign,
            })
        };
        let left = mk(
            &wheelset.wheel_left,
            &track.rail_left,
            wheelset.radius_left,
            1.0,
            "left",
        )?;
        let right = mk(
            &wheelset.wheel_right,
            &track.rail_right,
            wheelset.radius_right,
            -1.0,
            "right",
        )?;
        Ok(ContactGeometry {
            sides: [left, right],
            nominal_radius: 0.5 * (wheelset.radius_left + wheelset.radius_right),
            settings,
        })
    }

    /// Mean nominal rolling radius (m).
    pub fn nominal_radius(&self) -> f64 {
        self.nominal_radius
    }

    /// Lateral position (m, from the track centre, outward) of the left and right rail's
    /// profile origin (its top).
    pub fn rail_positions(&self) -> [f64; 2] {
        [self.sides[0].rail_origin, self.sides[1].rail_origin]
    }

    /// Contacts of both wheels for lateral shift `y` (m) and roll `roll` (rad), wheelset height
    /// `z = 0` (the direct minimum-distance search).
    pub fn contacts(&self, y: f64, roll: f64) -> Result<[ContactSet; 2], GeometryError> {
        if !(y.is_finite() && roll.is_finite()) {
            return Err(invalid(
                "wheelset position",
                format!("lateral shift {y} and roll {roll} must be finite"),
            ));
        }
        Ok([
            self.side_contacts(0, y, roll)?,
            self.side_contacts(1, y, roll)?,
        ])
    }

    /// Vertical distance at wheel coordinate `u` (height `h`) for side-local shift `ys` and roll
    /// with cosine `cs`, sine `ss`, and the rail coordinate below the wheel point; `None` where
    /// the rail does not exist there. `seg` is a segment hint for the rail lookup.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn distance(
        &self,
        s: &Side,
        ys: f64,
        cs: f64,
        ss: f64,
        u: f64,
        h: f64,
        seg: &mut usize,
    ) -> Option<(f64, f64)> {
        let xi = s.taping + u;
        let zeta = -s.radius + h;
        let yy = ys + cs * xi - ss * zeta;
        let zz = self.nominal_radius + ss * xi + cs * zeta;
        let v = yy - s.rail_origin;
        let hr = s.rail.height_hinted(v, seg)?;
        Some((zz - hr, v))
    }

    #[allow(clippy::needless_range_loop)] // scans over neighbouring samples
    fn side_contacts(&self, k: usize, y: f64, roll: f64) -> Result<ContactSet, GeometryError> {
        let s = &self.sides[k];
        let ys = s.sign * y;
        let ps = s.sign * roll;
        let (ss, cs) = ps.sin_cos();
        let n = s.samples.len();
        let mut d = vec![f64::INFINITY; n];
        let mut seg = 0;
        let mut best = usize::MAX;
        for (i, &(u, h)) in s.samples.iter().enumerate() {
            if let Some((dist, _)) = self.distance(s, ys, cs, ss, u, h, &mut seg) {
                d[i] = dist;
                if best == usize::MAX || dist < d[best] {
                    best = i;
                }
            }
        }
        if best == usize::MAX {
            return Err(GeometryError::NoContact {
                side: if k == 0 { "left" } else { "right" },
                y,
                roll,
            });
        }
        // Nearly conformal profiles make the distance flat with ripples: refine every sampled
        // local minimum within `min_hump` of the deepest sample and keep the deepest result.
        let is_local_min = |i: usize| {
            let l = if i > 0 { d[i - 1] } else { f64::INFINITY };
            let r = if i + 1 < n { d[i + 1] } else { f64::INFINITY };
            d[i].is_finite() && d[i] <= l && d[i] <= r
        };
        let bracket = |i: usize| {
            (
                s.samples[i.saturating_sub(1)].0,
                s.samples[(i + 1).min(n - 1)].0,
            )
        };
        let mut best_refined = {
            let (a, b) = bracket(best);
            self.refine(s, ys, cs, ss, a, b)
        };
        let d_best_sample = d[best];
        for i in 0..n {
            if i != best && d[i] - d_best_sample < self.settings.min_hump && is_local_min(i) {
                let (a, b) = bracket(i);
                let r = self.refine(s, ys, cs, ss, a, b);
                if r.1 < best_refined.1 {
                    best_refined = r;
                    best = i;
                }
            }
        }
        // Second contact candidate: the deepest other sampled local minimum within the window
        // that is separated from the deepest one by a hump of at least `min_hump`.
        let window = self.settings.two_point_window;
        let mut second: Option<usize> = None;
        let mut hump = f64::NEG_INFINITY;
        // sweep right of best, tracking the running maximum between best and i
        for i in best + 1..n {
            if !d[i].is_finite() {
                break;
            }
            hump = hump.max(d[i]);
            let l = d[i - 1];
            let r = if i + 1 < n { d[i + 1] } else { f64::INFINITY };
            if d[i] <= l
                && d[i] < r
                && d[i] - d[best] < window
                && hump - d[i] >= self.settings.min_hump
                && second.is_none_or(|q| d[i] < d[q])
            {
                second = Some(i);
            }
        }
        hump = f64::NEG_INFINITY;
        for i in (0..best).rev() {
            if !d[i].is_finite() {
                break;
            }
            hump = hump.max(d[i]);
            let l = if i > 0 { d[i - 1] } else { f64::INFINITY };
            let r = d[i + 1];
            if d[i] < l
                && d[i] <= r
                && d[i] - d[best] < window
                && hump - d[i] >= self.settings.min_hump
                && second.is_none_or(|q| d[i] < d[q])
            {
                second = Some(i);
            }
        }
        let mut found: [(f64, f64); 2] = [best_refined, (0.0, 0.0)];
        let mut count = 1;
        if let Some(i) = second {
            let (a, b) = bracket(i);
            found[1] = self.refine(s, ys, cs, ss, a, b);
            count = 2;
        }
        if count == 2 && found[1].0 > found[0].0 {
            found.swap(0, 1); // field side (larger u) first
        }
        let mut set = ContactSet {
            count,
            ..Default::default()
        };
        for slot in 0..count {
            set.contacts[slot] = self.contact_at(k, ys, cs, ss, found[slot].0, (y, roll))?;
        }
        Ok(set)
    }

    /// The deepest point of each of two fixed regions of wheel `k`'s profile,
    /// `u ≥ split` (slot 0, the tread side) and `u < split` (slot 1, the
    /// flange side), for lateral shift `y` and roll `roll` (wheelset height
    /// z = 0). Unlike [`ContactGeometry::contacts`], whose contact points jump
    /// where a local minimum of the distance disappears (S1002 on UIC60 at
    /// the flange root), each slot's gap is a continuous function of y and
    /// roll (the minimum of a continuous function over a fixed domain), so
    /// tables of it interpolate without jumps. A slot's minimum may sit on
    /// the region's boundary; an empty region gets gap 1 m (never in
    /// contact) and the other slot's geometry.
    pub fn region_contacts(
        &self,
        k: usize,
        y: f64,
        roll: f64,
        split: f64,
    ) -> Result<[Contact; 2], GeometryError> {
        let s = &self.sides[k];
        let ys = s.sign * y;
        let (ss, cs) = (s.sign * roll).sin_cos();
        let mut seg = 0;
        let mut best = [usize::MAX; 2];
        let mut best_d = [f64::INFINITY; 2];
        for (i, &(u, h)) in s.samples.iter().enumerate() {
            if let Some((dist, _)) = self.distance(s, ys, cs, ss, u, h, &mut seg) {
                let r = usize::from(u < split);
                if dist < best_d[r] {
                    best_d[r] = dist;
                    best[r] = i;
                }
            }
        }
        let n = s.samples.len();
        let mut found = [None, None];
        for r in 0..2 {
            let i = best[r];
            if i == usize::MAX {
                continue;
            }
            let mut a = s.samples[i.saturating_sub(1)].0;
            let mut b = s.samples[(i + 1).min(n - 1)].0;
            if r == 0 {
                a = a.max(split);
            } else {
                b = b.min(split);
            }
            let (u, _) = self.refine(s, ys, cs, ss, a, b);
            found[r] = Some(self.contact_at(k, ys, cs, ss, u, (y, roll))?);
        }
        match found {
            [Some(a), Some(b)] => Ok([a, b]),
            [Some(a), None] => Ok([a, Contact { gap: 1.0, ..a }]),
            [None, Some(b)] => Ok([Contact { gap: 1.0, ..b }, b]),
            [None, None] => Err(GeometryError::NoContact {
                side: if k == 0 { "left" } else { "right" },
                y,
                roll,
            }),
        }
    }

    /// The vertical distance between wheel `k` (0 left, 1 right) and its rail
    /// sampled along the whole wheel profile every `step` (m) of the wheel
    /// coordinate `u`, for lateral shift `y` (m) and roll `roll` (rad),
    /// wheelset height `z = 0`: the undeformed gap function that non-elliptic
    /// contact models ([`crate::kik_piotrowski`]) cut into strips. Samples
    /// where the rail does not exist below the wheel are left out; they are
    /// ordered by the wheel coordinate, from the flange to the field side.
    pub fn gap_samples(
        &self,
        k: usize,
        y: f64,
        roll: f64,
        step: f64,
    ) -> Result<Vec<GapSample>, GeometryError> {
        let grid = self.sample_grid(k, y, roll, step)?;
        let mut hint = (0, 0);
        let out: Vec<GapSample> = (0..=grid.n)
            .filter_map(|i| self.gap_sample(&grid, i, &mut hint))
            .collect();
        if out.is_empty() {
            return Err(GeometryError::NoContact {
                side: if k == 0 { "left" } else { "right" },
                y,
                roll,
            });
        }
        Ok(out)
    }

    /// The samples of [`ContactGeometry::gap_samples`] (the same grid, the
    /// same values) where the wheel may touch: every sample with a gap below
    /// `max_gap` (m; e.g. the wheel's vertical approach `δ_z`, for which
    /// these are the interpenetrating samples) together with the samples
    /// between it and the nearest samples on either side whose gap is at
    /// least `max_gap` (included, so that every run of interpenetration is
    /// whole and bounded), in the order of the wheel coordinate; empty where
    /// nothing comes that close. For a contact model that needs only the
    /// patches (each a few mm of a 140 mm profile) this takes about half the
    /// time of the whole profile (the coarse pass is most of it).
    ///
    /// A first pass samples every [`GAP_SCAN_STRIDE`]th point of the grid
    /// and keeps the cells next to those whose gap is below
    /// `max_gap + GAP_SCAN_MARGIN`; the finer samples are taken only there.
    /// So a run of samples below `max_gap` is found unless it lies wholly
    /// between two coarse points whose gaps exceed it by the margin, which
    /// needs the gap's second derivative along the profile to exceed
    /// `2·margin/(stride·step/2)²` (625 1/m at the 0.1 mm step: a relative
    /// radius of curvature of the profiles below 1.6 mm; a wheel flange and
    /// rail gauge corner have 10 mm and more).
    pub fn gap_samples_below(
        &self,
        k: usize,
        y: f64,
        roll: f64,
        step: f64,
        max_gap: f64,
    ) -> Result<Vec<GapSample>, GeometryError> {
        if !max_gap.is_finite() {
            return Err(invalid(
                "largest gap",
                format!("must be finite, got {max_gap}"),
            ));
        }
        let grid = self.sample_grid(k, y, roll, step)?;
        let mut hint = (0, 0);
        let stride = GAP_SCAN_STRIDE;
        // Coarse points (every stride-th grid index, and the last one) that
        // may lie in or next to a patch.
        let coarse: Vec<usize> = (0..=grid.n)
            .step_by(stride)
            .chain((grid.n % stride != 0).then_some(grid.n))
            .collect();
        let near: Vec<bool> = coarse
            .iter()
            .map(|&i| {
                self.gap_sample(&grid, i, &mut hint)
                    .is_some_and(|s| s.gap < max_gap + GAP_SCAN_MARGIN)
            })
            .collect();
        let mut out = Vec::new();
        let mut hint = (0, 0);
        let mut next = 0; // first grid index not yet sampled
        for (c, &is_near) in near.iter().enumerate() {
            if !is_near {
                continue;
            }
            // The cells on either side of a near coarse point, from the
            // coarse point before it to the one after it (both included).
            let lo = coarse[c.saturating_sub(1)].max(next);
            let hi = coarse[(c + 1).min(coarse.len() - 1)];
            for i in lo..=hi {
                if let Some(s) = self.gap_sample(&grid, i, &mut hint) {
                    out.push(s);
                }
            }
            next = hi + 1;
        }
        Ok(out)
    }

    /// The sampling grid of wheel `k` for [`ContactGeometry::gap_samples`].
    fn sample_grid(
        &self,
        k: usize,
        y: f64,
        roll: f64,
        step: f64,
    ) -> Result<SampleGrid, GeometryError> {
        if k > 1 {
            return Err(invalid("wheel index", format!("must be 0 or 1, got {k}")));
        }
        check_positive("gap sampling step", step)?;
        if !(y.is_finite() && roll.is_finite()) {
            return Err(invalid(
                "wheelset position",
                format!("lateral shift {y} and roll {roll} must be finite"),
            ));
        }
        let s = &self.sides[k];
        let (u0, u1) = s.wheel.range();
        let n = ((u1 - u0) / step).ceil() as usize;
        if n > 10_000_000 {
            return Err(invalid(
                "gap sampling step",
                format!("{step} m gives more than 10^7 samples"),
            ));
        }
        let (ss, cs) = (s.sign * roll).sin_cos();
        Ok(SampleGrid {
            k,
            ys: s.sign * y,
            ss,
            cs,
            u0,
            u1,
            step,
            n,
        })
    }

    /// Sample `i` of `grid` (`None` where the rail does not exist below the
    /// wheel); `hint` holds the wheel's and rail's segment hints.
    #[inline]
    fn gap_sample(
        &self,
        grid: &SampleGrid,
        i: usize,
        hint: &mut (usize, usize),
    ) -> Option<GapSample> {
        let s = &self.sides[grid.k];
        let u = (grid.u0 + i as f64 * grid.step).min(grid.u1);
        let h = s.wheel.height_hinted(u, &mut hint.0)?;
        let (gap, v) = self.distance(s, grid.ys, grid.cs, grid.ss, u, h, &mut hint.1)?;
        let r = s.rail.eval(v)?;
        Some(GapSample {
            wheel_u: u,
            rail_y: s.sign * (s.rail_origin + v),
            rail_z: r.h,
            gap,
            rolling_radius: s.radius - h,
            contact_angle: r.slope.atan(),
        })
    }

    /// Golden-section refinement of a minimum of the vertical distance in `[a, b]`.
    fn refine(&self, s: &Side, ys: f64, cs: f64, ss: f64, a: f64, b: f64) -> (f64, f64) {
        let mut wseg = 0;
        let mut rseg = 0;
        let mut f = |u: f64| -> f64 {
            s.wheel
                .height_hinted(u, &mut wseg)
                .and_then(|h| self.distance(s, ys, cs, ss, u, h, &mut rseg))
                .map_or(f64::INFINITY, |x| x.0)
        };
        let (mut a, mut b) = (a, b);
        let mut x1 = b - INV_PHI * (b - a);
        let mut x2 = a + INV_PHI * (b - a);
        let mut f1 = f(x1);
        let mut f2 = f(x2);
        while b - a > 1e-10 {
            if f1 < f2 {
                b = x2;
                x2 = x1;
                f2 = f1;
                x1 = b - INV_PHI * (b - a);
                f1 = f(x1);
            } else {
                a = x1;
                x1 = x2;
                f1 = f2;
                x2 = a + INV_PHI * (b - a);
                f2 = f(x2);
            }
        }
        let u = 0.5 * (a + b);
        let fu = f(u);
        if fu.is_finite() { (u, fu) } else { (x1, f1) }
    }

    /// The contact of wheel `k` at wheel coordinate `u` (a refined minimum
    /// of the distance); `NoContact` at (y, roll) = `at` where the rail does
    /// not exist below it (profiles that barely overlap, or a wheel profile
    /// given as the rail).
    #[allow(clippy::too_many_arguments)]
    fn contact_at(
        &self,
        k: usize,
        ys: f64,
        cs: f64,
        ss: f64,
        u: f64,
        at: (f64, f64),
    ) -> Result<Contact, GeometryError> {
        let s = &self.sides[k];
        let no_contact = || GeometryError::NoContact {
            side: if k == 0 { "left" } else { "right" },
            y: at.0,
            roll: at.1,
        };
        let w = s.wheel.eval(u).ok_or_else(no_contact)?;
        let (gap, v) = self
            .distance(s, ys, cs, ss, u, w.h, &mut 0)
            .ok_or_else(no_contact)?;
        let r = s.rail.eval(v).ok_or_else(no_contact)?;
        let delta = r.slope.atan();
        let radius = s.radius - w.h;
        let gamma_w = w.slope.atan();
        Ok(Contact {
            gap,
            wheel_u: u,
            rail_u: v,
            wheel_y: s.sign * (s.taping + u),
            wheel_z: -s.radius + w.h,
            rail_y: s.sign * (s.rail_origin + v),
            rail_z: r.h,
            contact_angle: delta,
            rolling_radius: radius,
            wheel_longitudinal_curvature: gamma_w.cos() / radius,
            wheel_transverse_curvature: -w.curvature(),
            rail_transverse_curvature: -r.curvature(),
            yaw_lead: s.sign * radius * delta.tan(),
            // d = zz − h_r(v): dd/du = (sin φ + cos φ h_w') − h_r'(v)(cos φ − sin φ h_w').
            distance_slope: (ss + cs * w.slope) - r.slope * (cs - ss * w.slope),
        })
    }

    /// Rigid wheelset at lateral shift `y` (m): the roll and height at which both wheels touch
    /// their rails (equal smallest gaps), found by a safeguarded secant iteration on the roll.
    pub fn rigid(&self, y: f64) -> Result<RigidContact, GeometryError> {
        self.rigid_from(y, 0.0)
    }

    fn rigid_from(&self, y: f64, roll_guess: f64) -> Result<RigidContact, GeometryError> {
        let f = |roll: f64| -> Result<(f64, [ContactSet; 2]), GeometryError> {
            let c = self.contacts(y, roll)?;
            Ok((c[0].deepest().gap - c[1].deepest().gap, c))
        };
        // d(gap_L − gap_R)/dφ ≈ distance between the contacts ≈ 2 × taping half distance
        let slope0 = 2.0 * self.sides[0].taping;
        let mut x0 = roll_guess;
        let (mut f0, mut c0) = f(x0)?;
        let mut x1 = x0 - f0 / slope0;
        let (mut f1, mut c1) = f(x1)?;
        for _ in 0..60 {
            if f1.abs() < 1e-12 {
                break;
            }
            let denom = f1 - f0;
            let step = if denom.abs() > 1e-300 {
                -f1 * (x1 - x0) / denom
            } else {
                -f1 / slope0
            };
            // guard against wild secant steps across a kink of the gap function
            let step = if (step * slope0 / f1).abs() > 10.0 || !step.is_finite() {
                -f1 / slope0
            } else {
                step
            };
            x0 = x1;
            f0 = f1;
            c0 = c1;
            x1 += step;
            (f1, c1) = f(x1)?;
        }
        let _ = c0;
        if f1.abs() > 1e-9 {
            return Err(GeometryError::NoConvergence { y });
        }
        let z = -0.5 * (c1[0].deepest().gap + c1[1].deepest().gap);
        Ok(RigidContact {
            y,
            roll: x1,
            z,
            sides: c1,
        })
    }

    /// Rigid contact geometry functions over the lateral shifts `ys` (m): roll, height,
    /// contacts and hence `Δr(y)`, contact angles, rolling radii.
    pub fn rigid_functions(&self, ys: &[f64]) -> Result<Vec<RigidContact>, GeometryError> {
        let mut out = Vec::with_capacity(ys.len());
        let mut guess = 0.0;
        for &y in ys {
            let r = self.rigid_from(y, guess)?;
            guess = r.roll;
            out.push(r);
        }
        Ok(out)
    }

    /// Critical lateral shift `y*` (m) of two-point contact of the left wheel for shifts towards
    /// the left (use a negative `y_max` for the right wheel): the shift at which the rigid
    /// wheelset's left contact jumps from the tread to the flange (jump criterion: the contact
    /// point moves by more than `jump` (m) on the wheel within one step `dy`, onto a surface
    /// inclined more than `min_flange_angle` (rad), which tells a flange contact from the jumps
    /// of nearly conformal treads), refined by bisection to the shift where both minima have
    /// equal gaps. Returns `None` if no such jump occurs within `y_max`.
    pub fn two_point_shift(
        &self,
        y_max: f64,
        dy: f64,
        jump: f64,
        min_flange_angle: f64,
    ) -> Result<Option<TwoPointContact>, GeometryError> {
        check_positive("step", dy)?;
        check_positive("jump threshold", jump)?;
        if !y_max.is_finite() || y_max == 0.0 {
            return Err(invalid("maximum shift", "must be finite and non-zero"));
        }
        let dir = y_max.signum();
        let side = if dir > 0.0 { 0 } else { 1 };
        let n = (y_max.abs() / dy).ceil() as usize;
        let mut prev = self.rigid(0.0)?;
        for k in 1..=n {
            let y = dir * (k as f64 * dy).min(y_max.abs());
            let cur = self.rigid_from(y, prev.roll)?;
            let (u0, u1) = (
                prev.sides[side].deepest().wheel_u,
                cur.sides[side].deepest().wheel_u,
            );
            if (u1 - u0).abs() > jump
                && u1 < u0
                && cur.sides[side].deepest().contact_angle > min_flange_angle
            {
                let umid = 0.5 * (u0 + u1);
                let on_flange = |r: &RigidContact| r.sides[side].deepest().wheel_u < umid;
                let (mut a, mut b) = (prev, cur);
                for _ in 0..40 {
                    let m = self.rigid_from(0.5 * (a.y + b.y), a.roll)?;
                    if on_flange(&m) {
                        b = m;
                    } else {
                        a = m;
                    }
                }
                let flange = b.sides[side].deepest();
                let tread = a.sides[side].deepest();
                return Ok(Some(TwoPointContact {
                    y_star: 0.5 * (a.y + b.y),
                    tread: *tread,
                    flange: *flange,
                }));
            }
            prev = cur;
        }
        Ok(None)
    }
}

/// Two-point contact at the critical shift.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoPointContact {
    /// Critical lateral shift `y*` (m).
    pub y_star: f64,
    /// Tread contact just before the jump.
    pub tread: Contact,
    /// Flange contact just after the jump.
    pub flange: Contact,
}

/// Grid of a [`ContactTable`].
#[derive(Debug, Clone, Copy)]
pub struct TableSettings {
    /// Largest lateral shift (m); the table covers `[−y_max, y_max]`.
    pub y_max: f64,
    /// Lateral step (m).
    pub dy: f64,
    /// Largest roll (rad); the table covers `[−roll_max, roll_max]`.
    pub roll_max: f64,
    /// Roll step (rad).
    pub droll: f64,
}

impl Default for TableSettings {
    fn default() -> Self {
        TableSettings {
            y_max: 0.015,
            dy: 0.1e-3,
            roll_max: 0.02,
            droll: 2e-3,
        }
    }
}

/// Contact tables over lateral shift and roll, computed once before a simulation and
/// interpolated during it, plus the rigid contact geometry functions over the lateral shift.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct ContactTable {
    ny: usize,
    nr: usize,
    y0: f64,
    dy: f64,
    r0: f64,
    dr: f64,
    rigid: Vec<RigidContact>,
    /// Per side, the wheel profile coordinate `u` (m) that separates the
    /// tread and flange regions of [`ContactTable::lookup_regions`].
    split: [f64; 2],
    /// Per side, nodes over (w, ψ): w = y_s + sin(φ_s)·R the side-local
    /// lateral shift of the wheel's lowest point (y_s, φ_s the side-local
    /// shift and roll, R the wheel radius), ψ = φ_s on the roll grid; per
    /// node the deepest point of each region. With w instead of y the
    /// geometry depends only weakly on the roll (a roll mostly moves the
    /// wheel sideways by R·φ), so the roll grid may stay coarse.
    regions: [Vec<[Contact; 2]>; 2],
    /// The w grid: first value and count (step `dy`).
    w0: f64,
    nw: usize,
    /// Wheel radius R per side, m.
    radius: [f64; 2],
}

impl ContactTable {
    /// Computes the tables for `wheelset` on `track`.
    pub fn new(
        wheelset: &Wheelset,
        track: &Track,
        search: SearchSettings,
        settings: TableSettings,
    ) -> Result<ContactTable, GeometryError> {
        let geo = ContactGeometry::new(wheelset, track, search)?;
        ContactTable::from_geometry(&geo, settings)
    }

    /// Computes the tables from a prepared geometry.
    pub fn from_geometry(
        geo: &ContactGeometry,
        settings: TableSettings,
    ) -> Result<ContactTable, GeometryError> {
        check_positive("table lateral range", settings.y_max)?;
        check_positive("table lateral step", settings.dy)?;
        check_positive("table roll step", settings.droll)?;
        if !(settings.roll_max.is_finite() && settings.roll_max >= 0.0) {
            return Err(invalid("table roll range", "must be finite and ≥ 0"));
        }
        let ny = 2 * (settings.y_max / settings.dy).round() as usize + 1;
        let nr = 2 * (settings.roll_max / settings.droll).round() as usize + 1;
        let y0 = -(((ny - 1) / 2) as f64) * settings.dy;
        let r0 = -(((nr - 1) / 2) as f64) * settings.droll;
        // rigid functions from the centre outwards (continuation of the roll guess)
        let mut rigid = vec![None; ny];
        let ic = (ny - 1) / 2;
        for dir in [1i64, -1] {
            let mut guess = 0.0;
            let mut i = ic as i64;
            while i >= 0 && (i as usize) < ny {
                let y = y0 + i as f64 * settings.dy;
                let r = geo.rigid_from(y, guess)?;
                guess = r.roll;
                rigid[i as usize] = Some(r);
                i += dir;
            }
        }
        let rigid: Vec<RigidContact> = rigid.into_iter().map(|r| r.expect("filled")).collect();
        let split = [0, 1].map(|side| region_split(&rigid, side));
        let radius = [geo.sides[0].radius, geo.sides[1].radius];
        let w_max = settings.y_max + settings.roll_max.sin() * radius[0].max(radius[1]);
        let nw = 2 * (w_max / settings.dy).ceil() as usize + 1;
        let w0 = -(((nw - 1) / 2) as f64) * settings.dy;
        let mut regions = [Vec::with_capacity(nw * nr), Vec::with_capacity(nw * nr)];
        for (side, nodes) in regions.iter_mut().enumerate() {
            let sign = geo.sides[side].sign;
            for i in 0..nw {
                let w = w0 + i as f64 * settings.dy;
                for j in 0..nr {
                    let ps = r0 + j as f64 * settings.droll;
                    let ys = w - ps.sin() * radius[side];
                    nodes.push(geo.region_contacts(side, sign * ys, sign * ps, split[side])?);
                }
            }
        }
        Ok(ContactTable {
            ny,
            nr,
            y0,
            dy: settings.dy,
            r0,
            dr: settings.droll,
            rigid,
            split,
            regions,
            w0,
            nw,
            radius,
        })
    }

    /// The rigid contact geometry functions at the table's lateral shifts.
    pub fn rigid_functions(&self) -> &[RigidContact] {
        &self.rigid
    }

    /// Lateral range `(min, max)` (m).
    pub fn y_range(&self) -> (f64, f64) {
        (self.y0, self.y0 + (self.ny - 1) as f64 * self.dy)
    }

    /// Roll range `(min, max)` (rad).
    pub fn roll_range(&self) -> (f64, f64) {
        (self.r0, self.r0 + (self.nr - 1) as f64 * self.dr)
    }

    fn locate(
        what: &'static str,
        v: f64,
        x0: f64,
        dx: f64,
        n: usize,
    ) -> Result<(usize, f64), GeometryError> {
        let max = x0 + (n - 1) as f64 * dx;
        let t = (v - x0) / dx;
        if !(t >= -1e-9 && t <= (n - 1) as f64 + 1e-9) {
            return Err(GeometryError::OutOfRange {
                what,
                value: v,
                min: x0,
                max,
            });
        }
        if n == 1 {
            return Ok((0, 0.0));
        }
        let i = (t.floor() as usize).min(n - 2);
        Ok((i, (t - i as f64).clamp(0.0, 1.0)))
    }

    /// The wheel profile coordinates `u` (m; left, right wheel) that separate
    /// the tread and flange regions of [`ContactTable::lookup_regions`]: the
    /// middle of the jump of the rigid wheelset's contact point (by more than
    /// 2 mm) that turns the contact normal the most over the table's lateral
    /// range — the flange-root fold of profiles like S1002 on UIC60 — or −∞
    /// (one region) if the contact point never jumps.
    pub fn region_split(&self) -> [f64; 2] {
        self.split
    }

    /// The deepest point of the tread and of the flange region of each wheel
    /// ([`ContactGeometry::region_contacts`]) at lateral shift `y` (m) and
    /// roll `roll` (rad), wheelset height z = 0: `[side][slot]`, slot 0 the
    /// tread side. The gap is interpolated cubically along the wheel's own
    /// lateral shift w and linearly in roll, and the contact angle is the one
    /// of the gap's lateral slope, `tan δ = −∂gap/∂y` — the profiles' contact
    /// angle where the contact point moves smoothly, and continuous (the
    /// gradient of the gap) where it jumps; the other quantities are
    /// bilinear. So the result is continuous in y and roll — what a time
    /// integration needs. Both slots are always returned; a slot
    /// with a positive gap is not in contact. Near the flange root of
    /// profiles whose contact point jumps, both slots may touch at once: the
    /// load is then shared by two patches where in reality one conformal
    /// patch spans both.
    pub fn lookup_regions(&self, y: f64, roll: f64) -> Result<[[Contact; 2]; 2], GeometryError> {
        Ok([
            self.lookup_regions_of(0, y, roll)?,
            self.lookup_regions_of(1, y, roll)?,
        ])
    }

    /// One wheel's `[slot]` of [`Self::lookup_regions`] (`side` 0 left,
    /// 1 right), the same numbers, with only that wheel's lateral shift
    /// checked against the table: the contact looks each wheel up at its
    /// own rail's position.
    pub fn lookup_regions_of(
        &self,
        side: usize,
        y: f64,
        roll: f64,
    ) -> Result<[Contact; 2], GeometryError> {
        if !(y.is_finite() && roll.is_finite()) {
            return Err(invalid(
                "wheelset position",
                format!("lateral shift {y} and roll {roll} must be finite"),
            ));
        }
        if side > 1 {
            return Err(invalid(
                "wheel side",
                format!("{side}: 0 is the left wheel, 1 the right"),
            ));
        }
        let mut out = [Contact::default(); 2];
        let sign = if side == 0 { 1.0 } else { -1.0 };
        let (ys, ps) = (sign * y, sign * roll);
        let w = ys + ps.sin() * self.radius[side];
        let (i, tw) = Self::locate("lateral shift", w, self.w0, self.dy, self.nw)?;
        let (j, tr) = Self::locate("roll", ps, self.r0, self.dr, self.nr)?;
        let j1 = (j + 1).min(self.nr - 1);
        let i1 = (i + 1).min(self.nw - 1);
        let corners = [
            (i, j, (1.0 - tw) * (1.0 - tr)),
            (i1, j, tw * (1.0 - tr)),
            (i, j1, (1.0 - tw) * tr),
            (i1, j1, tw * tr),
        ];
        let nodes = &self.regions[side];
        // In (w, roll) the gap is nearly linear in roll (its rigid-body
        // part sin φ·ξ + (cos φ − 1)·ζ: with ξ ≈ 0.75 m, ζ ≈ −0.46 m the
        // error of linear interpolation over a 2 mrad cell is below 1 µm).
        let node_gap = |ci: usize, cj: usize, slot: usize| nodes[ci * self.nr + cj][slot].gap;
        for slot in 0..2 {
            // The gap along w by cubic Hermite interpolation (slopes by
            // central differences), linear in roll: continuous with a
            // continuous slope, so the contact angle taken from the slope
            // below is continuous too and is the gradient of the gap — the
            // normal force stays (nearly) conservative even across a jump
            // of the contact point, where the profile's own contact angle
            // would switch within one cell.
            let mut gap = 0.0;
            let mut slope = 0.0;
            for (cj, wr) in [(j, 1.0 - tr), (j1, tr)] {
                if wr == 0.0 {
                    continue;
                }
                let g = |k: isize| {
                    let k = k.clamp(0, self.nw as isize - 1) as usize;
                    node_gap(k, cj, slot)
                };
                let (a, b) = (i as isize, i1 as isize);
                let (p0, p1) = (g(a), g(b));
                let m0 = 0.5 * (p1 - g(a - 1));
                let m1 = 0.5 * (g(b + 1) - p0);
                let t = tw;
                let (t2, t3) = (t * t, t * t * t);
                gap += wr
                    * ((2.0 * t3 - 3.0 * t2 + 1.0) * p0
                        + (t3 - 2.0 * t2 + t) * m0
                        + (-2.0 * t3 + 3.0 * t2) * p1
                        + (t3 - t2) * m1);
                slope += wr
                    * ((6.0 * t2 - 6.0 * t) * p0
                        + (3.0 * t2 - 4.0 * t + 1.0) * m0
                        + (-6.0 * t2 + 6.0 * t) * p1
                        + (3.0 * t2 - 2.0 * t) * m1)
                    / self.dy;
            }
            let mut acc = [0.0; 14];
            for &(ci, cj, wt) in &corners {
                if wt == 0.0 {
                    continue;
                }
                let v = nodes[ci * self.nr + cj][slot].values();
                for (a, v) in acc.iter_mut().zip(v) {
                    *a += wt * v;
                }
            }
            let mut c = Contact::from_values(acc);
            c.gap = gap;
            // ∂gap/∂y_s = −tan δ (moving the wheel outwards onto a surface
            // inclined by δ closes the gap by tan δ per metre).
            c.contact_angle = (-slope).atan();
            out[slot] = c;
        }
        Ok(out)
    }

    /// The linear (small-amplitude) equivalent conicity of the profiles about
    /// the centred wheelset (–): λ = ½ dΔr/dy at y = 0 by the central
    /// difference of the rigid contact functions ([`Self::rigid_functions`]:
    /// the exact contact geometry, the roll following the shift) at the
    /// table's two lateral nodes next to the centre, ±`dy`; Δr the
    /// rolling radius difference of the deepest contacts. It is the limit of
    /// EN 15302's equivalent conicity ([`crate::conicity`], with the rigid
    /// wheelset's roll) as the amplitude goes to zero where Δr is linear, so
    /// that the kinematic wavelength of Klingel's linear wheelset is
    /// 2π √(r0 e / λ). An error if the table has no node on each side of the
    /// centre.
    pub fn central_conicity(&self) -> Result<f64, GeometryError> {
        let ic = (self.ny - 1) / 2;
        if self.ny < 3 {
            return Err(invalid(
                "table for the central conicity",
                format!(
                    "{} lateral node(s): needs one on each side of the centre",
                    self.ny
                ),
            ));
        }
        let dr = |i: usize| self.rigid[i].rolling_radius_difference();
        let (yp, ym) = (self.rigid[ic + 1].y, self.rigid[ic - 1].y);
        Ok(0.5 * (dr(ic + 1) - dr(ic - 1)) / (yp - ym))
    }
}

/// The tread/flange split of one side from the rigid contact sweep (see
/// [`ContactTable::region_split`]).
fn region_split(rigid: &[RigidContact], side: usize) -> f64 {
    let mut split = f64::NEG_INFINITY;
    let mut largest = 0.0;
    for w in rigid.windows(2) {
        let (a, b) = (w[0].sides[side].deepest(), w[1].sides[side].deepest());
        // A jump of the contact point (more than 2 mm on the wheel) that
        // turns the normal the most: the flange-root fold rather than a
        // jump between two tread points.
        let turn = (a.contact_angle.tan() - b.contact_angle.tan()).abs();
        if (a.wheel_u - b.wheel_u).abs() > 2e-3 && turn > largest {
            largest = turn;
            split = 0.5 * (a.wheel_u + b.wheel_u);
        }
    }
    split
}

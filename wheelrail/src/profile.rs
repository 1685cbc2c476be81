//! Wheel and rail profiles: reading, orientation, smoothing, evaluation.
//!
//! # Convention (one for wheels and rails, all lengths in metres)
//!
//! A profile is a curve `h(u)` in its own cross-section plane:
//!
//! - `u` is the lateral coordinate, **positive towards the field side** (away from the
//!   track centre) for both wheels and rails; a profile therefore describes a *left*
//!   wheel or rail as seen from behind, and a right one as its mirror image;
//! - `h` is the height, **positive upwards**.
//!
//! **Wheel**: origin at the nominal taping line (the nominal rolling circle, 70 mm from
//! the flange back for S1002/EN 15302 profiles): `u = 0`, `h = 0` there. The flange lies at
//! `u < 0` (the flange back of S1002 at `u = −0.070`), the tread at `u > 0`. The rolling radius
//! at `u` is `r(u) = r0 − h(u)` (`h < 0` on the flange, whose tip is about 28 mm below the tread).
//!
//! **Rail**: origin at the highest point of the head in the rail's mounted orientation
//! (after the rail inclination has been applied): `h ≤ 0` everywhere, `h = 0` at `u = 0`; the
//! gauge face lies at `u < 0`.
//!
//! # File formats (coordinates in mm, converted to m on reading)
//!
//! | extension | format | orientation in the file |
//! |---|---|---|
//! | `.prw` | SIMPACK wheel | `y` towards the flange before mirroring (`mirror.y = 1`), `z` down; points may be in descending `y` |
//! | `.prr` | SIMPACK rail | `y` towards the field side (`mirror.y` honoured), `z` down |
//! | `.whl` | MiniProf wheel | `X` from the flange back towards the field side, `Y` down |
//! | `.ban` | MiniProf rail | `X` towards the gauge side, `Y` down |
//! | other | two columns `y z` | already in the convention above (`y` to the field side, `z` up) |
//!
//! Lines starting with `!`, `#`, `%` or `//` are comments in two-column files. Wheel profiles
//! are checked after conversion: if the flange (lowest point) comes out at `u > 0` the profile
//! is mirrored, and the height is shifted so that `h(0) = 0` (the taping line).
//!
//! # Smoothing
//!
//! The points are approximated by a cubic smoothing spline (Reinsch 1967) minimising
//! `Σ wᵢ (hᵢ − s(uᵢ))² + L⁴ ∫ s''(u)² du` with weights `wᵢ` equal to the lateral length each
//! point represents (half the distance to its neighbours), so that the data term
//! approximates `∫ (h − s)² du` independently of the point spacing. The smoothing length
//! `L` (m) is the documented smoothing parameter: the spline acts as a low-pass filter with
//! transfer function `1/(1 + (ωL)⁴)`, i.e. it removes wavelengths shorter than about `2πL`
//! and leaves smooth shapes untouched (the bias on a circle arc of radius `R` is of relative
//! order `(L/R)⁴`). `L = 0` gives the natural interpolating cubic spline. The default
//! `L = 0.1 mm` removes measurement ripple shorter than about 0.6 mm and keeps the standard
//! profiles within 5 µm of their points; with it the EN 15302 reference conicities of cases
//! E1–E4 are reproduced (a larger `L`, e.g. 0.3 mm, moves the Δr jumps of wheel B by 0.1 mm).

use std::fmt;
use std::path::Path;

/// Wheel or rail.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProfileKind {
    /// A wheel profile.
    Wheel,
    /// A rail profile.
    Rail,
}

impl fmt::Display for ProfileKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ProfileKind::Wheel => write!(f, "wheel"),
            ProfileKind::Rail => write!(f, "rail"),
        }
    }
}

/// The file formats understood by [`read_points`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProfileFormat {
    /// SIMPACK `.prw` (wheel) or `.prr` (rail).
    Simpack,
    /// MiniProf `.whl` (wheel) or `.ban` (rail).
    MiniProf,
    /// Two columns `y z` in mm, already in the library convention.
    TwoColumn,
}

impl ProfileFormat {
    /// Format and, where the extension implies it, kind of a file from its extension.
    pub fn from_path(path: &Path) -> (ProfileFormat, Option<ProfileKind>) {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .unwrap_or_default();
        match ext.as_str() {
            "prw" => (ProfileFormat::Simpack, Some(ProfileKind::Wheel)),
            "prr" => (ProfileFormat::Simpack, Some(ProfileKind::Rail)),
            "whl" => (ProfileFormat::MiniProf, Some(ProfileKind::Wheel)),
            "ban" => (ProfileFormat::MiniProf, Some(ProfileKind::Rail)),
            _ => (ProfileFormat::TwoColumn, None),
        }
    }
}

/// Errors of reading and preparing profiles. Every variant names the file (or the name
/// given to [`parse_points`]) and, where there is one, the line.
#[derive(Debug, thiserror::Error)]
pub enum ProfileError {
    /// The file could not be read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// File name.
        file: String,
        /// Underlying error.
        source: std::io::Error,
    },
    /// A line could not be parsed.
    #[error("{file}:{line}: {message}")]
    Syntax {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The lateral coordinate is not strictly monotonic.
    #[error(
        "{file}:{line}: lateral coordinate not strictly monotonic ({value} mm after {previous} mm)"
    )]
    NotMonotonic {
        /// File name.
        file: String,
        /// 1-based line number of the offending point.
        line: usize,
        /// Offending value (mm, as in the file).
        value: f64,
        /// Previous value (mm).
        previous: f64,
    },
    /// Too few points for a spline.
    #[error("{file}: only {found} profile points, at least {needed} are needed")]
    TooFewPoints {
        /// File name.
        file: String,
        /// Points found.
        found: usize,
        /// Points needed.
        needed: usize,
    },
    /// The file is a wheel profile where a rail was expected, or the reverse.
    #[error("{file}: is a {found} profile, a {expected} profile was expected")]
    WrongKind {
        /// File name.
        file: String,
        /// Kind found in the file (extension or header).
        found: ProfileKind,
        /// Kind requested.
        expected: ProfileKind,
    },
    /// An invalid setting or a profile that cannot be prepared.
    #[error("{file}: {message}")]
    Invalid {
        /// File name.
        file: String,
        /// What is wrong.
        message: String,
    },
}

/// Points of a profile in the library convention (metres), before smoothing.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfilePoints {
    /// Wheel or rail.
    pub kind: ProfileKind,
    /// File name (for messages).
    pub name: String,
    /// Points `[u, h]` (m), strictly increasing in `u`.
    pub points: Vec<[f64; 2]>,
}

/// A raw point read from a file, with its line number.
#[derive(Debug, Clone, Copy)]
struct RawPoint {
    y: f64,
    z: f64,
    line: usize,
}

fn syntax(file: &str, line: usize, message: impl Into<String>) -> ProfileError {
    ProfileError::Syntax {
        file: file.to_string(),
        line,
        message: message.into(),
    }
}

fn parse_pair(file: &str, line: usize, text: &str) -> Result<(f64, f64), ProfileError> {
    let mut it = text
        .split(|c: char| c.is_whitespace() || c == ',' || c == ';')
        .filter(|s| !s.is_empty());
    let a = it
        .next()
        .ok_or_else(|| syntax(file, line, "expected two numbers y z"))?;
    let b = it.next().ok_or_else(|| {
        syntax(
            file,
            line,
            format!("expected two numbers y z, found only `{a}`"),
        )
    })?;
    let pa: f64 = a
        .parse()
        .map_err(|_| syntax(file, line, format!("`{a}` is not a number")))?;
    let pb: f64 = b
        .parse()
        .map_err(|_| syntax(file, line, format!("`{b}` is not a number")))?;
    if !pa.is_finite() || !pb.is_finite() {
        return Err(syntax(file, line, "coordinates must be finite"));
    }
    Ok((pa, pb))
}

fn is_comment(t: &str) -> bool {
    t.starts_with('!') || t.starts_with('#') || t.starts_with('%') || t.starts_with("//")
}

fn parse_two_column(file: &str, text: &str) -> Result<Vec<RawPoint>, ProfileError> {
    let mut pts = Vec::new();
    for (i, l) in text.lines().enumerate() {
        let t = l.trim();
        if t.is_empty() || is_comment(t) {
            continue;
        }
        let (y, z) = parse_pair(file, i + 1, t)?;
        pts.push(RawPoint { y, z, line: i + 1 });
    }
    Ok(pts)
}

/// SIMPACK `.prw`/`.prr`: header keys, points between `point.begin` and `point.end`.
/// Returns points, header type (0 rail, 1 wheel) and the mirror flags.
fn parse_simpack(
    file: &str,
    text: &str,
) -> Result<(Vec<RawPoint>, Option<i64>, bool, bool), ProfileError> {
    let mut pts = Vec::new();
    let mut in_points = false;
    let mut seen_points = false;
    let mut kind = None;
    let mut mirror_y = false;
    let mut mirror_z = false;
    for (i, l) in text.lines().enumerate() {
        let t = l.trim();
        if t.is_empty() || t.starts_with('!') {
            continue;
        }
        if in_points {
            if t.starts_with("point.end") {
                in_points = false;
                continue;
            }
            let data = t.split('!').next().unwrap_or("").trim();
            if data.is_empty() {
                continue;
            }
            let (y, z) = parse_pair(file, i + 1, data)?;
            pts.push(RawPoint { y, z, line: i + 1 });
            continue;
        }
        if t.starts_with("point.begin") {
            in_points = true;
            seen_points = true;
            continue;
        }
        if let Some((key, value)) = t.split_once('=') {
            let key = key.trim();
            let value = value.split('!').next().unwrap_or("").trim();
            let int = || -> Result<i64, ProfileError> {
                value
                    .parse::<i64>()
                    .map_err(|_| syntax(file, i + 1, format!("`{key}` must be an integer")))
            };
            match key {
                "type" if kind.is_none() => kind = Some(int()?),
                "mirror.y" => mirror_y = int()? == 1,
                "mirror.z" => mirror_z = int()? == 1,
                _ => {}
            }
        }
    }
    if !seen_points {
        return Err(ProfileError::Invalid {
            file: file.to_string(),
            message: "no `point.begin` section: not a SIMPACK profile".into(),
        });
    }
    if in_points {
        return Err(ProfileError::Invalid {
            file: file.to_string(),
            message: "`point.begin` without `point.end`".into(),
        });
    }
    Ok((pts, kind, mirror_y, mirror_z))
}

/// MiniProf `.whl`/`.ban`: `key=value` header lines, then data lines `X Y`; a data line
/// may start with `"` (MiniProf marks interpolated points that way).
fn parse_miniprof(file: &str, text: &str) -> Result<Vec<RawPoint>, ProfileError> {
    let mut pts = Vec::new();
    for (i, l) in text.lines().enumerate() {
        let t = l.trim();
        if t.is_empty() || is_comment(t) {
            continue;
        }
        let data = t.trim_start_matches('"').trim();
        let first = data.chars().next().unwrap_or(' ');
        let numeric_start = first.is_ascii_digit() || first == '-' || first == '+' || first == '.';
        if !numeric_start {
            if t.contains('=') && pts.is_empty() {
                continue; // header line
            }
            return Err(syntax(
                file,
                i + 1,
                format!("expected a data line `X Y`, found `{t}`"),
            ));
        }
        let (y, z) = parse_pair(file, i + 1, data)?;
        pts.push(RawPoint { y, z, line: i + 1 });
    }
    Ok(pts)
}

/// Checks strict monotonicity of the lateral coordinate (either direction) in file order.
fn check_monotonic(file: &str, pts: &[RawPoint]) -> Result<(), ProfileError> {
    if pts.len() < 2 {
        return Ok(());
    }
    let increasing = pts[1].y > pts[0].y;
    for w in pts.windows(2) {
        let ok = if increasing {
            w[1].y > w[0].y
        } else {
            w[1].y < w[0].y
        };
        if !ok {
            return Err(ProfileError::NotMonotonic {
                file: file.to_string(),
                line: w[1].line,
                value: w[1].y,
                previous: w[0].y,
            });
        }
    }
    Ok(())
}

/// Minimum number of points of a profile.
pub const MIN_POINTS: usize = 4;

/// Parses profile text in the given format into points in the library convention.
/// `name` is used in error messages. For [`ProfileFormat::TwoColumn`] the `kind` must be
/// given by the caller; for the other formats it is checked against the file.
pub fn parse_points(
    text: &str,
    name: &str,
    format: ProfileFormat,
    kind: ProfileKind,
) -> Result<ProfilePoints, ProfileError> {
    let mm = 1e-3;
    let pts: Vec<[f64; 2]> = match format {
        ProfileFormat::TwoColumn => {
            let raw = parse_two_column(name, text)?;
            check_count(name, raw.len())?;
            check_monotonic(name, &raw)?;
            raw.iter().map(|p| [p.y * mm, p.z * mm]).collect()
        }
        ProfileFormat::Simpack => {
            let (raw, t, mirror_y, mirror_z) = parse_simpack(name, text)?;
            if let Some(t) = t {
                let found = if t == 1 {
                    ProfileKind::Wheel
                } else {
                    ProfileKind::Rail
                };
                if found != kind {
                    return Err(ProfileError::WrongKind {
                        file: name.to_string(),
                        found,
                        expected: kind,
                    });
                }
            }
            check_count(name, raw.len())?;
            check_monotonic(name, &raw)?;
            // SIMPACK: z points down; mirror.y flips y (for S1002 .prw it turns the flange to
            // y < 0, i.e. y towards the field side, as for the rail).
            raw.iter()
                .map(|p| {
                    let y = if mirror_y { -p.y } else { p.y };
                    let z = if mirror_z { -p.z } else { p.z };
                    [y * mm, -z * mm]
                })
                .collect()
        }
        ProfileFormat::MiniProf => {
            let raw = parse_miniprof(name, text)?;
            check_count(name, raw.len())?;
            check_monotonic(name, &raw)?;
            match kind {
                // X from the flange back towards the field side: the taping line is 70 mm
                // from the flange back; Y down.
                ProfileKind::Wheel => {
                    let xmin = raw.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
                    let shift = if xmin > -1.0 { 70.0 } else { 0.0 };
                    raw.iter()
                        .map(|p| [(p.y - shift) * mm, -p.z * mm])
                        .collect()
                }
                // X towards the gauge side, Y down.
                ProfileKind::Rail => raw.iter().map(|p| [-p.y * mm, -p.z * mm]).collect(),
            }
        }
    };
    let mut pts = pts;
    if pts[0][0] > pts[pts.len() - 1][0] {
        pts.reverse();
    }
    let mut out = ProfilePoints {
        kind,
        name: name.to_string(),
        points: pts,
    };
    if kind == ProfileKind::Wheel {
        out.normalize_wheel()?;
    }
    Ok(out)
}

fn check_count(name: &str, n: usize) -> Result<(), ProfileError> {
    if n < MIN_POINTS {
        return Err(ProfileError::TooFewPoints {
            file: name.to_string(),
            found: n,
            needed: MIN_POINTS,
        });
    }
    Ok(())
}

/// Reads a profile file; the format follows from the extension (see the module docs).
pub fn read_points(path: &Path, kind: ProfileKind) -> Result<ProfilePoints, ProfileError> {
    let name = path.display().to_string();
    let (format, implied) = ProfileFormat::from_path(path);
    if let Some(found) = implied
        && found != kind
    {
        return Err(ProfileError::WrongKind {
            file: name,
            found,
            expected: kind,
        });
    }
    let text = std::fs::read_to_string(path).map_err(|source| ProfileError::Io {
        file: name.clone(),
        source,
    })?;
    parse_points(&text, &name, format, kind)
}

impl ProfilePoints {
    /// Wheel normalisation: flange at `u < 0` (mirror if needed), `h(0) = 0`.
    fn normalize_wheel(&mut self) -> Result<(), ProfileError> {
        let lowest =
            self.points.iter().fold(
                [0.0, f64::INFINITY],
                |a, p| if p[1] < a[1] { *p } else { a },
            );
        if lowest[0] > 0.0 {
            for p in &mut self.points {
                p[0] = -p[0];
            }
            self.points.reverse();
        }
        let (u0, u1) = (self.points[0][0], self.points[self.points.len() - 1][0]);
        if !(u0 < 0.0 && u1 > 0.0) {
            return Err(ProfileError::Invalid {
                file: self.name.clone(),
                message: format!(
                    "wheel profile spans y = {:.3} .. {:.3} mm and does not contain the taping line y = 0",
                    u0 * 1e3,
                    u1 * 1e3
                ),
            });
        }
        let i = self.points.partition_point(|p| p[0] < 0.0).max(1);
        let (a, b) = (self.points[i - 1], self.points[i]);
        let h0 = a[1] + (b[1] - a[1]) * (0.0 - a[0]) / (b[0] - a[0]);
        for p in &mut self.points {
            p[1] -= h0;
        }
        Ok(())
    }

    /// Rotates the points by `angle` (rad) counter-clockwise in the `(u, h)` plane, i.e. a
    /// positive angle tilts the top of a rail towards the gauge side (`u < 0`), as a rail
    /// inclination of 1:40 does (`angle = atan(1/40)`).
    pub fn rotated(&self, angle: f64) -> ProfilePoints {
        let (s, c) = angle.sin_cos();
        ProfilePoints {
            kind: self.kind,
            name: self.name.clone(),
            points: self
                .points
                .iter()
                .map(|p| [c * p[0] - s * p[1], s * p[0] + c * p[1]])
                .collect(),
        }
    }
}

/// Settings for turning points into a smooth [`Profile`].
#[derive(Debug, Clone, Copy)]
pub struct ProfileSettings {
    /// Smoothing length `L` (m) of the smoothing spline (see the module docs); 0 interpolates.
    /// Default 0.1 mm.
    pub smoothing_length: f64,
    /// Points closer than this (m) in `u` to the previously kept point are dropped (near-vertical
    /// parts of a profile, e.g. a rail's gauge face, are measured with tiny lateral steps).
    pub min_spacing: f64,
    /// Rail inclination (rad) applied to a rail profile as read (positive tilts the head towards
    /// the track centre; `atan(1/40)` for 1:40). Use 0 for a profile already inclined in its file.
    pub rail_inclination: f64,
}

impl Default for ProfileSettings {
    fn default() -> Self {
        ProfileSettings {
            smoothing_length: 0.1e-3,
            min_spacing: 0.01e-3,
            rail_inclination: 0.0,
        }
    }
}

/// A smooth profile `h(u)` (library convention, metres): a piecewise cubic on knots `u_i`.
#[derive(Debug, Clone)]
pub struct Profile {
    kind: ProfileKind,
    name: String,
    knots: Vec<f64>,
    /// Per segment `[a, b, c, d]`: `h = a + b t + c t² + d t³`, `t = u − u_i`.
    coef: Vec<[f64; 4]>,
}

/// Height, slope and second derivative of a profile at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileValue {
    /// Height `h` (m).
    pub h: f64,
    /// Slope `dh/du` (–).
    pub slope: f64,
    /// Second derivative `d²h/du²` (1/m).
    pub second: f64,
}

impl ProfileValue {
    /// Signed curvature of the curve `h(u)`, `h''/(1 + h'²)^{3/2}` (1/m): positive where the
    /// curve is concave seen from above (bends upwards).
    pub fn curvature(&self) -> f64 {
        self.second / (1.0 + self.slope * self.slope).powf(1.5)
    }
}

/// The largest lateral extent of a profile's points, m: five times a wheel
/// profile's width (a rail with its foot spans 0.15 m).
pub const MAX_LATERAL_EXTENT: f64 = 0.75;

impl Profile {
    /// Builds a smooth profile from points. For a rail, the inclination of `settings` is applied
    /// first, parts folding back under the head after rotation are trimmed, and the origin is
    /// moved to the highest point.
    pub fn from_points(
        points: &ProfilePoints,
        settings: &ProfileSettings,
    ) -> Result<Profile, ProfileError> {
        let name = &points.name;
        let bad = |message: String| ProfileError::Invalid {
            file: name.clone(),
            message,
        };
        if !(settings.smoothing_length.is_finite() && settings.smoothing_length >= 0.0) {
            return Err(bad(format!(
                "smoothing length must be finite and ≥ 0, got {}",
                settings.smoothing_length
            )));
        }
        if !(settings.min_spacing.is_finite() && settings.min_spacing >= 0.0) {
            return Err(bad(format!(
                "minimum point spacing must be finite and ≥ 0, got {}",
                settings.min_spacing
            )));
        }
        if !(settings.rail_inclination.is_finite() && settings.rail_inclination.abs() < 0.5) {
            return Err(bad(format!(
                "rail inclination must be finite and below 0.5 rad in magnitude, got {}",
                settings.rail_inclination
            )));
        }
        // A wheel's profile spans about 0.14 m laterally and a rail's head
        // 0.07 m (with its foot 0.15 m); the contact search samples the
        // profile every 0.25 mm, so an extent of kilometres (a value in mm
        // read as m, or a stray point) would allocate without bound.
        let (lo, hi) = points
            .points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p[0]), hi.max(p[0]))
            });
        if hi - lo > MAX_LATERAL_EXTENT {
            return Err(bad(format!(
                "the points span {:.4} m laterally (from {lo} to {hi} m), more than the {} m \
                 a wheel or rail profile can: check the units (files are in mm) and for stray points",
                hi - lo,
                MAX_LATERAL_EXTENT
            )));
        }
        let mut pts = points.points.clone();
        if points.kind == ProfileKind::Rail {
            if settings.rail_inclination != 0.0 {
                pts = points.rotated(settings.rail_inclination).points;
                pts = trim_folds(&pts);
            }
            let top = pts.iter().fold(
                [0.0, f64::NEG_INFINITY],
                |a, p| if p[1] > a[1] { *p } else { a },
            );
            for p in &mut pts {
                p[0] -= top[0];
                p[1] -= top[1];
            }
        }
        // thin out points closer than min_spacing (keep the last point)
        let mut kept: Vec<[f64; 2]> = Vec::with_capacity(pts.len());
        for (i, p) in pts.iter().enumerate() {
            match kept.last() {
                Some(q) if p[0] - q[0] < settings.min_spacing.max(f64::MIN_POSITIVE) => {
                    if i == pts.len() - 1 && kept.len() > 1 {
                        *kept.last_mut().expect("non-empty") = *p;
                    }
                }
                _ => kept.push(*p),
            }
        }
        if kept.len() < MIN_POINTS {
            return Err(ProfileError::TooFewPoints {
                file: name.clone(),
                found: kept.len(),
                needed: MIN_POINTS,
            });
        }
        let u: Vec<f64> = kept.iter().map(|p| p[0]).collect();
        let h: Vec<f64> = kept.iter().map(|p| p[1]).collect();
        let coef = smoothing_spline(&u, &h, settings.smoothing_length.powi(4));
        if coef.iter().flatten().any(|c| !c.is_finite()) {
            return Err(bad(
                "smoothing spline failed (non-finite coefficients)".into()
            ));
        }
        Ok(Profile {
            kind: points.kind,
            name: name.clone(),
            knots: u,
            coef,
        })
    }

    /// Reads a file and smooths it (see [`read_points`] and [`Profile::from_points`]).
    pub fn read(
        path: &Path,
        kind: ProfileKind,
        settings: &ProfileSettings,
    ) -> Result<Profile, ProfileError> {
        Profile::from_points(&read_points(path, kind)?, settings)
    }

    /// Wheel or rail.
    pub fn kind(&self) -> ProfileKind {
        self.kind
    }

    /// Name (file) of the profile.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Lateral range `(u_min, u_max)` (m) where the profile is defined.
    pub fn range(&self) -> (f64, f64) {
        (self.knots[0], self.knots[self.knots.len() - 1])
    }

    /// Height, slope and second derivative at `u` (m); `None` outside [`Profile::range`].
    #[inline]
    pub fn eval(&self, u: f64) -> Option<ProfileValue> {
        let n = self.knots.len();
        if !(u >= self.knots[0] && u <= self.knots[n - 1]) {
            return None;
        }
        let i = (self.knots.partition_point(|&k| k <= u)).clamp(1, n - 1) - 1;
        let t = u - self.knots[i];
        let [a, b, c, d] = self.coef[i];
        Some(ProfileValue {
            h: a + t * (b + t * (c + t * d)),
            slope: b + t * (2.0 * c + 3.0 * d * t),
            second: 2.0 * c + 6.0 * d * t,
        })
    }

    /// Height `h(u)` (m) using and updating a segment hint `seg` (fast for monotone sweeps
    /// over `u`); `None` outside the range.
    #[inline]
    pub fn height_hinted(&self, u: f64, seg: &mut usize) -> Option<f64> {
        let n = self.knots.len();
        if !(u >= self.knots[0] && u <= self.knots[n - 1]) {
            return None;
        }
        let mut i = (*seg).min(n - 2);
        let mut steps = 0;
        while u < self.knots[i] && steps < 8 {
            i -= 1;
            steps += 1;
        }
        while u >= self.knots[i + 1] && i + 2 < n && steps < 8 {
            i += 1;
            steps += 1;
        }
        if !(u >= self.knots[i] && (u < self.knots[i + 1] || i + 2 == n)) {
            i = self.knots.partition_point(|&k| k <= u).clamp(1, n - 1) - 1;
        }
        *seg = i;
        let t = u - self.knots[i];
        let [a, b, c, d] = self.coef[i];
        Some(a + t * (b + t * (c + t * d)))
    }

    /// Height `h(u)` (m); `None` outside the range.
    pub fn height(&self, u: f64) -> Option<f64> {
        self.eval(u).map(|v| v.h)
    }

    /// Slope `dh/du` at `u`; `None` outside the range.
    pub fn slope(&self, u: f64) -> Option<f64> {
        self.eval(u).map(|v| v.slope)
    }

    /// Signed curvature at `u` (1/m, see [`ProfileValue::curvature`]); `None` outside the range.
    pub fn curvature(&self, u: f64) -> Option<f64> {
        self.eval(u).map(|v| v.curvature())
    }

    /// Lateral position `u` (m) of the gauge point of a rail: the point of the gauge side
    /// (`u < 0`) at `depth` (m) below the top of the head, found by walking from the top
    /// towards the gauge side.
    pub fn gauge_point(&self, depth: f64) -> Option<f64> {
        let target = -depth;
        let (u0, _) = self.range();
        let step = 0.05e-3;
        let mut u = 0.0_f64.min(self.range().1);
        let mut prev = (u, self.height(u)?);
        while u > u0 {
            u = (u - step).max(u0);
            let h = self.height(u)?;
            if h <= target {
                // bisect between prev.0 and u
                let (mut a, mut b) = (u, prev.0);
                for _ in 0..60 {
                    let m = 0.5 * (a + b);
                    if self.height(m)? <= target {
                        a = m;
                    } else {
                        b = m;
                    }
                }
                return Some(0.5 * (a + b));
            }
            prev = (u, h);
        }
        None
    }
}

/// Keeps the part of a rotated profile around its highest point along which `u` increases;
/// where the curve folds back (a face rotated past the vertical) the rest is dropped.
fn trim_folds(pts: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let top = pts
        .iter()
        .enumerate()
        .fold((0, f64::NEG_INFINITY), |a, (i, p)| {
            if p[1] > a.1 { (i, p[1]) } else { a }
        })
        .0;
    let mut hi = top;
    while hi + 1 < pts.len() && pts[hi + 1][0] > pts[hi][0] {
        hi += 1;
    }
    let mut lo = top;
    while lo > 0 && pts[lo - 1][0] < pts[lo][0] {
        lo -= 1;
    }
    pts[lo..=hi].to_vec()
}

/// Cubic smoothing spline (Reinsch): minimises `Σ wᵢ (yᵢ − s(xᵢ))² + α ∫ s''²` with
/// `wᵢ = (x_{i+1} − x_{i−1})/2` (half-widths at the ends). Natural end conditions.
/// Returns per-segment polynomial coefficients.
#[allow(clippy::needless_range_loop)] // banded linear algebra reads clearer with indices
fn smoothing_spline(x: &[f64], y: &[f64], alpha: f64) -> Vec<[f64; 4]> {
    let n = x.len();
    let h: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
    let w: Vec<f64> = (0..n)
        .map(|i| {
            let l = if i > 0 { h[i - 1] } else { 0.0 };
            let r = if i + 1 < n { h[i] } else { 0.0 };
            0.5 * (l + r)
        })
        .collect();
    let m = n - 2; // interior knots 1..=n-2 -> index j-1
    // Q column j (interior knot j): entries at rows j-1, j, j+1.
    let q = |j: usize| -> [f64; 3] { [1.0 / h[j - 1], -1.0 / h[j - 1] - 1.0 / h[j], 1.0 / h[j]] };
    // Symmetric pentadiagonal A = R + α Qᵀ W⁻¹ Q, stored as diagonals d0, d1, d2.
    let mut d0 = vec![0.0; m];
    let mut d1 = vec![0.0; m];
    let mut d2 = vec![0.0; m];
    let mut rhs = vec![0.0; m];
    for k in 0..m {
        let j = k + 1;
        let qj = q(j);
        d0[k] = (h[j - 1] + h[j]) / 3.0;
        if k + 1 < m {
            d1[k] = h[j] / 6.0;
        }
        // (QᵀW⁻¹Q)_{j,j'} = Σ_r Q_{r,j} Q_{r,j'} / w_r
        d0[k] +=
            alpha * (qj[0] * qj[0] / w[j - 1] + qj[1] * qj[1] / w[j] + qj[2] * qj[2] / w[j + 1]);
        if k + 1 < m {
            let qn = q(j + 1); // rows j, j+1, j+2
            d1[k] += alpha * (qj[1] * qn[0] / w[j] + qj[2] * qn[1] / w[j + 1]);
        }
        if k + 2 < m {
            let qn = q(j + 2); // rows j+1, j+2, j+3
            d2[k] += alpha * (qj[2] * qn[0] / w[j + 1]);
        }
        rhs[k] = qj[0] * y[j - 1] + qj[1] * y[j] + qj[2] * y[j + 1];
    }
    let gamma = solve_pentadiagonal(&d0, &d1, &d2, &rhs);
    // g = y − α W⁻¹ Q γ
    let mut g = y.to_vec();
    if alpha > 0.0 {
        let mut qg = vec![0.0; n];
        for k in 0..m {
            let j = k + 1;
            let qj = q(j);
            qg[j - 1] += qj[0] * gamma[k];
            qg[j] += qj[1] * gamma[k];
            qg[j + 1] += qj[2] * gamma[k];
        }
        for i in 0..n {
            g[i] -= alpha * qg[i] / w[i];
        }
    }
    let mut c2 = vec![0.0; n]; // second derivatives at knots
    c2[1..(m + 1)].copy_from_slice(&gamma[..m]);
    (0..n - 1)
        .map(|i| {
            let hi = h[i];
            let a = g[i];
            let b = (g[i + 1] - g[i]) / hi - hi * (2.0 * c2[i] + c2[i + 1]) / 6.0;
            let c = c2[i] / 2.0;
            let d = (c2[i + 1] - c2[i]) / (6.0 * hi);
            [a, b, c, d]
        })
        .collect()
}

/// Solves a symmetric positive definite pentadiagonal system (diagonal `d0`, first and second
/// super-diagonals `d1`, `d2`) by an LDLᵀ factorisation.
#[allow(clippy::needless_range_loop)]
fn solve_pentadiagonal(d0: &[f64], d1: &[f64], d2: &[f64], b: &[f64]) -> Vec<f64> {
    let m = d0.len();
    if m == 0 {
        return Vec::new();
    }
    // L unit lower with sub-diagonals l1, l2; D diagonal dd.
    let mut dd = vec![0.0; m];
    let mut l1 = vec![0.0; m];
    let mut l2 = vec![0.0; m];
    for i in 0..m {
        let mut di = d0[i];
        if i >= 1 {
            di -= l1[i - 1] * l1[i - 1] * dd[i - 1];
        }
        if i >= 2 {
            di -= l2[i - 2] * l2[i - 2] * dd[i - 2];
        }
        dd[i] = di;
        if i + 1 < m {
            let mut e = d1[i];
            if i >= 1 {
                e -= l1[i - 1] * l2[i - 1] * dd[i - 1];
            }
            l1[i] = e / di;
        }
        if i + 2 < m {
            l2[i] = d2[i] / di;
        }
    }
    // forward: L z = b
    let mut z = b.to_vec();
    for i in 0..m {
        if i >= 1 {
            z[i] -= l1[i - 1] * z[i - 1];
        }
        if i >= 2 {
            z[i] -= l2[i - 2] * z[i - 2];
        }
    }
    for i in 0..m {
        z[i] /= dd[i];
    }
    // backward: Lᵀ x = z
    for i in (0..m).rev() {
        if i + 1 < m {
            z[i] -= l1[i] * z[i + 1];
        }
        if i + 2 < m {
            z[i] -= l2[i] * z[i + 2];
        }
    }
    z
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(clippy::needless_range_loop)]
    fn pentadiagonal_solver_matches_dense_product() {
        // A x = b with a known x: build b from A x and solve back.
        let m = 7;
        let d0: Vec<f64> = (0..m).map(|i| 6.0 + i as f64).collect();
        let d1: Vec<f64> = (0..m).map(|i| 1.0 + 0.1 * i as f64).collect();
        let d2: Vec<f64> = (0..m).map(|i| 0.5 - 0.02 * i as f64).collect();
        let x: Vec<f64> = (0..m).map(|i| (i as f64 * 0.7).sin()).collect();
        let mut b = vec![0.0; m];
        for i in 0..m {
            b[i] += d0[i] * x[i];
            if i + 1 < m {
                b[i] += d1[i] * x[i + 1];
                b[i + 1] += d1[i] * x[i];
            }
            if i + 2 < m {
                b[i] += d2[i] * x[i + 2];
                b[i + 2] += d2[i] * x[i];
            }
        }
        let s = solve_pentadiagonal(&d0, &d1, &d2, &b);
        for i in 0..m {
            assert!((s[i] - x[i]).abs() < 1e-12);
        }
    }

    #[test]
    fn interpolating_spline_reproduces_cubic_free_of_end_effects_for_a_line() {
        // A natural spline reproduces a straight line exactly (second derivative zero).
        let x: Vec<f64> = (0..10)
            .map(|i| i as f64 * 0.3 + 0.01 * (i * i) as f64)
            .collect();
        let y: Vec<f64> = x.iter().map(|v| 2.0 * v - 1.0).collect();
        for alpha in [0.0, 1e-2] {
            let c = smoothing_spline(&x, &y, alpha);
            for (i, s) in c.iter().enumerate() {
                assert!((s[0] - y[i]).abs() < 1e-12);
                assert!((s[1] - 2.0).abs() < 1e-12);
                assert!(s[2].abs() < 1e-12 && s[3].abs() < 1e-12);
            }
        }
    }
}

//! The choice of a creep-force law and its settings, as one value:
//! [`CreepLawSpec`]. Model files (through serde, feature `serde`), `umsim
//! creep` and `umsim bench --creep` (through [`FromStr`] and [`Display`]) and
//! the runtime's wheel–rail element all describe a law with it, and
//! [`CreepLawSpec::build`] is the one place that turns it into a [`CreepLaw`].
//!
//! The spec is generic over the type `N` of its real-valued settings (Mueller's
//! exponent, Polach's `k_A`, `k_S` and friction decrease), so that a model file
//! can give them as expressions over its parameters: the model language keeps a
//! `CreepLawSpec<Expr>` and resolves it with [`CreepLawSpec::map`] or
//! [`CreepLawSpec::try_map`] into a `CreepLawSpec<f64>`. Counts (strips,
//! elements, Gauss nodes) are plain integers.
//!
//! The syntax is documented on [`CreepLawSpec`].

use std::fmt::{self, Display};
use std::str::FromStr;

use super::{
    CreepError, CreepLaw, Fastsim, FastsimA, FastsimSa, INTEGRATED_NODES, KalkerLinear,
    MUELLER_EXPONENT, Mueller, MuellerKalkerSaturated, Polach, STRIP_THEORY_STRIPS, SlidingZone,
    StripTheory,
};

/// Default number of strips of FastSim_A when a command line leaves it out
/// (`fastsim-a`); also the model files' default law
/// ([`CreepLawSpec::default`]).
pub const FASTSIM_A_STRIPS: usize = 20;

/// Default number of strips and of elements per strip of FASTSIM when a
/// command line leaves them out (`fastsim`: 10 × 10).
pub const FASTSIM_DIVISIONS: usize = 10;

/// A creep-force law and its settings; `N` is the type of the real-valued
/// settings (`f64` to [`build`](CreepLawSpec::build) the law; an expression
/// type in model files).
///
/// # Command-line syntax
///
/// `LAW[:SETTING,SETTING…]`, each setting `key=value` with the keys of the
/// model files; the first setting may be a bare value for the law's main one:
///
/// | text | law |
/// |---|---|
/// | `kalker` | [`KalkerLinear`] |
/// | `mueller`, `mueller:3`, `mueller:exponent=3` | [`Mueller`] (Pogorelov 2005, Sect. 4.2), exponent default [`MUELLER_EXPONENT`] |
/// | `mueller-kalker-saturated[:EXPONENT]` | [`MuellerKalkerSaturated`], exponent default [`MUELLER_EXPONENT`] |
/// | `fastsim`, `fastsim:20` (20 × 20), `fastsim:nx=20,ny=10` | [`Fastsim`], `nx` elements per strip, `ny` strips, default [`FASTSIM_DIVISIONS`] each |
/// | `fastsim-sa`, `fastsim-sa:20` (20 × 20), `fastsim-sa:nx=20,ny=10` | [`FastsimSa`], `nx` FASTSIM elements per strip (in the sliding zone), `ny` strips, default [`FASTSIM_DIVISIONS`] each |
/// | `fastsim-a`, `fastsim-a:20`, `fastsim-a:strips=20,sliding=integrated,nodes=8` | [`FastsimA`], default [`FASTSIM_A_STRIPS`] strips, sliding `continuation` (default), `integrated` or `picard` with `nodes` Gauss nodes (default [`INTEGRATED_NODES`]) |
/// | `fastsim-a-integrated[:STRIPS]` | `fastsim-a:strips=STRIPS,sliding=integrated` |
/// | `polach`, `polach:ka=0.5,ks=0.3,friction_decrease=0.4/0.6` | [`Polach`], `ka`, `ks` default 1, `friction_decrease` = `A/B` (B in s/m) optional |
/// | `strip`, `strip:20`, `strip:strips=20` | [`StripTheory`], default [`STRIP_THEORY_STRIPS`] strips |
///
/// [`Display`] writes every setting as `key=value` (for example
/// `fastsim-a:strips=20,sliding=continuation`), which [`FromStr`] reads back
/// to the same spec.
///
/// # Model-file syntax (RON, feature `serde`)
///
/// ```text
/// Kalker | Mueller(exponent: 2) | MuellerKalkerSaturated(exponent: 2)
/// Fastsim(nx: 10, ny: 10) | FastsimSa(nx: 10, ny: 10)
/// FastsimA(strips: 20, sliding: Continuation)      // or Integrated(nodes: 8), Picard(nodes: 8)
/// Polach(ka: 1.0, ks: 1.0, friction_decrease: (0.4, 0.6))
/// Strip(strips: 20)
/// ```
///
/// The Mueller laws' exponent, `FastsimA`'s sliding and all of `Polach`'s settings
/// may be left out (their defaults as above); `Fastsim`'s and `FastsimSa`'s `nx`, `ny` and
/// `FastsimA`'s `strips` must be given.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(
        rename = "CreepLaw",
        bound(
            serialize = "N: serde::Serialize",
            deserialize = "N: serde::Deserialize<'de> + From<f64>"
        )
    )
)]
pub enum CreepLawSpec<N = f64> {
    /// Kalker's linear theory, no saturation ([`KalkerLinear`]).
    Kalker,
    /// Mueller's method as Pogorelov 2005, Sect. 4.2 gives it ([`Mueller`]):
    /// empirical load-dependent slope, pure sliding at the flange contact of
    /// a two-point contact.
    Mueller {
        /// Exponent `m` of the saturation, – (> 0; default [`MUELLER_EXPONENT`]).
        #[cfg_attr(feature = "serde", serde(default = "serde_impl::mueller_exponent"))]
        exponent: N,
    },
    /// Kalker's linear forces saturated towards `μN`
    /// ([`MuellerKalkerSaturated`]; this project's `Mueller` before the
    /// paper's law came).
    MuellerKalkerSaturated {
        /// Exponent `n` of the saturation, – (> 0; default [`MUELLER_EXPONENT`]).
        #[cfg_attr(feature = "serde", serde(default = "serde_impl::mueller_exponent"))]
        exponent: N,
    },
    /// Kalker's FASTSIM ([`Fastsim`]) in its strip layout, parabolic bound.
    Fastsim {
        /// Elements per strip, in the rolling direction (≥ 1).
        nx: usize,
        /// Strips across the ellipse (≥ 1).
        ny: usize,
    },
    /// FastSim_SA ([`FastsimSa`]): analytic adhesion zone, FASTSIM's
    /// elements in the sliding zone.
    FastsimSa {
        /// FASTSIM elements per strip, in the rolling direction (≥ 1); the
        /// sliding zone gets elements no longer than `2a_y/nx`.
        nx: usize,
        /// Strips across the ellipse (≥ 1).
        ny: usize,
    },
    /// Pogorelov's semi-analytic FastSim_A ([`FastsimA`]).
    FastsimA {
        /// Strips across the ellipse (≥ 1).
        strips: usize,
        /// Treatment of the sliding zones (default [`SlidingZone::Continuation`]).
        #[cfg_attr(feature = "serde", serde(default))]
        sliding: SlidingZone,
    },
    /// Polach's method ([`Polach`]): 1999 with `ka = ks = 1` and no friction
    /// decrease, else its 2005 extension.
    Polach {
        /// Reduction factor `k_A` in the area of adhesion, in (0, 1] (default 1).
        #[cfg_attr(feature = "serde", serde(default = "serde_impl::one"))]
        ka: N,
        /// Reduction factor `k_S` in the area of slip, in (0, 1] (default 1).
        #[cfg_attr(feature = "serde", serde(default = "serde_impl::one"))]
        ks: N,
        /// Friction decrease `μ = μ0[(1 − A)e^(−B w) + A]` as `(A, B)`: `A`
        /// (–, ≥ 0) and `B` (s/m, ≥ 0); `None`: constant friction. Written as
        /// a bare pair in model files.
        #[cfg_attr(
            feature = "serde",
            serde(
                default,
                skip_serializing_if = "Option::is_none",
                serialize_with = "serde_impl::ser_pair",
                deserialize_with = "serde_impl::de_pair"
            )
        )]
        friction_decrease: Option<(N, N)>,
    },
    /// Strip theory calibrated to Kalker's linear theory, spin through
    /// FASTSIM's flexibility ([`StripTheory`], FaStrip-like).
    Strip {
        /// Strips across the ellipse (≥ 1).
        strips: usize,
    },
}

impl<N> Default for CreepLawSpec<N> {
    /// FastSim_A with [`FASTSIM_A_STRIPS`] strips and the continuation
    /// sliding zone: the law of a model file's wheel–rail element that names
    /// none.
    fn default() -> Self {
        Self::FastsimA {
            strips: FASTSIM_A_STRIPS,
            sliding: SlidingZone::Continuation,
        }
    }
}

impl<N> CreepLawSpec<N> {
    /// The law's short name, as on the command line (`kalker`, `mueller`,
    /// `mueller-kalker-saturated`, `fastsim`, `fastsim-a`, `polach`).
    pub fn name(&self) -> &'static str {
        match self {
            Self::Kalker => "kalker",
            Self::Mueller { .. } => "mueller",
            Self::MuellerKalkerSaturated { .. } => "mueller-kalker-saturated",
            Self::Fastsim { .. } => "fastsim",
            Self::FastsimSa { .. } => "fastsim-sa",
            Self::FastsimA { .. } => "fastsim-a",
            Self::Polach { .. } => "polach",
            Self::Strip { .. } => "strip",
        }
    }

    /// The same law with every real-valued setting converted by `f`, called
    /// with the setting's key (`exponent`, `ka`, `ks`, `friction_decrease.A`,
    /// `friction_decrease.B`) and value.
    pub fn map<M>(&self, mut f: impl FnMut(&'static str, &N) -> M) -> CreepLawSpec<M> {
        match self.try_map(|key, v| Ok::<M, std::convert::Infallible>(f(key, v))) {
            Ok(s) => s,
            Err(never) => match never {},
        }
    }

    /// As [`map`](Self::map) with a fallible conversion: the first error is
    /// returned.
    pub fn try_map<M, E>(
        &self,
        mut f: impl FnMut(&'static str, &N) -> Result<M, E>,
    ) -> Result<CreepLawSpec<M>, E> {
        Ok(match self {
            Self::Kalker => CreepLawSpec::Kalker,
            Self::Mueller { exponent } => CreepLawSpec::Mueller {
                exponent: f("exponent", exponent)?,
            },
            Self::MuellerKalkerSaturated { exponent } => CreepLawSpec::MuellerKalkerSaturated {
                exponent: f("exponent", exponent)?,
            },
            Self::Fastsim { nx, ny } => CreepLawSpec::Fastsim { nx: *nx, ny: *ny },
            Self::FastsimSa { nx, ny } => CreepLawSpec::FastsimSa { nx: *nx, ny: *ny },
            Self::FastsimA { strips, sliding } => CreepLawSpec::FastsimA {
                strips: *strips,
                sliding: *sliding,
            },
            Self::Polach {
                ka,
                ks,
                friction_decrease,
            } => CreepLawSpec::Polach {
                ka: f("ka", ka)?,
                ks: f("ks", ks)?,
                friction_decrease: match friction_decrease {
                    Some((a, b)) => {
                        Some((f("friction_decrease.A", a)?, f("friction_decrease.B", b)?))
                    }
                    None => None,
                },
            },
            Self::Strip { strips } => CreepLawSpec::Strip { strips: *strips },
        })
    }

    /// Calls `f` on every real-valued setting (key as in [`map`](Self::map)),
    /// mutably: to rewrite expressions in place.
    pub fn for_each_value_mut(&mut self, mut f: impl FnMut(&'static str, &mut N)) {
        match self {
            Self::Kalker
            | Self::Fastsim { .. }
            | Self::FastsimSa { .. }
            | Self::FastsimA { .. }
            | Self::Strip { .. } => {}
            Self::Mueller { exponent } | Self::MuellerKalkerSaturated { exponent } => {
                f("exponent", exponent)
            }
            Self::Polach {
                ka,
                ks,
                friction_decrease,
            } => {
                f("ka", ka);
                f("ks", ks);
                if let Some((a, b)) = friction_decrease {
                    f("friction_decrease.A", a);
                    f("friction_decrease.B", b);
                }
            }
        }
    }
}

impl CreepLawSpec<f64> {
    /// Mueller's law with the default exponent [`MUELLER_EXPONENT`].
    pub fn mueller() -> Self {
        Self::Mueller {
            exponent: MUELLER_EXPONENT,
        }
    }

    /// FASTSIM with [`FASTSIM_DIVISIONS`] × [`FASTSIM_DIVISIONS`] elements.
    pub fn fastsim() -> Self {
        Self::Fastsim {
            nx: FASTSIM_DIVISIONS,
            ny: FASTSIM_DIVISIONS,
        }
    }

    /// Polach's 1999 law: `k_A = k_S = 1`, constant friction.
    pub fn polach() -> Self {
        Self::Polach {
            ka: 1.0,
            ks: 1.0,
            friction_decrease: None,
        }
    }

    /// Every law with its default settings, once each (FastSim_A with both
    /// its continuation and integrated sliding zones), FASTSIM first (the
    /// reference of `umsim creep --compare`'s differences when it is given
    /// no laws).
    pub fn every_law() -> Vec<Self> {
        vec![
            Self::fastsim(),
            Self::Kalker,
            Self::mueller(),
            Self::MuellerKalkerSaturated {
                exponent: MUELLER_EXPONENT,
            },
            Self::FastsimSa {
                nx: FASTSIM_DIVISIONS,
                ny: FASTSIM_DIVISIONS,
            },
            Self::default(),
            Self::FastsimA {
                strips: FASTSIM_A_STRIPS,
                sliding: SlidingZone::Integrated {
                    nodes: INTEGRATED_NODES,
                },
            },
            Self::polach(),
            Self::Strip {
                strips: STRIP_THEORY_STRIPS,
            },
        ]
    }

    /// The law, after checking every setting (an error names the setting
    /// and its valid range). Polach's friction decrease is set up at speed 0;
    /// the caller passes the rolling speed to
    /// [`CreepLaw::forces_at_speed`].
    pub fn build(&self) -> Result<Box<dyn CreepLaw + Send + Sync>, CreepError> {
        Ok(match *self {
            Self::Kalker => Box::new(KalkerLinear),
            Self::Mueller { exponent } => Box::new(Mueller::new(exponent)?),
            Self::MuellerKalkerSaturated { exponent } => {
                Box::new(MuellerKalkerSaturated::new(exponent)?)
            }
            Self::Fastsim { nx, ny } => Box::new(Fastsim::new(ny, nx)?),
            Self::FastsimSa { nx, ny } => Box::new(FastsimSa::new(ny, nx)?),
            Self::FastsimA { strips, sliding } => {
                Box::new(FastsimA::new(strips)?.with_sliding(sliding)?)
            }
            Self::Polach {
                ka,
                ks,
                friction_decrease,
            } => {
                let mut p = Polach::new().with_reduction(ka, ks)?;
                if let Some((a, b)) = friction_decrease {
                    p = p.with_falling_friction(a, b, 0.0)?;
                }
                Box::new(p)
            }
            Self::Strip { strips } => Box::new(StripTheory::new(strips)?),
        })
    }

    /// Checks every setting as [`build`](Self::build) does, without keeping
    /// the law.
    pub fn validate(&self) -> Result<(), CreepError> {
        self.build().map(|_| ())
    }
}

impl<N: Display> Display for CreepLawSpec<N> {
    /// The command-line text with every setting spelled out, e.g.
    /// `fastsim-a:strips=20,sliding=integrated,nodes=8`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())?;
        match self {
            Self::Kalker => Ok(()),
            Self::Mueller { exponent } | Self::MuellerKalkerSaturated { exponent } => {
                write!(f, ":exponent={exponent}")
            }
            Self::Fastsim { nx, ny } | Self::FastsimSa { nx, ny } => {
                write!(f, ":nx={nx},ny={ny}")
            }
            Self::Strip { strips } => write!(f, ":strips={strips}"),
            Self::FastsimA { strips, sliding } => {
                write!(f, ":strips={strips},sliding=")?;
                match sliding {
                    SlidingZone::Continuation => f.write_str("continuation"),
                    SlidingZone::Integrated { nodes } => write!(f, "integrated,nodes={nodes}"),
                    SlidingZone::Picard { nodes } => write!(f, "picard,nodes={nodes}"),
                }
            }
            Self::Polach {
                ka,
                ks,
                friction_decrease,
            } => {
                write!(f, ":ka={ka},ks={ks}")?;
                if let Some((a, b)) = friction_decrease {
                    write!(f, ",friction_decrease={a}/{b}")?;
                }
                Ok(())
            }
        }
    }
}

/// A creep-law text that [`CreepLawSpec`]'s [`FromStr`] cannot read: the
/// message says what is wrong and what is expected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("creep law \"{text}\": {message}")]
pub struct ParseCreepLawError {
    /// The text as given.
    pub text: String,
    /// What is wrong with it.
    pub message: String,
}

/// The syntax, for error messages and command-line help.
pub const CREEP_LAW_SYNTAX: &str = "kalker | mueller[:EXPONENT] | \
     mueller-kalker-saturated[:EXPONENT] | fastsim[:N] | \
     fastsim:nx=NX,ny=NY | fastsim-sa[:N] | fastsim-sa:nx=NX,ny=NY | fastsim-a[:STRIPS][,sliding=continuation|integrated|picard][,nodes=K] | \
     fastsim-a-integrated[:STRIPS] | polach[:ka=KA,ks=KS,friction_decrease=A/B] | strip[:STRIPS]";

/// One `key=value` (or bare `value`, key `None`) of a creep-law text.
struct Setting<'a> {
    key: Option<&'a str>,
    value: &'a str,
}

impl FromStr for CreepLawSpec<f64> {
    type Err = ParseCreepLawError;

    /// Reads the command-line syntax of [`CreepLawSpec`];
    /// the settings are checked as [`build`](Self::build) checks them.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let fail = |message: String| ParseCreepLawError {
            text: text.to_string(),
            message,
        };
        let (name, rest) = match text.trim().split_once(':') {
            Some((n, r)) => (n.trim(), Some(r)),
            None => (text.trim(), None),
        };
        let mut settings = Vec::new();
        if let Some(rest) = rest {
            for (k, part) in rest.split(',').enumerate() {
                let part = part.trim();
                let s = match part.split_once('=') {
                    Some((key, value)) => Setting {
                        key: Some(key.trim()),
                        value: value.trim(),
                    },
                    None if k == 0 => Setting {
                        key: None,
                        value: part,
                    },
                    None => {
                        return Err(fail(format!(
                            "\"{part}\" is not key=value (only the first setting may be a bare value)"
                        )));
                    }
                };
                if s.value.is_empty() {
                    return Err(fail(format!("empty value in \"{part}\"")));
                }
                settings.push(s);
            }
        }
        // (key, the key a bare value stands for): the keys each law accepts.
        let (keys, bare): (&[&str], Option<&str>) = match name {
            "kalker" => (&[], None),
            "mueller" | "mueller-kalker-saturated" => (&["exponent"], Some("exponent")),
            "fastsim" | "fastsim-sa" => (&["nx", "ny"], Some("nx,ny")),
            "fastsim-a" | "fastsim-a-integrated" => {
                (&["strips", "sliding", "nodes"], Some("strips"))
            }
            "polach" => (&["ka", "ks", "friction_decrease"], None),
            "strip" => (&["strips"], Some("strips")),
            _ => {
                return Err(fail(format!(
                    "unknown law \"{name}\"; expected {CREEP_LAW_SYNTAX}"
                )));
            }
        };
        let mut values: Vec<(&str, &str)> = Vec::new();
        for s in &settings {
            let ks: Vec<&str> = match (s.key, bare) {
                (Some(k), _) => vec![k],
                (None, Some(b)) => b.split(',').collect(),
                (None, None) => {
                    return Err(fail(format!(
                        "{name} takes no bare value; use key=value with keys {}",
                        keys.join(", ")
                    )));
                }
            };
            for k in ks {
                if !keys.contains(&k) {
                    return Err(fail(if keys.is_empty() {
                        format!("{name} has no settings")
                    } else {
                        format!(
                            "{name} has no setting \"{k}\" (its settings: {})",
                            keys.join(", ")
                        )
                    }));
                }
                if values.iter().any(|(key, _)| *key == k) {
                    return Err(fail(format!("\"{k}\" is given twice")));
                }
                values.push((k, s.value));
            }
        }
        let get = |key: &str| values.iter().find(|(k, _)| *k == key).map(|(_, v)| *v);
        let count =
            |key: &str, default: usize| -> Result<usize, ParseCreepLawError> {
                match get(key) {
                    None => Ok(default),
                    Some(v) => v.parse::<usize>().ok().filter(|&n| n > 0).ok_or_else(|| {
                        fail(format!("{key}: \"{v}\" is not a positive whole number"))
                    }),
                }
            };
        let real = |key: &str, v: &str| -> Result<f64, ParseCreepLawError> {
            v.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| fail(format!("{key}: \"{v}\" is not a finite number")))
        };
        let spec = match name {
            "kalker" => Self::Kalker,
            "mueller" | "mueller-kalker-saturated" => {
                let exponent = match get("exponent") {
                    Some(v) => real("exponent", v)?,
                    None => MUELLER_EXPONENT,
                };
                if name == "mueller" {
                    Self::Mueller { exponent }
                } else {
                    Self::MuellerKalkerSaturated { exponent }
                }
            }
            "fastsim" => Self::Fastsim {
                nx: count("nx", FASTSIM_DIVISIONS)?,
                ny: count("ny", FASTSIM_DIVISIONS)?,
            },
            "fastsim-sa" => Self::FastsimSa {
                nx: count("nx", FASTSIM_DIVISIONS)?,
                ny: count("ny", FASTSIM_DIVISIONS)?,
            },
            "fastsim-a" | "fastsim-a-integrated" => {
                let strips = count("strips", FASTSIM_A_STRIPS)?;
                let nodes = count("nodes", INTEGRATED_NODES)?;
                let default = if name == "fastsim-a" {
                    "continuation"
                } else {
                    "integrated"
                };
                let sliding = match get("sliding").unwrap_or(default) {
                    "continuation" if get("nodes").is_some() => {
                        return Err(fail(
                            "nodes applies to sliding=integrated or sliding=picard only".into(),
                        ));
                    }
                    "continuation" => SlidingZone::Continuation,
                    "integrated" => SlidingZone::Integrated { nodes },
                    "picard" => SlidingZone::Picard { nodes },
                    other => {
                        return Err(fail(format!(
                            "sliding: \"{other}\" is not continuation, integrated or picard"
                        )));
                    }
                };
                if name == "fastsim-a-integrated" && sliding != (SlidingZone::Integrated { nodes })
                {
                    return Err(fail(
                        "fastsim-a-integrated has integrated sliding zones; use fastsim-a:sliding=…"
                            .into(),
                    ));
                }
                Self::FastsimA { strips, sliding }
            }
            "strip" => Self::Strip {
                strips: count("strips", STRIP_THEORY_STRIPS)?,
            },
            _ => {
                let ka = get("ka").map_or(Ok(1.0), |v| real("ka", v))?;
                let ks = get("ks").map_or(Ok(1.0), |v| real("ks", v))?;
                let friction_decrease = match get("friction_decrease") {
                    None => None,
                    Some(v) => {
                        let (a, b) = v.split_once('/').ok_or_else(|| {
                            fail(format!(
                                "friction_decrease: \"{v}\" is not A/B (for example 0.4/0.6)"
                            ))
                        })?;
                        Some((
                            real("friction_decrease.A", a.trim())?,
                            real("friction_decrease.B", b.trim())?,
                        ))
                    }
                };
                Self::Polach {
                    ka,
                    ks,
                    friction_decrease,
                }
            }
        };
        spec.validate().map_err(|e| fail(e.to_string()))?;
        Ok(spec)
    }
}

/// The serde helpers of the model-file syntax.
#[cfg(feature = "serde")]
mod serde_impl {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub(super) fn mueller_exponent<N: From<f64>>() -> N {
        N::from(super::MUELLER_EXPONENT)
    }

    pub(super) fn one<N: From<f64>>() -> N {
        N::from(1.0)
    }

    /// `friction_decrease: (A, B)` without `Some`.
    pub(super) fn de_pair<'de, D: Deserializer<'de>, N: Deserialize<'de>>(
        d: D,
    ) -> Result<Option<(N, N)>, D::Error> {
        <(N, N)>::deserialize(d).map(Some)
    }

    /// Written only when present (`skip_serializing_if`), as the bare pair.
    pub(super) fn ser_pair<S: Serializer, N: Serialize>(
        v: &Option<(N, N)>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        match v {
            Some(pair) => pair.serialize(s),
            None => s.serialize_none(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> CreepLawSpec {
        text.parse().unwrap_or_else(|e| panic!("{text}: {e}"))
    }

    #[test]
    fn short_forms_and_defaults() {
        assert_eq!(parse("kalker"), CreepLawSpec::Kalker);
        assert_eq!(parse("mueller"), CreepLawSpec::mueller());
        assert_eq!(parse("mueller:3"), CreepLawSpec::Mueller { exponent: 3.0 });
        assert_eq!(
            parse("mueller-kalker-saturated:exponent=3"),
            CreepLawSpec::MuellerKalkerSaturated { exponent: 3.0 }
        );
        assert_eq!(parse("fastsim"), CreepLawSpec::fastsim());
        assert_eq!(
            parse("fastsim:20"),
            CreepLawSpec::Fastsim { nx: 20, ny: 20 }
        );
        assert_eq!(
            parse("fastsim:ny=5"),
            CreepLawSpec::Fastsim { nx: 10, ny: 5 }
        );
        assert_eq!(
            parse("fastsim-sa:20"),
            CreepLawSpec::FastsimSa { nx: 20, ny: 20 }
        );
        assert_eq!(
            parse("fastsim-sa:ny=5"),
            CreepLawSpec::FastsimSa { nx: 10, ny: 5 }
        );
        assert_eq!(parse("fastsim-a"), CreepLawSpec::default());
        assert_eq!(
            parse("fastsim-a:12"),
            CreepLawSpec::FastsimA {
                strips: 12,
                sliding: SlidingZone::Continuation
            }
        );
        assert_eq!(
            parse("fastsim-a-integrated"),
            CreepLawSpec::FastsimA {
                strips: FASTSIM_A_STRIPS,
                sliding: SlidingZone::Integrated {
                    nodes: INTEGRATED_NODES
                }
            }
        );
        assert_eq!(
            parse("fastsim-a-integrated:10"),
            parse("fastsim-a:10,sliding=integrated")
        );
        assert_eq!(
            parse(" fastsim-a : strips = 10 , sliding = picard , nodes = 4 "),
            CreepLawSpec::FastsimA {
                strips: 10,
                sliding: SlidingZone::Picard { nodes: 4 }
            }
        );
        assert_eq!(parse("polach"), CreepLawSpec::polach());
        assert_eq!(
            parse("polach:ks=0.5,friction_decrease=0.4/0.6"),
            CreepLawSpec::Polach {
                ka: 1.0,
                ks: 0.5,
                friction_decrease: Some((0.4, 0.6))
            }
        );
    }

    #[test]
    fn display_round_trips() {
        for spec in [
            CreepLawSpec::Kalker,
            CreepLawSpec::mueller(),
            CreepLawSpec::Mueller { exponent: 2.5 },
            CreepLawSpec::MuellerKalkerSaturated { exponent: 2.0 },
            CreepLawSpec::fastsim(),
            CreepLawSpec::Fastsim { nx: 40, ny: 7 },
            CreepLawSpec::FastsimSa { nx: 40, ny: 7 },
            CreepLawSpec::default(),
            CreepLawSpec::FastsimA {
                strips: 3,
                sliding: SlidingZone::Integrated { nodes: 16 },
            },
            CreepLawSpec::FastsimA {
                strips: 30,
                sliding: SlidingZone::Picard { nodes: 1 },
            },
            CreepLawSpec::polach(),
            CreepLawSpec::Polach {
                ka: 0.7,
                ks: 0.1 + 0.2,
                friction_decrease: Some((0.44, 0.6)),
            },
        ] {
            let text = spec.to_string();
            assert_eq!(parse(&text), spec, "{text}");
        }
        assert_eq!(
            CreepLawSpec::<f64>::default().to_string(),
            "fastsim-a:strips=20,sliding=continuation"
        );
        assert_eq!(
            CreepLawSpec::Polach {
                ka: 1.0,
                ks: 0.5,
                friction_decrease: Some((0.4, 0.6))
            }
            .to_string(),
            "polach:ka=1,ks=0.5,friction_decrease=0.4/0.6"
        );
    }

    #[test]
    fn errors_say_what_is_wrong() {
        for (text, expected) in [
            ("stribeck", "unknown law \"stribeck\""),
            ("kalker:3", "kalker takes no bare value"),
            ("kalker:n=3", "kalker has no settings"),
            ("fastsim:0", "nx: \"0\" is not a positive whole number"),
            ("fastsim:x", "is not a positive whole number"),
            ("fastsim:nx=4,nx=5", "\"nx\" is given twice"),
            ("fastsim:nx=4,8", "is not key=value"),
            (
                "fastsim-a:strips=10,sliding=exact",
                "\"exact\" is not continuation",
            ),
            ("fastsim-a:nodes=4", "nodes applies to sliding=integrated"),
            ("fastsim-a:sliding=integrated,nodes=33", "1..=32"),
            (
                "fastsim-a-integrated:sliding=picard",
                "fastsim-a-integrated has integrated",
            ),
            ("fastsim-a:layers=3", "fastsim-a has no setting \"layers\""),
            ("mueller:-1", "Mueller exponent must be positive"),
            ("mueller:exponent=", "empty value"),
            ("mueller:inf", "not a finite number"),
            ("polach:0.5", "polach takes no bare value"),
            ("polach:ka=1.5", "k_A = 1.5"),
            ("polach:friction_decrease=0.4", "is not A/B"),
            ("polach:friction_decrease=-0.4/1", "A = μ∞/μ0 = -0.4"),
        ] {
            let e = text.parse::<CreepLawSpec>().unwrap_err().to_string();
            assert!(e.contains(expected), "{text}: {e}");
            assert!(e.starts_with(&format!("creep law \"{text}\"")), "{e}");
        }
    }

    /// `every_law` names every law once (a new law must be added there).
    #[test]
    fn every_law_is_listed() {
        let names: Vec<&str> = CreepLawSpec::every_law().iter().map(|s| s.name()).collect();
        for spec in CreepLawSpec::every_law() {
            // Exhaustive: a new variant fails to compile here until listed.
            match spec {
                CreepLawSpec::Kalker
                | CreepLawSpec::Mueller { .. }
                | CreepLawSpec::MuellerKalkerSaturated { .. }
                | CreepLawSpec::Fastsim { .. }
                | CreepLawSpec::FastsimSa { .. }
                | CreepLawSpec::FastsimA { .. }
                | CreepLawSpec::Polach { .. }
                | CreepLawSpec::Strip { .. } => {}
            }
        }
        for name in [
            "kalker",
            "mueller",
            "mueller-kalker-saturated",
            "fastsim",
            "fastsim-sa",
            "fastsim-a",
            "polach",
            "strip",
        ] {
            assert!(names.contains(&name), "{name}");
        }
    }

    #[test]
    fn build_uses_the_settings() {
        assert_eq!(
            parse("fastsim-a-integrated").build().unwrap().name(),
            "fastsim-a"
        );
        assert_eq!(CreepLawSpec::fastsim().build().unwrap().name(), "fastsim");
        assert!(CreepLawSpec::Fastsim { nx: 0, ny: 3 }.build().is_err());
        assert!(
            CreepLawSpec::FastsimA {
                strips: 0,
                sliding: SlidingZone::Continuation
            }
            .validate()
            .is_err()
        );
        assert!(CreepLawSpec::Mueller { exponent: 0.0 }.validate().is_err());
        assert!(
            CreepLawSpec::Polach {
                ka: 1.0,
                ks: 1.0,
                friction_decrease: Some((0.5, f64::NAN))
            }
            .validate()
            .is_err()
        );
    }

    #[test]
    fn map_visits_every_value_with_its_key() {
        let spec: CreepLawSpec<&str> = CreepLawSpec::Polach {
            ka: "ka0",
            ks: "1",
            friction_decrease: Some(("a", "b")),
        };
        let mut keys = Vec::new();
        let mapped = spec.map(|k, v| {
            keys.push(k);
            v.len()
        });
        assert_eq!(
            keys,
            ["ka", "ks", "friction_decrease.A", "friction_decrease.B"]
        );
        assert_eq!(
            mapped,
            CreepLawSpec::Polach {
                ka: 3,
                ks: 1,
                friction_decrease: Some((1, 1))
            }
        );
        let failed: Result<CreepLawSpec<f64>, String> =
            spec.try_map(|k, v| v.parse().map_err(|_| k.to_string()));
        assert_eq!(failed.unwrap_err(), "ka");
        let mut m = CreepLawSpec::Mueller { exponent: 1.0 };
        m.for_each_value_mut(|_, v| *v *= 3.0);
        assert_eq!(m, CreepLawSpec::Mueller { exponent: 3.0 });
    }

    #[cfg(feature = "serde")]
    #[test]
    fn model_file_syntax() {
        let read = |text: &str| -> CreepLawSpec {
            ron::from_str(text).unwrap_or_else(|e| panic!("{text}: {e}"))
        };
        assert_eq!(read("Kalker"), CreepLawSpec::Kalker);
        assert_eq!(read("Mueller()"), CreepLawSpec::mueller());
        assert_eq!(
            read("Mueller(exponent: 3)"),
            CreepLawSpec::Mueller { exponent: 3.0 }
        );
        assert_eq!(
            read("MuellerKalkerSaturated()"),
            parse("mueller-kalker-saturated")
        );
        assert_eq!(
            read("Fastsim(nx: 10, ny: 20)"),
            CreepLawSpec::Fastsim { nx: 10, ny: 20 }
        );
        assert_eq!(
            read("FastsimSa(nx: 30, ny: 20)"),
            CreepLawSpec::FastsimSa { nx: 30, ny: 20 }
        );
        assert_eq!(read("FastsimA(strips: 20)"), CreepLawSpec::default());
        assert_eq!(
            read("FastsimA(strips: 20, sliding: Integrated(nodes: 8))"),
            parse("fastsim-a-integrated")
        );
        assert_eq!(
            read("FastsimA(strips: 5, sliding: Picard(nodes: 2))"),
            parse("fastsim-a:5,sliding=picard,nodes=2")
        );
        assert_eq!(read("Polach()"), CreepLawSpec::polach());
        assert_eq!(
            read("Polach(ka: 1.0, ks: 0.5, friction_decrease: (0.4, 0.6))"),
            parse("polach:ks=0.5,friction_decrease=0.4/0.6")
        );
        assert!(ron::from_str::<CreepLawSpec>("Fastsim(nx: 10)").is_err());
        for spec in [
            CreepLawSpec::polach(),
            parse("polach:ka=0.3,friction_decrease=0.4/0.6"),
            parse("fastsim-a:sliding=integrated"),
            CreepLawSpec::mueller(),
        ] {
            let text = ron::to_string(&spec).unwrap();
            assert_eq!(read(&text), spec, "{text}");
        }
    }
}

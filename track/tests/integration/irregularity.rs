//! Irregularities: dips, sinusoids, widening, CSV, PSD generator.
#![allow(clippy::needless_range_loop)] // index loops mirror the vector formulas

use std::path::PathBuf;

use railmbs_track::psd::{FRA_A_A, FRA_K, FRA_OMEGA_C, SplitMix64, psd};
use railmbs_track::{
    Component, Dip, DipShape, GaugeWidening, Irregularities, Irregularity, MeasuredIrregularity,
    PsdModel, Rail, Sinusoid, StochasticIrregularity, StochasticSpec, TrackError,
};

#[test]
fn linear_dip_depth_and_extent() {
    let d = Dip::new(Rail::Left, 100.0, 10.0, 0.02, DipShape::Linear).unwrap();
    let irr = Irregularities::new().with(Irregularity::Dip(d));
    let dev = |s: f64| irr.deviation(s).unwrap();
    for s in [99.999, 100.0, 110.0, 110.001, 0.0, 500.0] {
        assert!(
            dev(s).left_vertical.abs() < 1e-15,
            "zero at/outside the ends, s = {s}"
        );
    }
    assert!(
        (dev(105.0).left_vertical + 0.02).abs() < 1e-15,
        "full depth at mid-length"
    );
    // Linear ramps: half depth at quarter and three-quarter length.
    assert!((dev(102.5).left_vertical + 0.01).abs() < 1e-15);
    assert!((dev(107.5).left_vertical + 0.01).abs() < 1e-15);
    assert!((dev(101.0).left_vertical + 0.004).abs() < 1e-15);
    // Only the left rail, only vertically.
    let x = dev(105.0);
    assert_eq!(
        (x.right_vertical, x.left_lateral, x.right_lateral),
        (0.0, 0.0, 0.0)
    );
    assert!((x.cross_level() + 0.02).abs() < 1e-15 && (x.level() + 0.01).abs() < 1e-15);
    // Slope ∓ 2d/L.
    let (_, r) = irr.deviation_and_rate(101.0).unwrap();
    assert!((r.left_vertical + 0.004).abs() < 1e-15);
    let (_, r) = irr.deviation_and_rate(108.0).unwrap();
    assert!((r.left_vertical - 0.004).abs() < 1e-15);
}

#[test]
fn cosine_dip_shape() {
    let d = Dip::new(Rail::Both, 0.0, 8.0, 0.01, DipShape::Cosine).unwrap();
    assert!((d.vertical(4.0).0 + 0.01).abs() < 1e-15);
    assert!((d.vertical(2.0).0 + 0.005).abs() < 1e-15);
    assert!(d.vertical(0.0).1.abs() < 1e-18 && d.vertical(8.0).1.abs() < 1e-17);
    // Derivative against a central difference (error h²/6·d·(2π/L)³ < 1e-12).
    let h = 1e-5;
    let fd = (d.vertical(3.0 + h).0 - d.vertical(3.0 - h).0) / (2.0 * h);
    assert!((d.vertical(3.0).1 - fd).abs() < 1e-9);
    assert!(Dip::new(Rail::Left, 0.0, 0.0, 0.01, DipShape::Linear).is_err());
}

#[test]
fn sinusoids_and_widening_map_to_the_rails() {
    let a = 0.003;
    let irr = Irregularities::new()
        .with(Irregularity::Sinusoid(
            Sinusoid::new(Component::Gauge, 20.0, a, 10.0, 110.0).unwrap(),
        ))
        .with(Irregularity::Sinusoid(
            Sinusoid::new(Component::Lateral, 40.0, a, 10.0, 110.0).unwrap(),
        ))
        .with(Irregularity::Sinusoid(
            Sinusoid::new(Component::CrossLevel, 25.0, a, 10.0, 110.0).unwrap(),
        ))
        .with(Irregularity::GaugeWidening(
            GaugeWidening::new(200.0, 10.0, 0.0254).unwrap(),
        ));
    let s = 10.0 + 5.0; // quarter wave of the gauge sinusoid
    let x = irr.deviation(s).unwrap();
    assert!((x.gauge() - a).abs() < 1e-15);
    assert!((x.alignment() - a * (2.0 * std::f64::consts::PI * 5.0 / 40.0).sin()).abs() < 1e-15);
    assert!((x.cross_level() - a * (2.0 * std::f64::consts::PI * 5.0 / 25.0).sin()).abs() < 1e-15);
    assert_eq!(x.level(), 0.0);
    assert_eq!(irr.deviation(5.0).unwrap(), Default::default());
    assert_eq!(irr.deviation(150.0).unwrap(), Default::default());
    // Widening: ramp then constant, split between the rails.
    assert!((irr.deviation(205.0).unwrap().gauge() - 0.0127).abs() < 1e-15);
    let w = irr.deviation(300.0).unwrap();
    assert!((w.gauge() - 0.0254).abs() < 1e-15 && w.alignment().abs() < 1e-18);
    assert!((w.left_lateral - 0.0127).abs() < 1e-15);
    let c = GaugeWidening::constant(0.0254).unwrap();
    let irr = Irregularities::new().with(Irregularity::GaugeWidening(c));
    assert!((irr.deviation(0.0).unwrap().gauge() - 0.0254).abs() < 1e-15);
    assert!(Sinusoid::new(Component::Lateral, 10.0, 0.01, 5.0, 5.0).is_err());
    assert!(irr.deviation(f64::NAN).is_err());
}

fn temp_csv(name: &str, text: &str) -> PathBuf {
    let p = std::env::temp_dir().join(format!("railmbs_track_{}_{name}.csv", std::process::id()));
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn measured_csv_reads_and_interpolates() {
    let p = temp_csv(
        "good",
        "# measured\ns,left_lateral,left_vertical,right_lateral,right_vertical\n\
         0, 0, 0, 0, 0\n10, 0.002, -0.004, 0.001, 0\n20, 0, 0, 0, 0.003\n",
    );
    let m = MeasuredIrregularity::from_csv(&p).unwrap();
    std::fs::remove_file(&p).ok();
    assert_eq!(m.range(), (0.0, 20.0));
    let irr = Irregularities::new().with(Irregularity::Measured(m));
    let x = irr.deviation(5.0).unwrap();
    assert!((x.left_lateral - 0.001).abs() < 1e-16 && (x.left_vertical + 0.002).abs() < 1e-16);
    let x = irr.deviation(15.0).unwrap();
    assert!((x.right_vertical - 0.0015).abs() < 1e-16);
    assert_eq!(irr.deviation(25.0).unwrap(), Default::default());
    // Columns in another order are fine.
    let p = temp_csv(
        "order",
        "right_vertical,s,left_lateral,left_vertical,right_lateral\n1,0,0,0,0\n3,2,0,0,0\n",
    );
    let m = MeasuredIrregularity::from_csv(&p).unwrap();
    std::fs::remove_file(&p).ok();
    let irr = Irregularities::new().with(Irregularity::Measured(m));
    assert!((irr.deviation(1.0).unwrap().right_vertical - 2.0).abs() < 1e-15);
}

#[test]
fn measured_csv_errors_name_file_and_row() {
    let cases = [
        (
            "missing",
            "s,left_lateral,left_vertical,right_lateral\n0,0,0,0\n",
            1,
            "right_vertical",
        ),
        (
            "nan",
            "s,left_lateral,left_vertical,right_lateral,right_vertical\n0,0,0,0,0\n1,0,x,0,0\n",
            3,
            "left_vertical",
        ),
        (
            "order",
            "s,left_lateral,left_vertical,right_lateral,right_vertical\n0,0,0,0,0\n2,0,0,0,0\n1,0,0,0,0\n",
            4,
            "not greater",
        ),
        (
            "short",
            "s,left_lateral,left_vertical,right_lateral,right_vertical\n0,0,0,0,0\n",
            1,
            "at least two",
        ),
        (
            "fields",
            "s,left_lateral,left_vertical,right_lateral,right_vertical\n0,0,0,0,0\n1,0,0\n",
            3,
            "",
        ),
        (
            "inf",
            "s,left_lateral,left_vertical,right_lateral,right_vertical\n0,0,0,0,0\n1,inf,0,0,0\n",
            3,
            "not finite",
        ),
    ];
    for (name, text, row, needle) in cases {
        let p = temp_csv(name, text);
        let e = MeasuredIrregularity::from_csv(&p).unwrap_err();
        std::fs::remove_file(&p).ok();
        match &e {
            TrackError::Csv {
                file,
                row: r,
                message,
            } => {
                assert_eq!(file, &p, "{name}");
                assert_eq!(*r, row, "{name}: {e}");
                assert!(message.contains(needle), "{name}: {e}");
            }
            other => panic!("{name}: unexpected {other}"),
        }
        assert!(e.to_string().contains(&p.display().to_string()));
    }
    let e = MeasuredIrregularity::from_csv("/nonexistent/track.csv").unwrap_err();
    assert!(matches!(e, TrackError::Io { .. }) && e.to_string().contains("/nonexistent/track.csv"));
}

/// ∫ S dΩ of the ERRI level/alignment PSD in closed form (partial fractions):
/// S = A Ωc²/(Ωc²−Ωr²)·[1/(Ω²+Ωr²) − 1/(Ω²+Ωc²)].
fn erri_integral(a: f64, o1: f64, o2: f64) -> f64 {
    let (c, r) = (0.8246f64, 0.0206f64);
    let f = |o: f64| a * c * c / (c * c - r * r) * ((o / r).atan() / r - (o / c).atan() / c);
    f(o2) - f(o1)
}

/// ∫ S dΩ of the FRA PSD: k A Ωc²/(Ω²(Ω²+Ωc²)) = k A [1/Ω² − 1/(Ω²+Ωc²)].
fn fra_integral(a_cm2: f64, o1: f64, o2: f64) -> f64 {
    let c = FRA_OMEGA_C;
    let f = |o: f64| FRA_K * a_cm2 * 1e-4 * (-1.0 / o - (o / c).atan() / c);
    f(o2) - f(o1)
}

fn spec(
    model: PsdModel,
    component: Component,
    lmin: f64,
    lmax: f64,
    n: usize,
    seed: u64,
) -> StochasticSpec {
    StochasticSpec {
        model,
        component,
        wavelength_min: lmin,
        wavelength_max: lmax,
        harmonics: n,
        seed,
        start: -1e7,
        end: 1e7,
        fade: 0.0,
    }
}

#[test]
fn psd_formula_reproduces_published_table_values() {
    // GENSYS TRC_IPSD documentation tabulates ORE B176 high level per cyclic
    // wavenumber f (m²/(1/m)): lateral 2.3194e-4 at 50 m, 6.1608e-6 at 10 m;
    // vertical 4.0897e-4 at 50 m, 1.0863e-5 at 10 m. S_f = 2π S_Ω.
    let tp = 2.0 * std::f64::consts::PI;
    for (c, lambda, value) in [
        (Component::Lateral, 50.0, 2.3194e-4),
        (Component::Lateral, 10.0, 6.1608e-6),
        (Component::Vertical, 50.0, 4.0897e-4),
        (Component::Vertical, 10.0, 1.0863e-5),
    ] {
        let s = tp * psd(PsdModel::ErriHigh, c, tp / lambda).unwrap();
        // Table values have 5 digits: 1e-4 relative.
        assert!(
            (s / value - 1.0).abs() < 1.5e-4,
            "{c:?} {lambda}: {s} vs {value}"
        );
    }
    assert!(psd(PsdModel::ErriLow, Component::Gauge, 1.0).is_err());
    assert!(psd(PsdModel::Fra(7), Component::Vertical, 1.0).is_err());
    assert!(psd(PsdModel::Fra(3), Component::Vertical, 0.0).is_err());
}

#[test]
fn generated_variance_over_one_period_equals_the_psd_integral() {
    // λ 2–102 m, N = 1025: Ω1/ΔΩ = N λmin/(λmax − λmin) = 20.5, so every
    // Ω_k = (21 + k) ΔΩ is a multiple of ΔΩ and the realization has period
    // P = 2π/ΔΩ. On Ns = 4096 equally spaced samples over one period every
    // cross term cos((Ω_j ± Ω_k)s + …) has an integer frequency 0 < m < Ns and
    // sums to zero exactly, so the sample mean square equals Σ a_k²/2 up to
    // rounding; that equals ∫S over the band up to the per-bin quadrature error
    // (< 1e-10 relative). Tolerance 1e-9 relative.
    for (model, comp, exact) in [
        (PsdModel::ErriLow, Component::Vertical, None),
        (PsdModel::ErriHigh, Component::Lateral, None),
        (PsdModel::Fra(4), Component::Lateral, Some(FRA_A_A[3])),
    ] {
        let g = StochasticIrregularity::generate(&spec(model, comp, 2.0, 102.0, 1025, 7)).unwrap();
        let (om, _, _) = g.harmonics();
        let d = om[1] - om[0];
        assert!((om[0] / d - 21.0).abs() < 1e-9);
        let period = 2.0 * std::f64::consts::PI / d;
        let ns = 4096;
        let ms: f64 = (0..ns)
            .map(|i| g.signal(i as f64 * period / ns as f64).0.powi(2))
            .sum::<f64>()
            / ns as f64;
        let (o1, o2) = (2.0 * std::f64::consts::PI / 102.0, std::f64::consts::PI);
        let integral = match (model, exact) {
            (PsdModel::Fra(_), Some(a)) => fra_integral(a, o1, o2),
            (PsdModel::ErriLow, _) => erri_integral(5.9233e-7, o1, o2),
            _ => erri_integral(6.125e-7, o1, o2),
        };
        assert!(
            (ms / integral - 1.0).abs() < 1e-9,
            "{model:?}: {ms} vs {integral}"
        );
        assert!((g.variance() / integral - 1.0).abs() < 1e-10);
    }
}

#[test]
fn generated_variance_on_an_arbitrary_window_is_within_statistical_tolerance() {
    // A window that is not a period: the sample mean square differs from ∫S by
    // the window means of the cross terms. With independent uniform phases each
    // term a_j a_k cos(ω s + ψ) contributes a zero-mean error of variance
    // (a_j a_k)² |M(ω)|²/2, M(ω) the window mean of e^{iωs} (computed exactly
    // for the sample grid); the terms are uncorrelated, so σ² is their sum.
    // Tolerance 5σ (a false failure chance below 1e-6 for a Gaussian error).
    let g = StochasticIrregularity::generate(&spec(
        PsdModel::ErriHigh,
        Component::Vertical,
        3.0,
        150.0,
        600,
        2024,
    ))
    .unwrap();
    let (om, a, _) = g.harmonics();
    let (s0, ds, ns) = (1234.5, 0.5, 12_000usize);
    let ms: f64 = (0..ns)
        .map(|i| g.signal(s0 + i as f64 * ds).0.powi(2))
        .sum::<f64>()
        / ns as f64;
    let m2 = |w: f64| -> f64 {
        let x = 0.5 * w * ds;
        let den = ns as f64 * x.sin();
        if den.abs() < 1e-300 {
            1.0
        } else {
            ((ns as f64 * x).sin() / den).powi(2)
        }
    };
    let mut var = 0.0;
    for j in 0..om.len() {
        var += (a[j].powi(4) / 4.0) * m2(2.0 * om[j]) / 2.0;
        for k in (j + 1)..om.len() {
            var += (a[j] * a[k]).powi(2) * (m2(om[j] - om[k]) + m2(om[j] + om[k])) / 2.0;
        }
    }
    let sigma = var.sqrt();
    let integral = erri_integral(
        1.08e-6,
        2.0 * std::f64::consts::PI / 150.0,
        2.0 * std::f64::consts::PI / 3.0,
    );
    assert!(
        sigma < 0.05 * integral,
        "the test is meaningful: σ = {sigma}, ∫S = {integral}"
    );
    assert!(
        (ms - integral).abs() < 5.0 * sigma,
        "{ms} vs {integral} ± 5·{sigma}"
    );
}

#[test]
fn seeds_reproduce_and_differ() {
    let make = |seed| {
        StochasticIrregularity::generate(&spec(
            PsdModel::Fra(5),
            Component::Vertical,
            1.0,
            60.0,
            300,
            seed,
        ))
        .unwrap()
    };
    let (a, b, c) = (make(11), make(11), make(12));
    for s in [0.0, 17.3, 250.0] {
        assert_eq!(a.signal(s), b.signal(s));
    }
    assert_ne!(a.signal(17.3), c.signal(17.3));
    assert_ne!(a.harmonics().2, c.harmonics().2);
    // Splitmix64 reference output for seed 0 (Vigna's splitmix64.c):
    // 0xE220A8397B1DCDAF, 0x6E789E6AA1B965F4.
    let mut r = SplitMix64::new(0);
    assert_eq!(r.next_u64(), 0xE220_A839_7B1D_CDAF);
    assert_eq!(r.next_u64(), 0x6E78_9E6A_A1B9_65F4);
}

#[test]
fn fade_sampling_and_derivative() {
    let mut sp = spec(PsdModel::ErriLow, Component::Lateral, 3.0, 100.0, 200, 3);
    sp.start = 0.0;
    sp.end = 400.0;
    sp.fade = 20.0;
    let g = StochasticIrregularity::generate(&sp).unwrap();
    let irr = Irregularities::new().with(Irregularity::Stochastic(g.clone()));
    assert_eq!(irr.deviation(0.0).unwrap().alignment(), 0.0);
    assert!(irr.deviation(400.0).unwrap().alignment().abs() < 1e-15);
    let mid = irr.deviation(200.0).unwrap();
    assert_eq!(mid.left_lateral, g.signal(200.0).0);
    // d/ds against a central difference, inside a fade (second derivative
    // bounded by Σ a Ω² ≈ 1e-3 1/m: error < 1e-12 with h = 1e-5).
    for s in [10.0, 200.0, 390.0] {
        let h = 1e-5;
        let fd = (irr.deviation(s + h).unwrap().alignment()
            - irr.deviation(s - h).unwrap().alignment())
            / (2.0 * h);
        let (_, r) = irr.deviation_and_rate(s).unwrap();
        assert!(
            (r.alignment() - fd).abs() < 1e-8,
            "{s}: {} vs {fd}",
            r.alignment()
        );
    }
    // Sampled table: interpolation error ≤ (π ds/λmin)²/2 · Σ a at ds = 0.05 m.
    let t = g.sampled(0.05).unwrap();
    let tab = Irregularities::new().with(Irregularity::Measured(t));
    let bound =
        (std::f64::consts::PI * 0.05 / 3.0).powi(2) / 2.0 * g.harmonics().1.iter().sum::<f64>();
    for i in 0..400 {
        let s = 0.013 + i as f64 * 0.997;
        let d = tab.deviation(s).unwrap().alignment() - irr.deviation(s).unwrap().alignment();
        assert!(d.abs() <= bound, "{s}: {d} > {bound}");
    }
    // Bad specs.
    let mut bad = sp;
    bad.wavelength_min = 200.0;
    assert!(StochasticIrregularity::generate(&bad).is_err());
    let mut bad = sp;
    bad.component = Component::Gauge;
    assert!(StochasticIrregularity::generate(&bad).is_err());
    let mut bad = sp;
    bad.harmonics = 0;
    assert!(StochasticIrregularity::generate(&bad).is_err());
}

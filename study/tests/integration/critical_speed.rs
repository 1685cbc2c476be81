//! The critical-speed criterion on a signal whose answer is known by hand.

use railmbs_runtime::run::{OutputSink, Table};
use railmbs_study::{Cell, Reduction, ReductionKind, reduce_table};

#[test]
fn the_critical_speed_is_the_speed_of_the_last_row_whose_amplitude_reaches_the_threshold() {
    // A run decelerating from 60 m/s at 2 m/s²; the lateral column
    // alternates ±1 mm every row (0.01 s) up to t = 4.99 s, then is 0.
    let mut table = Table::new();
    let header = ["time", "s[m]", "v[m/s]", "y"].map(String::from);
    table.begin(&header).unwrap();
    for k in 0..=1000 {
        let t = k as f64 * 0.01;
        let v = 60.0 - 2.0 * t;
        let y = if t < 4.995 {
            1e-3 * if k % 2 == 0 { 1.0 } else { -1.0 }
        } else {
            0.0
        };
        table.row(&[t, 60.0 * t - t * t, v, y]).unwrap();
    }
    let reduction = |window: f64| {
        Reduction::new(
            ReductionKind::CriticalSpeed {
                column: "y".into(),
                amplitude: 2e-4,
                window,
            },
            None,
        )
    };
    // With a 1.005 s window the amplitude (half the range over the window)
    // is at least 0.5 mm while the window holds the row at t = 4.99 s: up
    // to the row at t = 5.99 s (≤ 4.99 + 1.005), where v = 60 − 2·5.99.
    // (Windows ending between rows keep rounding out of the answer.)
    let cells = reduce_table(&[reduction(1.005)], &table, &[]).unwrap();
    let Cell::Num(v) = cells[0] else {
        panic!("{cells:?}")
    };
    assert!((v - (60.0 - 2.0 * 5.99)).abs() < 1e-9, "{v}");
    // A window of 0.505 s: up to t = 5.49 s.
    let cells = reduce_table(&[reduction(0.505)], &table, &[]).unwrap();
    let Cell::Num(v) = cells[0] else {
        panic!("{cells:?}")
    };
    assert!((v - (60.0 - 2.0 * 5.49)).abs() < 1e-9, "{v}");
    // A threshold above the amplitude: no limit cycle, no critical speed.
    let high = Reduction::new(
        ReductionKind::CriticalSpeed {
            column: "y".into(),
            amplitude: 2e-3,
            window: 1.0,
        },
        None,
    );
    assert_eq!(reduce_table(&[high], &table, &[]).unwrap(), [Cell::Empty]);
}

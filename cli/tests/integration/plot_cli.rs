//! `umsim plot` end to end: SVG and PNG files from a small results CSV, column
//! wildcards, x ranges, gaps, and the error messages.

use crate::common::umsim;
use std::path::{Path, PathBuf};

const HEADER: &str = "time,s[m],body.y[m],Bogie1.WS1.contact.L.Y/Q [-],\
                      Bogie1.WS2.contact.L.Y/Q [-],Bogie1.WS1.contact.R.Y/Q [-],\
                      const[N],gappy[m]";

/// A results CSV like `umsim run` writes: 101 rows over 1 s at 20 m/s, with a
/// constant column and a NaN in the middle of `gappy[m]`.
fn results(dir: &Path) -> PathBuf {
    let mut text = format!("{HEADER}\n");
    for i in 0..=100 {
        let t = f64::from(i) * 0.01;
        let gappy = if i == 50 { f64::NAN } else { 1.0 + t };
        text += &format!(
            "{t},{},{},{},{},{},5,{gappy}\n",
            20.0 * t,
            0.003 * (6.0 * t).sin(),
            0.3 * (9.0 * t).sin(),
            0.25 * (9.0 * t).cos(),
            -0.2 * t,
        );
    }
    let path = dir.join("results.csv");
    std::fs::write(&path, text).unwrap();
    path
}

fn ok(args: &[&str]) {
    let out = umsim(args);
    assert!(
        out.status.success(),
        "umsim {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Runs `umsim` expecting a failure; returns its standard error.
fn fails(args: &[&str]) -> String {
    let out = umsim(args);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!out.status.success(), "umsim {args:?} should fail");
    assert!(!err.contains("panicked"), "umsim {args:?} panicked: {err}");
    err
}

/// The contents of the SVG's `<text>` elements, XML entities decoded.
fn texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .map(|t| {
            let body = &t[t.find('>').unwrap() + 1..t.find("</text>").unwrap()];
            body.trim()
                .replace("&lt;", "<")
                .replace("&gt;", ">")
                .replace("&quot;", "\"")
                .replace("&apos;", "'")
                .replace("&amp;", "&")
        })
        .collect()
}

/// Point counts of the polylines drawn in `colour` (hex, as in the SVG) with
/// more than two points (legend samples have two).
fn lines(svg: &str, colour: &str) -> Vec<usize> {
    svg.split("<polyline")
        .skip(1)
        .filter(|p| p[..p.find("/>").unwrap()].contains(&format!("stroke=\"{colour}\"")))
        .map(|p| {
            let start = p.find("points=\"").unwrap() + 8;
            let end = start + p[start..].find('"').unwrap();
            p[start..end].split_whitespace().count()
        })
        .filter(|&n| n > 2)
        .collect()
}

const BLUE: &str = "#1F77B4";
const ORANGE: &str = "#FF7F0E";

#[test]
fn svg_has_legend_axis_labels_and_expanded_wildcards() {
    let dir = tempfile::tempdir().unwrap();
    let csv = results(dir.path());
    let svg = dir.path().join("plot.svg");
    ok(&[
        "plot",
        csv.to_str().unwrap(),
        "--y",
        "body.y[m]",
        "--y",
        "Bogie1.*.contact.L.Y/Q [-]",
        "--title",
        "Run <1> & more",
        "-o",
        svg.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg"), "{}", &text[..100]);
    let t = texts(&text);
    let count = |s: &str| t.iter().filter(|x| *x == s).count();
    // Title, x label, y label of each panel (the pattern as written) and legends.
    assert_eq!(count("Run <1> & more"), 1, "{t:?}");
    assert_eq!(count("time"), 1, "{t:?}");
    assert_eq!(count("body.y[m]"), 2, "y label and legend: {t:?}");
    assert_eq!(count("Bogie1.*.contact.L.Y/Q [-]"), 1, "{t:?}");
    assert_eq!(count("Bogie1.WS1.contact.L.Y/Q [-]"), 1, "{t:?}");
    assert_eq!(count("Bogie1.WS2.contact.L.Y/Q [-]"), 1, "{t:?}");
    assert_eq!(count("Bogie1.WS1.contact.R.Y/Q [-]"), 0, "{t:?}");
    // One line of 101 points per series; the panel's second series is orange.
    assert_eq!(lines(&text, BLUE), vec![101, 101]);
    assert_eq!(lines(&text, ORANGE), vec![101]);
}

#[test]
fn distance_axis_range_and_gaps() {
    let dir = tempfile::tempdir().unwrap();
    let csv = results(dir.path());
    let svg = dir.path().join("gaps.svg");
    ok(&[
        "plot",
        csv.to_str().unwrap(),
        "--x",
        "s[m]",
        "--from",
        "3.9",
        "--to",
        "16.1",
        "--y",
        "gappy[m],Bogie1.WS1.contact.R.Y/Q [-]",
        "-o",
        svg.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&svg).unwrap();
    let t = texts(&text);
    assert!(t.iter().any(|x| x == "s[m]"), "{t:?}");
    assert!(!t.iter().any(|x| x == "time"), "{t:?}");
    // Several short names: the label lists them as given.
    assert!(
        t.iter()
            .any(|x| x == "gappy[m], Bogie1.WS1.contact.R.Y/Q [-]"),
        "{t:?}"
    );
    assert!(t.iter().any(|x| x == "gappy[m]"), "{t:?}");
    // s = 3.9 … 16.1 m is t = 0.195 … 0.805 s: rows 20 … 80; the NaN of row 50 splits
    // gappy into rows 20 … 49 and 51 … 80 instead of dropping to zero.
    assert_eq!(lines(&text, BLUE), vec![30, 30]);
    assert_eq!(lines(&text, ORANGE), vec![61]);
    // The x ticks lie within the range.
    assert!(t.iter().any(|x| x == "10"), "{t:?}");
    assert!(!t.iter().any(|x| x == "20"), "{t:?}");
}

#[test]
fn constant_series_gets_a_range() {
    let dir = tempfile::tempdir().unwrap();
    let csv = results(dir.path());
    let svg = dir.path().join("const.svg");
    ok(&[
        "plot",
        csv.to_str().unwrap(),
        "--y",
        "const[N]",
        "-o",
        svg.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&svg).unwrap();
    let t = texts(&text);
    // ±10 % around 5 N, so ticks below and above 5.
    let ticks: Vec<f64> = t.iter().filter_map(|x| x.parse().ok()).collect();
    assert!(ticks.iter().any(|&v| v > 4.0 && v < 5.0), "{t:?}");
    assert!(ticks.iter().any(|&v| v > 5.0 && v < 6.0), "{t:?}");
    assert_eq!(lines(&text, BLUE), vec![101]);
}

fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    (be(&bytes[16..20]), be(&bytes[20..24]))
}

#[test]
fn png_of_the_requested_size() {
    let dir = tempfile::tempdir().unwrap();
    let csv = results(dir.path());
    let png = dir.path().join("plot.png");
    ok(&[
        "plot",
        csv.to_str().unwrap(),
        "--y",
        "body.y[m]",
        "--y",
        "Bogie1.*.Y/Q [-]",
        "--title",
        "PNG",
        "--width",
        "640",
        "--height",
        "480",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(png_size(&png), (640, 480));
    // Default size: 1000 wide, 60 + 280 per panel high; the extension's case
    // does not matter.
    let png = dir.path().join("default.PNG");
    ok(&[
        "plot",
        csv.to_str().unwrap(),
        "--y",
        "const[N]",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(png_size(&png), (1000, 340));
}

#[test]
fn errors_are_clear() {
    let dir = tempfile::tempdir().unwrap();
    let csv = results(dir.path());
    let csv = csv.to_str().unwrap();
    let out = dir.path().join("x.svg");
    let out = out.to_str().unwrap();

    let missing = dir.path().join("nope.csv");
    let e = fails(&["plot", missing.to_str().unwrap(), "--y", "a", "-o", out]);
    assert!(e.contains("cannot open") && e.contains("nope.csv"), "{e}");

    let e = fails(&["plot", csv, "--y", "body.Y[m]", "-o", out]);
    assert!(e.contains("unknown column \"body.Y[m]\""), "{e}");
    assert!(e.contains("\"body.y[m]\""), "close names: {e}");

    let e = fails(&[
        "plot",
        csv,
        "--y",
        "body.y[m]",
        "--x",
        "distance",
        "-o",
        out,
    ]);
    assert!(e.contains("unknown column \"distance\""), "{e}");

    let e = fails(&["plot", csv, "--y", "Bogie2.*.Y/Q [-]", "-o", out]);
    assert!(e.contains("\"Bogie2.*.Y/Q [-]\" matches no column"), "{e}");
    assert!(
        e.contains("Bogie1.WS1.contact.L.Y/Q [-]"),
        "close names: {e}"
    );

    let e = fails(&["plot", csv, "--y", "body.y[m]", "--from", "100", "-o", out]);
    assert!(e.contains("no data with time in [100, inf]"), "{e}");
    assert!(e.contains("0 … 1"), "the file's span: {e}");

    let e = fails(&[
        "plot",
        csv,
        "--y",
        "body.y[m]",
        "--from",
        "2",
        "--to",
        "1",
        "-o",
        out,
    ]);
    assert!(e.contains("--from 2 is beyond --to 1"), "{e}");

    let pdf = dir.path().join("x.pdf");
    let e = fails(&["plot", csv, "--y", "body.y[m]", "-o", pdf.to_str().unwrap()]);
    assert!(e.contains("unsupported output extension \".pdf\""), "{e}");
    assert!(!pdf.exists());

    let e = fails(&["plot", csv, "--y", "body.y[m],", "-o", out]);
    assert!(e.contains("empty column name"), "{e}");

    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "time,a[m],b[m]\n0,1,2\n0.1,1,2\n0.2,1,oops\n").unwrap();
    let bad = bad.to_str().unwrap();
    let e = fails(&["plot", bad, "--y", "a[m],b[m]", "-o", out]);
    assert!(
        e.contains("row 3 (line 4), column \"b[m]\": \"oops\" is not a number"),
        "{e}"
    );
    // Columns not plotted are not read.
    ok(&["plot", bad, "--y", "a[m]", "-o", out]);

    let empty = dir.path().join("empty.csv");
    std::fs::write(&empty, "time,a[m]\n").unwrap();
    let e = fails(&["plot", empty.to_str().unwrap(), "--y", "a[m]", "-o", out]);
    assert!(e.contains("no data rows"), "{e}");

    let nowhere = dir.path().join("no/such/dir/plot.svg");
    let e = fails(&[
        "plot",
        csv,
        "--y",
        "body.y[m]",
        "-o",
        nowhere.to_str().unwrap(),
    ]);
    assert!(e.contains("cannot write") && e.contains("plot.svg"), "{e}");
}

#[test]
fn help_documents_the_subcommand() {
    let out = umsim(&["--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(
        help.contains("Plot output columns against time or distance (SVG or PNG)"),
        "{help}"
    );
    let out = umsim(&["plot", "--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    for word in [
        "--y", "--x", "--from", "--to", "--title", "--output", "wildcard", "s[m]",
    ] {
        assert!(help.contains(word), "{word} in {help}");
    }
}

/// The pixels of `colour` in a PNG: (column, row) of each.
fn pixels_of(path: &Path, colour: [u8; 3]) -> Vec<(u32, u32)> {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    let mut out = Vec::new();
    for row in 0..info.height {
        for col in 0..info.width {
            let i = (row * info.width + col) as usize * channels;
            if buf[i..i + 3] == colour {
                out.push((col, row));
            }
        }
    }
    out
}

#[test]
fn png_lines_stay_inside_their_panel_where_the_data_turns_back_sharply() {
    // 20 000 rows on 600 px (thinned to each pixel column's first, lowest,
    // highest and last point) of a smooth wave with one-row spikes, as the
    // wheel forces of a vehicle run in a switch: thick lines with mitred
    // joints (how plotters' bitmap backend draws a path) shoot far out of the
    // panel where the thinned line turns back sharply.
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("time,zig[m]\n");
    for i in 0..20_000 {
        let t = f64::from(i) * 1e-4;
        let spike = if i % 997 == 0 {
            -0.8
        } else if i % 1499 == 0 {
            0.8
        } else {
            0.0
        };
        text += &format!("{t},{}\n", 0.2 * (20.0 * t).sin() + spike);
    }
    let csv = dir.path().join("zig.csv");
    std::fs::write(&csv, text).unwrap();
    let png = dir.path().join("zig.png");
    ok(&[
        "plot",
        csv.to_str().unwrap(),
        "--y",
        "zig[m]",
        "--width",
        "600",
        "--height",
        "300",
        "-o",
        png.to_str().unwrap(),
    ]);
    let blue = pixels_of(&png, [31, 119, 180]);
    assert!(!blue.is_empty(), "the series is drawn");
    // The panel: 8 px top margin, 40 px x-axis area at the bottom; the data
    // (±1 with 5 % padding) lies inside, the line's 1 px half-width beyond
    // it at most.
    let (top, bottom) = (8, 300 - 40);
    let rows = (
        blue.iter().map(|p| p.1).min().unwrap(),
        blue.iter().map(|p| p.1).max().unwrap(),
    );
    assert!(
        rows.0 >= top && rows.1 <= bottom,
        "line rows {rows:?} outside {top}..={bottom}"
    );
}

#[test]
fn legends_go_where_they_hide_no_data() {
    use plotters::prelude::SeriesLabelPosition;
    use railmbs_cli::plot::place_legend;
    let (plot, legend) = ((800.0, 300.0), (200.0, 60.0));
    // A line along the top right: the legend goes to the upper left.
    let top_right = vec![vec![vec![(0.5, 0.95), (1.0, 0.95)]]];
    let (corner, y1) = place_legend(&top_right, (0.0, 1.0), (0.0, 1.0), plot, legend);
    assert_eq!(corner, SeriesLabelPosition::UpperLeft);
    assert_eq!(y1, 1.0);
    // A diagonal from lower left to upper right leaves the other two corners.
    let diagonal = vec![vec![vec![(0.0, 0.0), (1.0, 1.0)]]];
    let (corner, _) = place_legend(&diagonal, (0.0, 1.0), (0.0, 1.0), plot, legend);
    assert_eq!(corner, SeriesLabelPosition::UpperLeft);
    // Two horizontal lines near the top and the bottom (rows 30 and 270 of
    // 300) cover every corner: the y range grows until the data ends below
    // the legend (its height and a 5 px inset).
    let both = vec![
        vec![vec![(0.0, 0.9), (1.0, 0.9)]],
        vec![vec![(0.0, 0.1), (1.0, 0.1)]],
    ];
    let (corner, y1) = place_legend(&both, (0.0, 1.0), (0.0, 1.0), plot, legend);
    assert_eq!(corner, SeriesLabelPosition::UpperRight);
    let data_top_px = (y1 - 0.9) / y1 * plot.1;
    assert!(
        data_top_px >= legend.1 + 5.0,
        "data top at {data_top_px} px, y1 = {y1}"
    );
}

//! `umsim plot`: plot output columns of a results CSV against time or distance.
//!
//! ```text
//! umsim plot RESULTS.csv --y "COL[,COL…]" [--y …] [--x COLUMN] [--from X] [--to X]
//!            [--title T] [--width W] [--height H] -o plot.svg|plot.png
//! ```
//!
//! Reads a CSV written by `umsim run` (header `time`, then the output names with
//! their units in brackets, e.g. `body.y[m]` or `Bogie1.WS1.contact.L.Y/Q [-]`;
//! `s[m]`, the arc position along the track, on runs on a track). Each `--y`
//! is one panel; the panels are stacked with a shared x axis (`--x`, `time` by
//! default, `s[m]` for distance) restricted to `--from`…`--to`. A panel may
//! hold several comma-separated columns, one colour each, with a legend. A
//! column spec may use `*` for any characters (`Bogie1.*.contact.L.Y/Q [-]`);
//! it expands, in header order, to every matching column but the x column.
//! NaN and infinite cells are gaps in the lines. The format follows the
//! output's extension: `.svg` (text as SVG text) or `.png` (text drawn with the
//! embedded DejaVu Sans, so no system font library is needed).

use ab_glyph::{Font, ScaleFont};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{BackendColor, BackendCoord, BackendTextStyle, DrawingErrorKind};
use std::error::Error;
use std::path::{Path, PathBuf};

/// Arguments of `umsim plot`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:
  umsim plot out.csv --y 'body.y[m]' -o y.svg
  umsim plot out.csv --x 's[m]' --from 100 --to 400 \\
      --y 'Bogie1.*.contact.L.Y/Q [-]' --y 'body.y,Bogie1.WS1.ws.y' -o yq.png")]
pub struct Args {
    /// Results CSV written by `umsim run` (header: `time`, then names with units).
    pub input: PathBuf,
    /// Columns of one panel, comma-separated, names as in the header; `*` is a
    /// wildcard for any characters. Repeat for more panels, stacked top to bottom.
    #[arg(long = "y", value_name = "COL[,COL…]", required = true)]
    pub y: Vec<String>,
    /// Column of the horizontal axis, e.g. `s[m]` for the distance along the track.
    #[arg(long = "x", value_name = "COLUMN", default_value = "time")]
    pub x: String,
    /// Plot only rows with x ≥ this value (in the x column's unit: s for time, m for `s[m]`).
    #[arg(long, value_name = "X", allow_negative_numbers = true)]
    pub from: Option<f64>,
    /// Plot only rows with x ≤ this value (in the x column's unit).
    #[arg(long, value_name = "X", allow_negative_numbers = true)]
    pub to: Option<f64>,
    /// Title above the panels.
    #[arg(long)]
    pub title: Option<String>,
    /// Width of the picture in pixels.
    #[arg(long, value_name = "PIXELS", default_value_t = 1000)]
    pub width: u32,
    /// Height of the picture in pixels [default: 60 + 280 per panel, + 40 with a title].
    #[arg(long, value_name = "PIXELS")]
    pub height: Option<u32>,
    /// Output file: `.svg` or `.png`.
    #[arg(short = 'o', long, value_name = "FILE")]
    pub output: PathBuf,
}

/// Output format, chosen by the output file's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Scalable vector graphics.
    Svg,
    /// Portable network graphics.
    Png,
}

impl Format {
    /// The format for `path`'s extension (case-insensitive).
    pub fn of(path: &Path) -> Result<Format, String> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("svg") => Ok(Format::Svg),
            Some("png") => Ok(Format::Png),
            Some(e) => Err(format!(
                "unsupported output extension \".{e}\" of {} (use .svg or .png)",
                path.display()
            )),
            None => Err(format!(
                "output {} has no extension (use .svg or .png)",
                path.display()
            )),
        }
    }
}

/// One panel: its y-axis label and its columns (indices into the header).
#[derive(Debug, Clone, PartialEq)]
pub struct PanelSpec {
    /// Label of the y axis.
    pub label: String,
    /// Header indices of the panel's series, in order.
    pub columns: Vec<usize>,
}

/// A column-name pattern: `*` matches any (possibly empty) run of characters and
/// every other character matches itself (column names hold brackets and slashes,
/// `B1.WS1.contact.L.Y/Q [-]`, so they are escaped rather than read as glob syntax).
pub fn column_pattern(pattern: &str) -> globset::GlobMatcher {
    let escaped: Vec<String> = pattern.split('*').map(globset::escape).collect();
    globset::GlobBuilder::new(&escaped.join("*"))
        .literal_separator(false)
        .backslash_escape(false)
        .build()
        .expect("an escaped pattern is valid")
        .compile_matcher()
}

/// The fewest edits turning `piece` into some substring of `text`.
fn substring_distance(piece: &str, text: &str) -> usize {
    let t: Vec<char> = text.chars().collect();
    // Edit distance with free start and end in `text` (Sellers' algorithm).
    let mut row = vec![0usize; t.len() + 1];
    for (i, pc) in piece.chars().enumerate() {
        let mut diag = row[0];
        row[0] = i + 1;
        for (j, &tc) in t.iter().enumerate() {
            let up = row[j + 1];
            row[j + 1] = (diag + usize::from(pc != tc)).min(up + 1).min(row[j] + 1);
            diag = up;
        }
    }
    row.into_iter().min().unwrap_or(0)
}

/// Up to `max` header names close to `query` (a name or a `*` pattern), the
/// closest first: names holding the query (every literal part of a pattern)
/// to within a few edits, the nearest in length first.
pub fn close_names<'h>(header: &'h [String], query: &str, max: usize) -> Vec<&'h str> {
    let q = query.to_lowercase();
    let pieces: Vec<&str> = q.split('*').filter(|s| !s.is_empty()).collect();
    let letters: usize = pieces.iter().map(|p| p.chars().count()).sum();
    let limit = (letters / 4).max(1);
    let mut scored: Vec<(usize, usize, usize, &str)> = header
        .iter()
        .enumerate()
        .filter_map(|(k, h)| {
            let l = h.to_lowercase();
            let d = pieces.iter().map(|p| substring_distance(p, &l)).sum();
            let extra = l.chars().count().abs_diff(letters);
            (d <= limit).then_some((d, extra, k, h.as_str()))
        })
        .collect();
    scored.sort();
    scored.into_iter().take(max).map(|(.., h)| h).collect()
}

fn quoted_list(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ")
}

fn hint(header: &[String], query: &str) -> String {
    let close = close_names(header, query, 5);
    if close.is_empty() {
        let first: Vec<&str> = header.iter().take(5).map(String::as_str).collect();
        format!(
            "the {} columns begin with {}",
            header.len(),
            quoted_list(&first)
        )
    } else {
        format!("close names: {}", quoted_list(&close))
    }
}

/// Index of the column named exactly `name`, or an error naming close names.
pub fn find_column(header: &[String], name: &str, source: &str) -> Result<usize, String> {
    header.iter().position(|h| h == name).ok_or_else(|| {
        format!(
            "{source}: unknown column \"{name}\"; {}",
            hint(header, name)
        )
    })
}

/// Expands one `--y` value into a panel: comma-separated column names or `*`
/// patterns; a pattern expands in header order and never to the column `skip`
/// (the x axis). A column named twice is plotted once.
pub fn resolve_panel(
    header: &[String],
    spec: &str,
    skip: usize,
    source: &str,
) -> Result<PanelSpec, String> {
    let items: Vec<&str> = spec.split(',').map(str::trim).collect();
    let mut columns = Vec::new();
    for item in &items {
        if item.is_empty() {
            return Err(format!("--y \"{spec}\": empty column name"));
        }
        if item.contains('*') {
            let pattern = column_pattern(item);
            let found: Vec<usize> = (0..header.len())
                .filter(|&k| k != skip && pattern.is_match(&header[k]))
                .collect();
            if found.is_empty() {
                return Err(format!(
                    "{source}: the pattern \"{item}\" matches no column; {}",
                    hint(header, item)
                ));
            }
            columns.extend(found);
        } else {
            columns.push(find_column(header, item, source)?);
        }
    }
    let mut seen = std::collections::HashSet::new();
    columns.retain(|k| seen.insert(*k));
    let label = if items.len() == 1 {
        items[0].to_string()
    } else {
        let joined = items.join(", ");
        if joined.chars().count() <= 48 {
            joined
        } else {
            common_label(
                &columns
                    .iter()
                    .map(|&k| header[k].as_str())
                    .collect::<Vec<_>>(),
            )
        }
    };
    Ok(PanelSpec { label, columns })
}

/// The unit in brackets at the end of `name`, e.g. `[m]` of `body.y[m]`.
fn unit(name: &str) -> Option<&str> {
    let name = name.trim_end();
    if !name.ends_with(']') {
        return None;
    }
    name.rfind('[').map(|i| &name[i..])
}

/// A y label for several columns: their common last name parts (`Y/Q [-]` of
/// `WS1.contact.L.Y/Q [-]` and `WS1.contact.R.Y/Q [-]`), else their common
/// unit, else "(several units)".
fn common_label(names: &[&str]) -> String {
    let rev: Vec<Vec<char>> = names.iter().map(|n| n.chars().rev().collect()).collect();
    let mut n = 0;
    while rev.iter().all(|r| n < r.len() && r[n] == rev[0][n]) {
        n += 1;
    }
    let suffix: String = rev[0][..n].iter().rev().collect();
    // The suffix is a whole name part when every name has it whole or after a dot.
    let whole = rev.iter().all(|r| r.len() == n || r[n] == '.');
    let part = if whole {
        suffix.trim()
    } else {
        suffix.find('.').map_or("", |i| suffix[i + 1..].trim())
    };
    let units: Vec<Option<&str>> = names.iter().map(|n| unit(n)).collect();
    if !part.is_empty() && Some(part) != units[0] {
        part.to_string()
    } else if units.iter().all(|u| u.is_some() && *u == units[0]) {
        units[0].unwrap_or_default().to_string()
    } else {
        "(several units)".to_string()
    }
}

/// The data to plot: the x column and the panels' columns over the rows kept.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Values of the x column (finite), one per kept row.
    pub x: Vec<f64>,
    /// For each needed header index, its values on the kept rows (NaN for gaps).
    pub columns: std::collections::HashMap<usize, Vec<f64>>,
}

fn parse_cell(cell: &str, row: usize, line: u64, name: &str, source: &str) -> Result<f64, String> {
    cell.parse::<f64>().map_err(|_| {
        if cell.is_empty() {
            format!("{source}: row {row} (line {line}), column \"{name}\": empty cell")
        } else {
            format!(
                "{source}: row {row} (line {line}), column \"{name}\": \"{cell}\" is not a number"
            )
        }
    })
}

/// Reads the header of `input`, resolves the `--x` column and the panels, and
/// reads the needed columns of the rows whose x lies in `from..=to`. Rows with
/// a non-finite x are left out; other non-finite cells are kept as NaN gaps.
pub fn read_table<R: std::io::Read>(
    input: R,
    source: &str,
    x_name: &str,
    specs: &[String],
    from: Option<f64>,
    to: Option<f64>,
) -> Result<(Vec<String>, usize, Vec<PanelSpec>, Table), String> {
    let mut rd = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(input);
    let header: Vec<String> = rd
        .headers()
        .map_err(|e| format!("{source}: cannot read the header: {e}"))?
        .iter()
        .map(str::to_string)
        .collect();
    if header.iter().all(|h| h.is_empty()) {
        return Err(format!("{source}: empty file (no header)"));
    }
    let xi = find_column(&header, x_name, source)?;
    let panels = specs
        .iter()
        .map(|s| resolve_panel(&header, s, xi, source))
        .collect::<Result<Vec<_>, _>>()?;
    let mut needed: Vec<usize> = panels.iter().flat_map(|p| p.columns.clone()).collect();
    needed.sort_unstable();
    needed.dedup();
    needed.retain(|&k| k != xi);

    let mut table = Table {
        x: Vec::new(),
        columns: needed.iter().map(|&k| (k, Vec::new())).collect(),
    };
    let (mut rows, mut x_lo, mut x_hi) = (0usize, f64::INFINITY, f64::NEG_INFINITY);
    let mut record = csv::StringRecord::new();
    loop {
        match rd.read_record(&mut record) {
            Ok(true) => {}
            Ok(false) => break,
            Err(e) => return Err(format!("{source}: {e}")),
        }
        rows += 1;
        let line = record.position().map_or(0, |p| p.line());
        let x = parse_cell(&record[xi], rows, line, &header[xi], source)?;
        let mut values = Vec::with_capacity(needed.len());
        for &k in &needed {
            values.push(parse_cell(&record[k], rows, line, &header[k], source)?);
        }
        if !x.is_finite() {
            continue;
        }
        x_lo = x_lo.min(x);
        x_hi = x_hi.max(x);
        if from.is_some_and(|f| x < f) || to.is_some_and(|t| x > t) {
            continue;
        }
        table.x.push(x);
        for (&k, v) in needed.iter().zip(values) {
            table
                .columns
                .get_mut(&k)
                .expect("every needed column has a vector")
                .push(if v.is_finite() { v } else { f64::NAN });
        }
    }
    if table.x.is_empty() {
        return Err(if rows == 0 {
            format!("{source}: no data rows")
        } else if x_lo > x_hi {
            format!("{source}: no finite value in column \"{x_name}\"")
        } else {
            format!(
                "{source}: no data with {x_name} in [{}, {}]; the file spans {x_name} = {x_lo} … {x_hi}",
                from.map_or("-inf".to_string(), |f| f.to_string()),
                to.map_or("inf".to_string(), |t| t.to_string()),
            )
        });
    }
    Ok((header, xi, panels, table))
}

/// The largest axis bound: ranges stay finite (plotters loops on infinite ones).
const LIMIT: f64 = f64::MAX / 4.0;

/// An axis range holding `lo..hi` (within ±`LIMIT`) with a small margin; a
/// single value gets a range of ±10 % of it (±1 around zero).
pub fn padded_range(lo: f64, hi: f64) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) || lo > hi {
        return (-1.0, 1.0);
    }
    let (lo, hi) = (lo.max(-LIMIT), hi.min(LIMIT));
    let span = hi - lo;
    let scale = lo.abs().max(hi.abs());
    if span <= scale * 1e-12 {
        let mid = 0.5 * (lo + hi);
        let half = if mid == 0.0 { 1.0 } else { 0.1 * mid.abs() };
        return (mid - half, mid + half);
    }
    (lo - 0.05 * span, hi + 0.05 * span)
}

/// Finite minimum and maximum of `values`, if any.
fn finite_bounds<'a>(values: impl Iterator<Item = &'a f64>) -> Option<(f64, f64)> {
    values
        .filter(|v| v.is_finite())
        .fold(None, |acc, &v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
}

/// A tick-label formatter for an axis over `lo..hi` with about `n` labels.
fn tick_format(lo: f64, hi: f64, n: usize) -> impl Fn(&f64) -> String {
    let step = (hi - lo) / n.max(1) as f64;
    let mag = lo.abs().max(hi.abs());
    let scientific = mag >= 1e6 || (mag > 0.0 && mag < 1e-3);
    // plotters steps by 1, 2 or 5 × 10^k, at least `step`.
    let mut step_exp = step.log10().floor();
    if step / 10f64.powf(step_exp) > 5.0 {
        step_exp += 1.0;
    }
    let decimals = (-step_exp).clamp(0.0, 12.0) as usize;
    let digits = (mag.log10().floor() - step_exp).clamp(0.0, 8.0) as usize;
    move |v: &f64| {
        let v = if v.abs() < step * 1e-9 { 0.0 } else { *v };
        if v == 0.0 {
            "0".to_string()
        } else if scientific {
            format!("{v:.digits$e}")
        } else {
            format!("{v:.decimals$}")
        }
    }
}

const COLOURS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Runs of consecutive finite points, thinned to at most about four points
/// per horizontal pixel (first, lowest, highest and last of each pixel column).
fn segments(x: &[f64], y: &[f64], x0: f64, x1: f64, pixels: u32) -> Vec<Vec<(f64, f64)>> {
    let mut out = Vec::new();
    let mut current: Vec<usize> = Vec::new();
    let flush = |current: &mut Vec<usize>, out: &mut Vec<Vec<(f64, f64)>>| {
        if current.is_empty() {
            return;
        }
        let pts = if current.len() > 4 * pixels as usize {
            thin(x, y, current, x0, x1, pixels)
        } else {
            current.iter().map(|&i| (x[i], y[i])).collect()
        };
        out.push(pts);
        current.clear();
    };
    for (i, v) in y.iter().enumerate().take(x.len()) {
        if v.is_finite() {
            current.push(i);
        } else {
            flush(&mut current, &mut out);
        }
    }
    flush(&mut current, &mut out);
    out
}

fn thin(x: &[f64], y: &[f64], idx: &[usize], x0: f64, x1: f64, pixels: u32) -> Vec<(f64, f64)> {
    let width = (x1 - x0).max(f64::MIN_POSITIVE);
    let bucket = |i: usize| ((x[i] - x0) / width * f64::from(pixels)).floor() as i64;
    let mut out = Vec::new();
    let mut start = 0;
    while start < idx.len() {
        let b = bucket(idx[start]);
        let mut end = start + 1;
        while end < idx.len() && bucket(idx[end]) == b {
            end += 1;
        }
        let run = &idx[start..end];
        let (mut lo, mut hi) = (run[0], run[0]);
        for &i in run {
            if y[i] < y[lo] {
                lo = i;
            }
            if y[i] > y[hi] {
                hi = i;
            }
        }
        let mut keep = vec![run[0], lo, hi, run[run.len() - 1]];
        keep.sort_unstable();
        keep.dedup();
        out.extend(keep.into_iter().map(|i| (x[i], y[i])));
        start = end;
    }
    out
}

/// Everything `draw` needs.
struct Figure<'a> {
    title: Option<&'a str>,
    x_label: &'a str,
    x_range: (f64, f64),
    header: &'a [String],
    panels: &'a [PanelSpec],
    table: &'a Table,
    width: u32,
}

/// Legend layout in pixels (plotters' series-label box: a margin around the
/// sample lines and the labels, one row per series).
const LEGEND_MARGIN: u32 = 8;
const LEGEND_LINE: u32 = 28;
const LEGEND_ROW: u32 = 16;
/// Distance of plotters' legend box from the plotting area's edges, px.
const LEGEND_INSET: f64 = 5.0;

/// A legend box of `size` pixels with its upper left corner at `at` on
/// `area`, drawn like plotters' series labels: a sample line and the label
/// per series, in order.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    at: (i32, i32),
    size: (f64, f64),
    labels: &[(&str, RGBColor)],
    style: &TextStyle,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (x, y) = at;
    let corner = (x + size.0 as i32, y + size.1 as i32);
    area.draw(&Rectangle::new([at, corner], WHITE.mix(0.85).filled()))?;
    area.draw(&Rectangle::new([at, corner], RGBColor(160, 160, 160)))?;
    let m = LEGEND_MARGIN as i32;
    for (row, (label, colour)) in labels.iter().enumerate() {
        let mid = y + m + (row as i32) * LEGEND_ROW as i32 + LEGEND_ROW as i32 / 2;
        area.draw(&PathElement::new(
            vec![(x + m, mid), (x + m + 20, mid)],
            colour.stroke_width(2),
        ))?;
        let text = style.pos(plotters::style::text_anchor::Pos::new(
            HPos::Left,
            VPos::Center,
        ));
        area.draw(&Text::new(
            label.to_string(),
            (x + m + LEGEND_LINE as i32, mid),
            text,
        ))?;
    }
    Ok(())
}

/// Where a legend of `legend_px` (w, h) pixels hides none of the `parts`
/// (per series, its polylines) on a plotting area of `plot_px` pixels for
/// the ranges `x` and `y`: the first free corner (upper right, upper left,
/// lower right, lower left), else the upper right with the top of the y
/// range raised so that the data stays below the legend. Returns the corner
/// and the (possibly raised) top of the y range.
pub fn place_legend(
    parts: &[Vec<Vec<(f64, f64)>>],
    x: (f64, f64),
    y: (f64, f64),
    plot_px: (f64, f64),
    legend_px: (f64, f64),
) -> (SeriesLabelPosition, f64) {
    let (w, h) = plot_px;
    let (lw, lh) = (legend_px.0 + 2.0, legend_px.1 + 2.0);
    let to_px =
        |(px, py): (f64, f64), y1: f64| ((px - x.0) / (x.1 - x.0) * w, (y1 - py) / (y1 - y.0) * h);
    let corners = [
        (
            SeriesLabelPosition::UpperRight,
            w - lw - LEGEND_INSET,
            LEGEND_INSET,
        ),
        (SeriesLabelPosition::UpperLeft, LEGEND_INSET, LEGEND_INSET),
        (
            SeriesLabelPosition::LowerRight,
            w - lw - LEGEND_INSET,
            h - lh - LEGEND_INSET,
        ),
        (
            SeriesLabelPosition::LowerLeft,
            LEGEND_INSET,
            h - lh - LEGEND_INSET,
        ),
    ];
    if lw + 2.0 * LEGEND_INSET < w && lh + 2.0 * LEGEND_INSET < h {
        for (corner, bx, by) in corners {
            let hidden = parts.iter().flatten().any(|line| {
                let pts: Vec<(f64, f64)> = line.iter().map(|&p| to_px(p, y.1)).collect();
                crosses_box(&pts, (bx, by), (bx + lw, by + lh))
            });
            if !hidden {
                return (corner, y.1);
            }
        }
    }
    // Raise the top so that the data fills only the height below the legend.
    let free = (h - lh - 2.0 * LEGEND_INSET).max(0.25 * h);
    let y1 = y.0 + (y.1 - y.0) * h / free;
    (SeriesLabelPosition::UpperRight, y1)
}

/// Whether the polyline `pts` (pixels) has a point in, or a segment through,
/// the box from `lo` to `hi`.
pub fn crosses_box(pts: &[(f64, f64)], lo: (f64, f64), hi: (f64, f64)) -> bool {
    let inside = |(x, y): (f64, f64)| x >= lo.0 && x <= hi.0 && y >= lo.1 && y <= hi.1;
    if pts.iter().any(|&p| inside(p)) {
        return true;
    }
    pts.windows(2).any(|s| {
        let ((xa, ya), (xb, yb)) = (s[0], s[1]);
        // The segment's part within the box's columns, then its rows.
        let (t0, t1) = if (xb - xa).abs() < 1e-12 {
            if xa < lo.0 || xa > hi.0 {
                return false;
            }
            (0.0, 1.0)
        } else {
            let ta = (lo.0 - xa) / (xb - xa);
            let tb = (hi.0 - xa) / (xb - xa);
            (ta.min(tb).max(0.0), ta.max(tb).min(1.0))
        };
        if t0 > t1 {
            return false;
        }
        let (y0, y1) = (ya + t0 * (yb - ya), ya + t1 * (yb - ya));
        y0.max(y1) >= lo.1 && y0.min(y1) <= hi.1
    })
}

const FONT: &str = "sans-serif";

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, fig: &Figure) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("cannot draw the plot: {e}");
    root.fill(&WHITE).map_err(err)?;
    let area = match fig.title {
        Some(t) => root.titled(t, (FONT, 22)).map_err(err)?,
        None => root.clone(),
    };
    let (_, height) = area.dim_in_pixel();
    let n = fig.panels.len() as u32;
    let x_axis = 48u32;
    let top = 8u32;
    let plot_h = (height.saturating_sub(x_axis) / n).max(1);
    let breaks: Vec<u32> = (1..n).map(|i| i * plot_h).collect();
    let areas = area.split_by_breakpoints([] as [u32; 0], breaks);
    let (x0, x1) = fig.x_range;
    let x_fmt = tick_format(x0, x1, 10);
    // Legend sizes (w, h) in pixels. A legend taller than a third of its
    // panel would squeeze the data: then every panel's legend goes to the
    // right of the plotting areas, which keep one width (and one x axis).
    let label_style = TextStyle::from((FONT, 12));
    let mut legends = Vec::with_capacity(fig.panels.len());
    for panel in fig.panels {
        let mut text_w = 0u32;
        for &k in &panel.columns {
            let (w, _) = area
                .estimate_text_size(&fig.header[k], &label_style)
                .map_err(err)?;
            text_w = text_w.max(w);
        }
        legends.push((
            f64::from(text_w + LEGEND_LINE + 2 * LEGEND_MARGIN),
            f64::from(LEGEND_ROW * panel.columns.len() as u32 + 2 * LEGEND_MARGIN),
        ));
    }
    let panel_h = f64::from(plot_h.saturating_sub(top + x_axis));
    let outside = legends.iter().any(|l| l.1 > panel_h / 3.0);
    let right = if outside {
        legends.iter().map(|l| l.0 as u32).max().unwrap_or(0) + 2 * LEGEND_INSET as u32 + 20
    } else {
        20
    };
    for (p, (panel, sub)) in fig.panels.iter().zip(&areas).enumerate() {
        let legend_px = legends[p];
        let last = p + 1 == fig.panels.len();
        let values = || {
            panel
                .columns
                .iter()
                .flat_map(|k| fig.table.columns.get(k).unwrap_or(&fig.table.x).iter())
        };
        let (y0, y1) = match finite_bounds(values()) {
            Some((lo, hi)) => padded_range(lo, hi),
            None => (-1.0, 1.0),
        };
        let y_fmt = tick_format(y0, y1, 6);
        // Shrink the y label's font until it fits the panel's height.
        let mut size = 15.0;
        while size > 9.0 {
            let style = TextStyle::from((FONT, size));
            let (w, _) = sub.estimate_text_size(&panel.label, &style).map_err(err)?;
            if w + 2 * top <= plot_h {
                break;
            }
            size -= 1.0;
        }
        let parts: Vec<Vec<Vec<(f64, f64)>>> = panel
            .columns
            .iter()
            .map(|k| {
                let ys = fig.table.columns.get(k).unwrap_or(&fig.table.x);
                segments(&fig.table.x, ys, x0, x1, fig.width)
            })
            .collect();
        // The legend goes into a corner of the plotting area where it hides
        // no data; if every corner has some, the y range grows upwards to
        // make room above the data.
        let x_label_area = if last { x_axis - 8 } else { 0 };
        let (sub_w, sub_h) = sub.dim_in_pixel();
        let plot_px = (
            f64::from(sub_w.saturating_sub(8 + right + 92)),
            f64::from(sub_h.saturating_sub(top + x_label_area)),
        );
        let (legend, y1) = if outside {
            (SeriesLabelPosition::UpperRight, y1)
        } else {
            place_legend(&parts, (x0, x1), (y0, y1), plot_px, legend_px)
        };
        let mut chart = ChartBuilder::on(sub)
            .margin_top(top)
            .margin_right(right)
            .margin_left(8)
            .x_label_area_size(x_label_area)
            .y_label_area_size(92)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(err)?;
        let mut mesh = chart.configure_mesh();
        mesh.x_labels(10)
            .y_labels(6)
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .y_desc(panel.label.as_str())
            .axis_desc_style((FONT, size))
            .label_style((FONT, 12))
            .light_line_style(RGBColor(235, 235, 235));
        if last {
            mesh.x_desc(fig.x_label);
        }
        mesh.draw().map_err(err)?;
        for (c, (&k, parts)) in panel.columns.iter().zip(&parts).enumerate() {
            let colour = COLOURS[c % COLOURS.len()];
            let style = colour.stroke_width(2);
            let name = if parts.is_empty() {
                format!("{} (no data)", fig.header[k])
            } else {
                fig.header[k].clone()
            };
            let mut labelled = false;
            for part in parts.iter().filter(|s| s.len() > 1) {
                let ann = chart
                    .draw_series(LineSeries::new(part.iter().copied(), style))
                    .map_err(err)?;
                if !labelled {
                    ann.label(name.clone())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
                    labelled = true;
                }
            }
            // Isolated points (between gaps) as dots.
            let dots = parts
                .iter()
                .filter(|s| s.len() == 1)
                .map(|s| Circle::new(s[0], 2, colour.filled()));
            let ann = chart.draw_series(dots).map_err(err)?;
            if !labelled {
                ann.label(name)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
            }
        }
        if outside {
            let labels: Vec<(&str, RGBColor)> = panel
                .columns
                .iter()
                .enumerate()
                .map(|(c, &k)| (fig.header[k].as_str(), COLOURS[c % COLOURS.len()]))
                .collect();
            let x = sub_w as i32 - legend_px.0 as i32 - LEGEND_INSET as i32;
            draw_legend(sub, (x, top as i32), legend_px, &labels, &label_style).map_err(err)?;
            continue;
        }
        chart
            .configure_series_labels()
            .position(legend)
            .margin(LEGEND_MARGIN)
            .legend_area_size(LEGEND_LINE)
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .label_font((FONT, 12))
            .draw()
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// The bitmap backend with its own text drawing: plotters 0.3.7 draws `ab_glyph`
/// text without each glyph's left side bearing, which spaces letters unevenly.
/// Text is laid out with kerning, anchored on the font's ascent-to-descent box.
struct Png<'a> {
    inner: BitMapBackend<'a>,
    font: ab_glyph::FontRef<'static>,
}

impl Png<'_> {
    /// The glyphs of `text` at `size` pixels on a baseline at y = 0, and the
    /// text's advance width.
    fn layout(&self, text: &str, size: f32) -> (Vec<ab_glyph::Glyph>, f32) {
        let font = self.font.as_scaled(size);
        let (mut caret, mut prev) = (0.0, None);
        let mut glyphs = Vec::with_capacity(text.len());
        for c in text.chars() {
            let id = font.glyph_id(c);
            if let Some(p) = prev {
                caret += font.kern(p, id);
            }
            glyphs.push(id.with_scale_and_position(size, ab_glyph::point(caret, 0.0)));
            caret += font.h_advance(id);
            prev = Some(id);
        }
        (glyphs, caret)
    }
}

type PngError = DrawingErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>;

impl DrawingBackend for Png<'_> {
    type ErrorType = <BitMapBackend<'static> as DrawingBackend>::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }
    fn ensure_prepared(&mut self) -> Result<(), PngError> {
        self.inner.ensure_prepared()
    }
    fn present(&mut self) -> Result<(), PngError> {
        self.inner.present()
    }
    fn draw_pixel(&mut self, point: BackendCoord, color: BackendColor) -> Result<(), PngError> {
        self.inner.draw_pixel(point, color)
    }
    fn draw_line<S: plotters_backend::BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), PngError> {
        self.inner.draw_line(from, to, style)
    }
    fn draw_rect<S: plotters_backend::BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), PngError> {
        self.inner.draw_rect(upper_left, bottom_right, style, fill)
    }
    /// Thick lines segment by segment with round joints: plotters' bitmap
    /// backend polygonizes a whole path with mitred joints, which shoot far
    /// past the data (and out of the panel) where a line turns back sharply,
    /// as thinned data with its per-pixel minima and maxima does.
    fn draw_path<S: plotters_backend::BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), PngError> {
        let width = style.stroke_width();
        if width <= 1 {
            return self.inner.draw_path(path, style);
        }
        let points: Vec<BackendCoord> = path.into_iter().collect();
        for pair in points.windows(2) {
            self.inner.draw_path(pair.iter().copied(), style)?;
        }
        let color = style.color();
        for &p in points.iter().skip(1).take(points.len().saturating_sub(2)) {
            self.inner.draw_circle(p, width / 2, &color, true)?;
        }
        Ok(())
    }
    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), PngError> {
        self.inner.blit_bitmap(pos, size, src)
    }
    fn estimate_text_size<T: BackendTextStyle>(
        &self,
        text: &str,
        style: &T,
    ) -> Result<(u32, u32), PngError> {
        let size = style.size() as f32;
        let (_, width) = self.layout(text, size);
        Ok((width.ceil() as u32, size.ceil() as u32))
    }
    fn draw_text<T: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &T,
        pos: BackendCoord,
    ) -> Result<(), PngError> {
        let color = style.color();
        if color.alpha == 0.0 {
            return Ok(());
        }
        let size = style.size() as f32;
        let (glyphs, width) = self.layout(text, size);
        let scaled = self.font.as_scaled(size);
        let height = scaled.height();
        let dx = match style.anchor().h_pos {
            HPos::Left => 0.0,
            HPos::Right => -width,
            HPos::Center => -0.5 * width,
        };
        let dy = match style.anchor().v_pos {
            VPos::Top => 0.0,
            VPos::Center => -0.5 * height,
            VPos::Bottom => -height,
        };
        let (dx, dy) = (dx.round() as i32, (dy + scaled.ascent()).round() as i32);
        let transform = style.transform();
        let (w, h) = self.get_size();
        let mut pixels = Vec::new();
        for glyph in glyphs {
            if let Some(outline) = self.font.outline_glyph(glyph) {
                let b = outline.px_bounds();
                let (x0, y0) = (b.min.x as i32 + dx, b.min.y as i32 + dy);
                outline.draw(|x, y, cover| pixels.push((x0 + x as i32, y0 + y as i32, cover)));
            }
        }
        for (x, y, cover) in pixels {
            let (x, y) = transform.transform(x, y);
            let (x, y) = (pos.0 + x, pos.1 + y);
            if x >= 0 && y >= 0 && x < w as i32 && y < h as i32 && cover > 0.0 {
                let alpha = color.alpha * f64::from(cover.min(1.0));
                self.inner.draw_pixel(
                    (x, y),
                    BackendColor {
                        alpha,
                        rgb: color.rgb,
                    },
                )?;
            }
        }
        Ok(())
    }
}

fn register_font() -> Result<(), String> {
    plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular())
        .map_err(|_| "cannot load the embedded DejaVu Sans font".to_string())
}

/// Runs `umsim plot`.
pub fn run(args: &Args) -> Result<(), Box<dyn Error>> {
    let format = Format::of(&args.output)?;
    if args.from.is_some_and(f64::is_nan) || args.to.is_some_and(f64::is_nan) {
        return Err("--from and --to must be numbers, not NaN".into());
    }
    // An infinite bound on its own side is no bound.
    let from = args.from.filter(|f| *f != f64::NEG_INFINITY);
    let to = args.to.filter(|t| *t != f64::INFINITY);
    if let (Some(f), Some(t)) = (from, to)
        && f > t
    {
        return Err(format!("--from {f} is beyond --to {t}").into());
    }
    let n = args.y.len() as u32;
    let height = args
        .height
        .unwrap_or(60 + 280 * n + if args.title.is_some() { 40 } else { 0 });
    if !(300..=20_000).contains(&args.width) {
        return Err(format!("--width {} is out of 300…20000 pixels", args.width).into());
    }
    let min_height = 60 + 100 * n + if args.title.is_some() { 40 } else { 0 };
    if height < min_height || height > 20_000 {
        return Err(format!(
            "--height {height} is out of {min_height}…20000 pixels for {n} panel(s)"
        )
        .into());
    }
    let source = args.input.display().to_string();
    let file =
        std::fs::File::open(&args.input).map_err(|e| format!("cannot open {source}: {e}"))?;
    let (header, xi, panels, table) = read_table(
        std::io::BufReader::new(file),
        &source,
        &args.x,
        &args.y,
        from,
        to,
    )?;
    let (lo, hi) = finite_bounds(table.x.iter()).expect("read_table keeps finite x only");
    let x_range = {
        let lo = from.unwrap_or(lo).max(-LIMIT);
        let hi = to.unwrap_or(hi).min(LIMIT);
        if hi > lo {
            (lo, hi)
        } else {
            padded_range(lo, hi)
        }
    };
    let fig = Figure {
        title: args.title.as_deref(),
        x_label: &header[xi],
        x_range,
        header: &header,
        panels: &panels,
        table: &table,
        width: args.width,
    };
    register_font()?;
    // Fail with the system's word on an unwritable output before drawing.
    std::fs::File::create(&args.output)
        .map_err(|e| format!("cannot write {}: {e}", args.output.display()))?;
    let size = (args.width, height);
    let out = args.output.display().to_string();
    let wrap = |e: String| format!("{out}: {e}");
    match format {
        Format::Svg => draw(
            SVGBackend::new(&args.output, size).into_drawing_area(),
            &fig,
        ),
        Format::Png => {
            let font = ab_glyph::FontRef::try_from_slice(dejavu::sans::regular())
                .map_err(|e| format!("cannot load the embedded DejaVu Sans font: {e}"))?;
            let inner = BitMapBackend::new(&args.output, size);
            draw(Png { inner, font }.into_drawing_area(), &fig)
        }
    }
    .map_err(wrap)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn h(names: &[&str]) -> Vec<String> {
        names.iter().map(|s| s.to_string()).collect()
    }

    fn glob_match(pattern: &str, name: &str) -> bool {
        column_pattern(pattern).is_match(name)
    }

    #[test]
    fn globs() {
        assert!(glob_match("a*c", "abc"));
        assert!(glob_match("a*c", "ac"));
        assert!(glob_match("*", ""));
        assert!(glob_match("B1.*.L.Y/Q [-]", "B1.WS1.contact.L.Y/Q [-]"));
        assert!(!glob_match("B1.*.L.Y/Q [-]", "B1.WS1.contact.R.Y/Q [-]"));
        assert!(glob_match("*a*a", "banana"));
        assert!(!glob_match("a*b", "acbc"));
        // glob syntax other than `*` is literal: brackets, braces, `?`, backslashes
        assert!(glob_match("s[m]", "s[m]"));
        assert!(!glob_match("s[m]", "sm"));
        assert!(glob_match("*{a,b}?\\*", "x{a,b}?\\y"));
        assert!(!glob_match("a?", "ab"));
    }

    #[test]
    fn panels_expand_in_header_order() {
        let header = h(&["time", "b.y[m]", "a.y[m]", "a.z[m]"]);
        let p = resolve_panel(&header, "*.y[m]", 0, "f").unwrap();
        assert_eq!(p.columns, vec![1, 2]);
        assert_eq!(p.label, "*.y[m]");
        let p = resolve_panel(&header, "a.z[m], *.y[m], a.z[m]", 0, "f").unwrap();
        assert_eq!(p.columns, vec![3, 1, 2]);
        assert!(resolve_panel(&header, "*", 0, "f").unwrap().columns == vec![1, 2, 3]);
        let e = resolve_panel(&header, "a.Y[m]", 0, "f").unwrap_err();
        assert!(e.contains("\"a.y[m]\""), "{e}");
    }

    #[test]
    fn labels_of_several_columns() {
        assert_eq!(
            common_label(&["B1.WS1.contact.L.Y/Q [-]", "B1.WS2.contact.R.Y/Q [-]"]),
            "Y/Q [-]"
        );
        assert_eq!(common_label(&["a.y[m]", "b.y[m]"]), "y[m]");
        assert_eq!(common_label(&["a.y[m]", "b.z[m]"]), "[m]");
        assert_eq!(common_label(&["a.y[m]", "ba.y[m]"]), "y[m]");
        assert_eq!(common_label(&["y[m]", "a.y[m]"]), "y[m]");
        assert_eq!(common_label(&["a.y[m]", "a.v[m/s]"]), "(several units)");
        assert_eq!(common_label(&["a", "b"]), "(several units)");
    }

    #[test]
    fn close_names_of_names_and_patterns() {
        let header = h(&[
            "time",
            "body.y[m]",
            "Bogie1.WS1.contact.L.Y/Q [-]",
            "Bogie1.WS2.contact.L.Y/Q [-]",
        ]);
        assert_eq!(close_names(&header, "body.Y[m]", 5), vec!["body.y[m]"]);
        assert_eq!(close_names(&header, "y[m]", 5), vec!["body.y[m]"]);
        assert_eq!(
            close_names(&header, "Bogie2.*.Y/Q [-]", 5),
            vec![
                "Bogie1.WS1.contact.L.Y/Q [-]",
                "Bogie1.WS2.contact.L.Y/Q [-]"
            ]
        );
        assert!(close_names(&header, "zzzzzzzz", 5).is_empty());
        assert!(close_names(&header, "*zzzzzzzz*", 5).is_empty());
        assert_eq!(
            close_names(&header, "WS1.contact.L.YQ", 5),
            vec![
                "Bogie1.WS1.contact.L.Y/Q [-]",
                "Bogie1.WS2.contact.L.Y/Q [-]"
            ]
        );
    }

    #[test]
    fn ranges() {
        assert_eq!(padded_range(0.0, 0.0), (-1.0, 1.0));
        let (a, b) = padded_range(2.0, 2.0);
        assert!((a - 1.8).abs() < 1e-12 && (b - 2.2).abs() < 1e-12);
        let (a, b) = padded_range(0.0, 10.0);
        assert!((a + 0.5).abs() < 1e-12 && (b - 10.5).abs() < 1e-12);
        let (a, b) = padded_range(-f64::MAX, f64::MAX);
        assert!((b - a).is_finite() && a < -1e307 && b > 1e307);
    }

    #[test]
    fn ticks() {
        let f = tick_format(0.0, 10.0, 10);
        assert_eq!(f(&2.0), "2");
        let f = tick_format(0.0, 0.9, 10);
        assert_eq!(f(&0.2), "0.2");
        let f = tick_format(-0.01, 0.01, 6);
        assert_eq!(f(&0.005), "0.005");
        let f = tick_format(-2e-4, 2e-4, 6);
        assert_eq!(f(&1e-4), "1e-4");
        let f = tick_format(-1.1e-6, 1.1e-6, 6);
        assert_eq!(f(&5e-7), "5.0e-7");
        assert_eq!(f(&1e-20), "0");
    }

    #[test]
    fn gaps_split_segments() {
        let x = [0.0, 1.0, 2.0, 3.0, 4.0];
        let y = [1.0, f64::NAN, 2.0, 3.0, f64::INFINITY];
        let s = segments(&x, &y, 0.0, 4.0, 100);
        assert_eq!(s, vec![vec![(0.0, 1.0)], vec![(2.0, 2.0), (3.0, 3.0)]]);
    }

    #[test]
    fn thinning_keeps_extremes() {
        let x: Vec<f64> = (0..10_000).map(|i| i as f64 / 10_000.0).collect();
        let y: Vec<f64> = x.iter().map(|&t| if t == 0.5 { 7.0 } else { t }).collect();
        let s = segments(&x, &y, 0.0, 1.0, 100);
        assert_eq!(s.len(), 1);
        assert!(s[0].len() <= 400);
        assert!(s[0].contains(&(0.5, 7.0)));
        assert_eq!(s[0].last(), Some(&(0.9999, 0.9999)));
    }
}

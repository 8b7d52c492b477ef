//! PNG plots (plotters, bitmap backend, embedded DejaVu Sans so no system fonts are needed).
use crate::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;

fn perr<E: std::fmt::Display>(e: E) -> Error {
    Error::Plot(e.to_string())
}

/// Ten distinguishable colours (matplotlib's tab10): a chart with up to ten series never repeats one.
const COLORS: [RGBColor; 10] = [
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

/// Height of one legend row below the panels, px.
const LEGEND_ROW: u32 = 22;

/// Tick label with at most 4 significant digits and no float noise ("0.7", "1e-3", "120").
pub fn fmt_tick(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.1e}");
    }
    let decimals = (3 - a.log10().floor() as i32).clamp(0, 6) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// An axis from `lo` to `hi` plotters can lay out: both ends and the span finite. A span that
/// overflows (values of ±1e308) would never finish placing its ticks.
fn drawable(what: &str, lo: f64, hi: f64) -> Result<()> {
    if lo.is_finite() && hi.is_finite() && (hi - lo).is_finite() {
        Ok(())
    } else {
        Err(Error::Plot(format!(
            "{what}: the values span {lo:e} to {hi:e}, too wide for an axis (give values whose \
             span is finite, well inside ±1e307)"
        )))
    }
}

/// One line of a line chart.
pub struct Series<'a> {
    pub name: String,
    pub points: &'a [(f64, f64)],
}

/// Several panels of line charts side by side, each `(title, x label, y label, log y, series)`.
pub fn line_panels(
    path: &Path,
    panels: &[(String, &str, &str, bool, Vec<Series>)],
    panel_w: u32,
    h: u32,
) -> Result<()> {
    if panels.is_empty() {
        return Err(Error::Plot("no panel to draw".into()));
    }
    // Every panel's axes, checked before the PNG is created: `None` for a panel with no point.
    let axes = panels
        .iter()
        .map(|(title, _, _, logy, series)| line_axes(title, *logy, series))
        .collect::<Result<Vec<_>>>()?;
    hil_sim::font::register();
    // Panels with more than one series share one legend below them, off the data.
    let legend: Vec<String> = panels
        .iter()
        .flat_map(|p| p.4.iter().map(|s| s.name.clone()))
        .fold(Vec::new(), |mut v, n| {
            if !v.contains(&n) {
                v.push(n);
            }
            v
        });
    let width = panel_w * panels.len() as u32;
    let per_row = (width / 260).max(1) as usize;
    let legend_h = if legend.len() > 1 {
        8 + LEGEND_ROW * legend.len().div_ceil(per_row) as u32
    } else {
        0
    };
    let root = BitMapBackend::new(path, (width, h + legend_h)).into_drawing_area();
    root.fill(&WHITE).map_err(perr)?;
    let (charts, legend_area) = root.split_vertically(h);
    for (k, name) in legend.iter().enumerate() {
        let c = COLORS[k % COLORS.len()];
        let (x, y) = (
            20 + 260 * (k % per_row) as i32,
            6 + (LEGEND_ROW * (k / per_row) as u32) as i32 + LEGEND_ROW as i32 / 2,
        );
        legend_area
            .draw(&PathElement::new([(x, y), (x + 24, y)], c.stroke_width(3)))
            .map_err(perr)?;
        legend_area
            .draw(&Text::new(
                name.clone(),
                (x + 30, y - 8),
                ("sans-serif", 14).into_font(),
            ))
            .map_err(perr)?;
    }
    let colour_of = |name: &str| {
        let k = legend.iter().position(|n| n == name).unwrap_or(0);
        COLORS[k % COLORS.len()]
    };
    let areas = charts.split_evenly((1, panels.len()));
    for (((title, xl, yl, logy, series), area), axes) in panels.iter().zip(areas).zip(axes) {
        let Some((x0, x1, y0, y1)) = axes else {
            continue;
        };
        let mut b = ChartBuilder::on(&area);
        b.caption(title, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60);
        macro_rules! draw {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(*xl)
                    .y_desc(*yl)
                    .x_label_formatter(&|v| fmt_tick(*v))
                    .y_label_formatter(&|v| fmt_tick(*v))
                    .light_line_style(WHITE)
                    .draw()
                    .map_err(perr)?;
                for s in series.iter() {
                    let c = colour_of(&s.name);
                    // Dense series (time histories) get thin lines so overlapping ones stay legible.
                    let width = if s.points.len() > 1000 { 1 } else { 2 };
                    chart
                        .draw_series(LineSeries::new(
                            s.points.iter().copied().filter(|(x, y)| {
                                x.is_finite() && y.is_finite() && (!*logy || *y > 0.0)
                            }),
                            c.stroke_width(width),
                        ))
                        .map_err(perr)?;
                }
            }};
        }
        if *logy {
            draw!(
                b.build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                    .map_err(perr)?
            );
        } else {
            draw!(b.build_cartesian_2d(x0..x1, y0..y1).map_err(perr)?);
        }
    }
    root.present().map_err(perr)?;
    Ok(())
}

/// The x and y ranges of a line panel (y padded: 5 % each side, or ×0.9..×1.1 on a log scale) over
/// its finite points (positive ones on a log scale); `None` when it has none; an error when an
/// axis would not be finite.
fn line_axes(title: &str, logy: bool, series: &[Series]) -> Result<Option<(f64, f64, f64, f64)>> {
    let pts = series.iter().flat_map(|s| s.points.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y) in pts {
        if !x.is_finite() || !y.is_finite() || (logy && *y <= 0.0) {
            continue;
        }
        x0 = x0.min(*x);
        x1 = x1.max(*x);
        y0 = y0.min(*y);
        y1 = y1.max(*y);
    }
    if x0 > x1 {
        return Ok(None);
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    if y1 <= y0 {
        y1 = y0 + 1e-9_f64.max(y0.abs() * 0.1);
    }
    let (y0, y1) = if logy {
        (y0 * 0.9, y1 * 1.1)
    } else {
        let pad = (y1 - y0) * 0.05;
        (y0 - pad, y1 + pad)
    };
    drawable(&format!("panel `{title}`, x"), x0, x1)?;
    drawable(&format!("panel `{title}`, y"), y0, y1)?;
    Ok(Some((x0, x1, y0, y1)))
}

/// Horizontal bar chart (e.g. mean |SHAP| per feature), largest first.
pub fn bars(path: &Path, title: &str, xlabel: &str, items: &[(String, f64)]) -> Result<()> {
    hil_sim::font::register();
    let mut items = items.to_vec();
    items.sort_by(|a, b| b.1.total_cmp(&a.1));
    let h = 80 + 28 * items.len() as u32;
    let max = items.iter().map(|i| i.1).fold(0.0, f64::max).max(1e-12);
    drawable(title, 0.0, max * 1.1)?;
    let root = BitMapBackend::new(path, (800, h)).into_drawing_area();
    root.fill(&WHITE).map_err(perr)?;
    let n = items.len();
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(150)
        .build_cartesian_2d(0.0..max * 1.1, (0..n).into_segmented())
        .map_err(perr)?;
    let names: Vec<String> = items.iter().map(|i| i.0.clone()).collect();
    chart
        .configure_mesh()
        .x_desc(xlabel)
        .y_labels(n)
        .y_label_formatter(&|v| reversed_label(&names, v))
        .draw()
        .map_err(perr)?;
    chart
        .draw_series(items.iter().enumerate().map(|(i, (_, v))| {
            let y = n - 1 - i;
            let mut r = Rectangle::new(
                [
                    (0.0, SegmentValue::Exact(y)),
                    (*v, SegmentValue::Exact(y + 1)),
                ],
                COLORS[0].filled(),
            );
            r.set_margin(3, 3, 0, 0);
            r
        }))
        .map_err(perr)?;
    root.present().map_err(perr)?;
    Ok(())
}

/// One panel of [`grouped_bar_panels`]: title, x label, rows (a label and one value per series).
pub type BarPanel<'a> = (String, &'a str, Vec<(String, Vec<f64>)>);

/// Panels of horizontal grouped bars side by side, each from 0 (to the left for a negative value);
/// a row's NaN value draws no bar. Rows are drawn
/// top-down in the given order, with a legend of `series` in empty rows above them.
pub fn grouped_bar_panels(path: &Path, panels: &[BarPanel], series: &[String]) -> Result<()> {
    if panels.is_empty() {
        return Err(Error::Plot("no panel to draw".into()));
    }
    // Every panel's value axis, checked before the PNG is created.
    let spans = panels
        .iter()
        .map(|(title, _, items)| {
            let (lo, hi) = bar_span(items);
            drawable(&format!("panel `{title}`"), lo, hi).map(|()| (lo, hi))
        })
        .collect::<Result<Vec<_>>>()?;
    hil_sim::font::register();
    let rows = panels.iter().map(|p| p.2.len()).max().unwrap_or(0);
    // Rows of 30 px kept free at the top for the legend (20 px per series).
    let legend_rows = (series.len() * 20).div_ceil(30);
    let h = 110 + 30 * (rows + legend_rows) as u32;
    let root = BitMapBackend::new(path, (620 * panels.len() as u32, h)).into_drawing_area();
    root.fill(&WHITE).map_err(perr)?;
    let k = series.len().max(1);
    let areas = root.split_evenly((1, panels.len()));
    for (((title, xl, items), area), (lo, hi)) in panels.iter().zip(areas).zip(spans) {
        let n = items.len();
        let names: Vec<String> = items.iter().map(|i| i.0.clone()).collect();
        let mut chart = ChartBuilder::on(&area)
            .caption(title.as_str(), ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(190)
            .build_cartesian_2d(lo..hi, (0..n + legend_rows).into_segmented())
            .map_err(perr)?;
        chart
            .configure_mesh()
            .x_desc(*xl)
            .x_label_formatter(&|v| fmt_tick(*v))
            .y_labels(n + legend_rows)
            .y_label_formatter(&|v| reversed_label(&names, v))
            .draw()
            .map_err(perr)?;
        for (si, name) in series.iter().enumerate() {
            let color = COLORS[si % COLORS.len()];
            let bars = items.iter().enumerate().filter_map(|(i, (_, v))| {
                let v = *v.get(si)?;
                if !v.is_finite() {
                    return None;
                }
                // Segment y spans [y, y + 1); series si takes its k-th slice, top to bottom.
                let y = n - 1 - i;
                let top = (k - si) as i32 * 24 / k as i32;
                let bottom = (k - si - 1) as i32 * 24 / k as i32;
                let mut r = Rectangle::new(
                    [
                        (0.0, SegmentValue::Exact(y)),
                        (v, SegmentValue::Exact(y + 1)),
                    ],
                    color.filled(),
                );
                r.set_margin(3 + (24 - top) as u32, 3 + bottom as u32, 0, 0);
                Some(r)
            });
            chart
                .draw_series(bars)
                .map_err(perr)?
                .label(name.as_str())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 12, y + 5)], color.filled())
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(perr)?;
    }
    root.present().map_err(perr)?;
    Ok(())
}

/// The value axis of a grouped-bar panel: bars grow from 0, so it spans 0 and every finite value
/// (left of 0 for a negative one), with 15 % to spare.
fn bar_span(items: &[(String, Vec<f64>)]) -> (f64, f64) {
    let (min, max) = items
        .iter()
        .flat_map(|i| i.1.iter())
        .copied()
        .filter(|v| v.is_finite())
        .fold((0.0, 0.0), |(lo, hi): (f64, f64), v| (lo.min(v), hi.max(v)));
    let max = max.max(1e-12);
    (min * 1.15, max * 1.15)
}

/// Label of a segmented axis drawn top-down: segment `i` from the bottom shows `names[n - 1 - i]`.
fn reversed_label(names: &[String], v: &SegmentValue<usize>) -> String {
    match v {
        SegmentValue::CenterOf(i) => (names.len().saturating_sub(1))
            .checked_sub(*i)
            .and_then(|k| names.get(k))
            .cloned()
            .unwrap_or_default(),
        _ => String::new(),
    }
}

/// Correlation heatmap, values in -1..=1 (blue negative, red positive).
pub fn heatmap(path: &Path, title: &str, names: &[String], m: &[Vec<f64>]) -> Result<()> {
    hil_sim::font::register();
    let n = names.len();
    let cell = 34u32;
    let side = 190 + cell * n as u32;
    let root = BitMapBackend::new(path, (side + 20, side + 40)).into_drawing_area();
    root.fill(&WHITE).map_err(perr)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(170)
        .y_label_area_size(170)
        .build_cartesian_2d((0..n).into_segmented(), (0..n).into_segmented())
        .map_err(perr)?;
    let ylabel = |v: &SegmentValue<usize>| reversed_label(names, v);
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(n)
        .y_labels(n)
        .x_label_formatter(&|_| String::new())
        .y_label_formatter(&ylabel)
        .y_label_style(("sans-serif", 12))
        .draw()
        .map_err(perr)?;
    // Column names drawn downwards from the bottom edge (rotated mesh labels get clipped).
    let rotated = ("sans-serif", 12)
        .into_font()
        .transform(FontTransform::Rotate90)
        .color(&BLACK);
    for (j, name) in names.iter().enumerate() {
        let (px, py) = chart.backend_coord(&(SegmentValue::CenterOf(j), SegmentValue::Exact(0)));
        root.draw(&Text::new(name.clone(), (px + 6, py + 6), rotated.clone()))
            .map_err(perr)?;
    }
    for (i, row) in m.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            let v = if v.is_finite() {
                v.clamp(-1.0, 1.0)
            } else {
                0.0
            };
            let t = (v.abs() * 255.0) as u8;
            let c = if v >= 0.0 {
                RGBColor(255, 255 - t, 255 - t)
            } else {
                RGBColor(255 - t, 255 - t, 255)
            };
            let y = n - 1 - i;
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [
                        (SegmentValue::Exact(j), SegmentValue::Exact(y)),
                        (SegmentValue::Exact(j + 1), SegmentValue::Exact(y + 1)),
                    ],
                    c.filled(),
                )))
                .map_err(perr)?;
            chart
                .draw_series(std::iter::once(Text::new(
                    format!("{:.1}", v),
                    (SegmentValue::CenterOf(j), SegmentValue::CenterOf(y)),
                    ("sans-serif", 10).into_font().color(&BLACK),
                )))
                .map_err(perr)?;
        }
    }
    root.present().map_err(perr)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("trainer-plots-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join("x.png")
    }

    /// Values of ±1e308 make an axis whose span overflows: refused before the PNG is created
    /// (plotters would place ticks on it forever).
    #[test]
    fn an_axis_whose_span_overflows_is_refused_and_nothing_is_written() {
        let path = scratch("span");
        let points = [(0.0, 1e308), (1.0, -1e308)];
        let panels = vec![(
            "t".to_string(),
            "x",
            "y",
            false,
            vec![Series {
                name: "s".into(),
                points: &points,
            }],
        )];
        let e = line_panels(&path, &panels, 300, 200).unwrap_err();
        assert!(
            matches!(&e, Error::Plot(m) if m.contains("panel `t`, y") && m.contains("too wide")),
            "{e}"
        );
        let xs = [(-1e308, 1.0), (1e308, 2.0)];
        let panels = vec![(
            "u".to_string(),
            "x",
            "y",
            false,
            vec![Series {
                name: "s".into(),
                points: &xs,
            }],
        )];
        let e = line_panels(&path, &panels, 300, 200).unwrap_err();
        assert!(
            matches!(&e, Error::Plot(m) if m.contains("panel `u`, x")),
            "{e}"
        );
        // One bar of 1.6e308 (its axis, 15 % wider, overflows), or two of ±1e308 (their span does).
        for rows in [vec![1.6e308], vec![-1.6e308], vec![1e308, -1e308]] {
            let rows = rows
                .into_iter()
                .map(|v| ("r".to_string(), vec![v]))
                .collect();
            let bars: Vec<BarPanel> = vec![("b".into(), "x", rows)];
            let e = grouped_bar_panels(&path, &bars, &["a".to_string()]).unwrap_err();
            assert!(
                matches!(&e, Error::Plot(m) if m.contains("panel `b`")),
                "{e}"
            );
        }
        assert!(bars(&path, "t", "x", &[("r".into(), 1.7e308)]).is_err());
        assert!(!path.exists());
    }

    #[test]
    fn no_panel_is_refused_and_nothing_is_written() {
        let path = scratch("empty");
        let e = grouped_bar_panels(&path, &[], &["a".to_string()]).unwrap_err();
        assert!(
            matches!(&e, Error::Plot(m) if m == "no panel to draw"),
            "{e}"
        );
        let e = line_panels(&path, &[], 300, 200).unwrap_err();
        assert!(
            matches!(&e, Error::Plot(m) if m == "no panel to draw"),
            "{e}"
        );
        assert!(!path.exists());
    }

    #[test]
    fn ticks_have_no_float_noise() {
        assert_eq!(fmt_tick(0.7000000000000001), "0.7");
        assert_eq!(fmt_tick(0.30000000000000004), "0.3");
        assert_eq!(fmt_tick(120.0), "120");
        assert_eq!(fmt_tick(-2.5), "-2.5");
        assert_eq!(fmt_tick(0.0123456), "0.01235");
        assert_eq!(fmt_tick(2.0e-5), "2.0e-5");
    }
}

//! PNG of a run: α and β truth vs estimate, their errors, and the link statistics in the caption.
//! Text uses the embedded DejaVu Sans (no system fonts in CI containers).

use std::path::Path;

use plotters::prelude::*;

use super::FrameRecord;
use super::{Summary, scorable};

const TRUTH: RGBColor = RGBColor(31, 119, 180);
const ESTIMATE: RGBColor = RGBColor(255, 127, 14);
const ERROR: RGBColor = RGBColor(214, 39, 40);

type Points = Vec<(f64, f64)>;
/// A panel: y label and its lines (name, points, colour).
type Panel<'a> = (&'a str, Vec<(&'a str, &'a Points, RGBColor)>);

fn series(
    records: &[FrameRecord],
    angle: fn(&FrameRecord) -> (f64, f64),
) -> (Points, Points, Points) {
    let truth = records.iter().map(|r| (r.time_s, angle(r).0)).collect();
    let scored: Vec<&FrameRecord> = records.iter().filter(|r| scorable(r)).collect();
    let est = scored.iter().map(|r| (r.time_s, angle(r).1)).collect();
    let err = scored
        .iter()
        .map(|r| (r.time_s, angle(r).1 - angle(r).0))
        .collect();
    (truth, est, err)
}

fn range(points: &[&Points]) -> (f64, f64) {
    let (lo, hi) = points
        .iter()
        .flat_map(|p| p.iter().map(|q| q.1))
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if lo > hi {
        return (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(0.1);
    (lo - pad, hi + pad)
}

/// Why the plot could not be drawn (plotters' error types are backend-generic: their text is kept).
#[derive(Debug, thiserror::Error)]
#[error("drawing the plot: {0}")]
pub struct PlotError(String);

fn plot_err(e: impl std::fmt::Display) -> PlotError {
    PlotError(e.to_string())
}

/// Writes the plot.
pub fn write_png(path: &Path, records: &[FrameRecord], s: &Summary) -> Result<(), PlotError> {
    crate::font::register();
    let root = BitMapBackend::new(path, (1400, 1000)).into_drawing_area();
    root.fill(&WHITE).map_err(plot_err)?;
    let fmt = |v: Option<f64>| v.map_or("n/a".to_string(), |v| format!("{v:.3}"));
    let caption = format!(
        "firmware {} | sent {} scored {} lost {} | rejected {} | deadline misses {} | link: {} B lost, {} bits flipped, {} bursts | α MAE {}° β MAE {}°",
        s.firmware,
        s.frames_sent,
        s.frames_scored,
        s.frames_lost,
        s.frames_corrupt_rejected,
        s.deadline_misses,
        s.uplink.bytes_lost + s.downlink.bytes_lost,
        s.uplink.bits_flipped + s.downlink.bits_flipped,
        s.uplink.bursts + s.downlink.bursts,
        fmt(s.alpha_mae_deg),
        fmt(s.beta_mae_deg),
    );
    let (title, body) = root.split_vertically(40);
    title
        .draw(&Text::new(
            caption,
            (10, 12),
            ("sans-serif", 16).into_font(),
        ))
        .map_err(plot_err)?;
    let panels = body.split_evenly((3, 1));
    let t_end = records.last().map_or(1.0, |r| r.time_s.max(1e-3));
    let alpha = series(records, super::alpha_deg);
    let beta = series(records, super::beta_deg);
    let plots: [Panel; 3] = [
        (
            "α (deg)",
            vec![("truth", &alpha.0, TRUTH), ("estimate", &alpha.1, ESTIMATE)],
        ),
        (
            "β (deg)",
            vec![("truth", &beta.0, TRUTH), ("estimate", &beta.1, ESTIMATE)],
        ),
        (
            "error (deg)",
            vec![("α error", &alpha.2, ERROR), ("β error", &beta.2, ESTIMATE)],
        ),
    ];
    for (area, (label, lines)) in panels.iter().zip(plots.iter()) {
        let all: Vec<&Points> = lines.iter().map(|l| l.1).collect();
        let (lo, hi) = range(&all);
        let mut chart = ChartBuilder::on(area)
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..t_end, lo..hi)
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc("flight time (s)")
            .y_desc(*label)
            .draw()
            .map_err(plot_err)?;
        for (name, pts, color) in lines {
            let c = *color;
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(1)))
                .map_err(plot_err)?
                .label(*name)
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], c));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(plot_err)?;
    }
    root.present().map_err(plot_err)
}

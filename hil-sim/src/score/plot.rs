//! PNG of a run, read at a glance: the flight's name and scores in the title; α and β, truth (a wide
//! light band) under the estimate (a thin dark line), so both show where they agree; the α and β
//! errors each in their own panel with a 10-second rolling MAE; every span where the estimate
//! carried a flag shaded, scripted faults marked. Text uses the embedded DejaVu Sans (no system
//! fonts in CI containers).

use std::path::Path;

use plotters::prelude::*;

use super::FrameRecord;
use super::{Summary, scorable};

const TRUTH: RGBColor = RGBColor(140, 170, 220);
const ESTIMATE: RGBColor = RGBColor(200, 80, 0);
const ERROR: RGBColor = RGBColor(120, 120, 120);
const ROLLING: RGBColor = RGBColor(20, 20, 20);
const FLAGGED: RGBColor = RGBColor(255, 200, 200);
const FAULT: RGBColor = RGBColor(200, 200, 255);

/// Window of the rolling MAE, s.
pub const ROLLING_S: f64 = 10.0;

type Points = Vec<(f64, f64)>;

/// Truth, estimate and error of one angle over the scored frames with a finite truth (the estimate
/// over every scored frame).
fn series(
    records: &[FrameRecord],
    angle: fn(&FrameRecord) -> (f64, f64),
) -> (Points, Points, Points) {
    let truth = records
        .iter()
        .map(|r| (r.time_s, angle(r).0))
        .filter(|p| p.1.is_finite())
        .collect();
    let scored: Vec<&FrameRecord> = records.iter().filter(|r| scorable(r)).collect();
    let est = scored.iter().map(|r| (r.time_s, angle(r).1)).collect();
    let err = scored
        .iter()
        .map(|r| (r.time_s, angle(r).1 - angle(r).0))
        .filter(|p| p.1.is_finite())
        .collect();
    (truth, est, err)
}

/// Mean |error| over the trailing [`ROLLING_S`] at each error point.
pub fn rolling_mae(err: &Points) -> Points {
    let mut out = Vec::with_capacity(err.len());
    let (mut lo, mut sum) = (0usize, 0.0);
    for (k, &(t, e)) in err.iter().enumerate() {
        sum += e.abs();
        while let Some(&(t0, e0)) = err.get(lo) {
            if t - t0 < ROLLING_S {
                break;
            }
            sum -= e0.abs();
            lo += 1;
        }
        let n = (k + 1).saturating_sub(lo).max(1);
        out.push((t, sum / n as f64));
    }
    out
}

/// Time spans `[start, end)` of consecutive answered frames with any flag raised.
pub fn flagged_spans(records: &[FrameRecord]) -> Vec<(f64, f64)> {
    let mut spans: Vec<(f64, f64)> = Vec::new();
    let half = super::PERIOD_S / 2.0;
    for r in records {
        let flagged = r.reply.is_some_and(|f| f.estimate.flags.0 != 0);
        if !flagged {
            continue;
        }
        let (a, b) = (r.time_s - half, r.time_s + half);
        match spans.last_mut() {
            Some(last) if a <= last.1 + 1e-9 => last.1 = b,
            _ => spans.push((a, b)),
        }
    }
    spans
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

/// One panel: y label, the shaded spans, and its lines (points, colour, width) in drawing order.
struct Panel<'a> {
    label: &'a str,
    lines: Vec<(&'a Points, RGBColor, u32)>,
}

/// Writes the plot.
pub fn write_png(path: &Path, records: &[FrameRecord], s: &Summary) -> Result<(), PlotError> {
    crate::font::register();
    let root = BitMapBackend::new(path, (1400, 1150)).into_drawing_area();
    root.fill(&WHITE).map_err(plot_err)?;
    let fmt = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.3}°"));
    let p = &s.provenance;
    let title = format!(
        "{} on {} firmware ({} frames): α MAE {}, β MAE {} over {} frames with truth",
        if p.flight.is_empty() {
            "flight"
        } else {
            &p.flight
        },
        s.firmware,
        p.suite,
        fmt(s.alpha_mae_deg),
        fmt(s.beta_mae_deg),
        s.frames_with_truth,
    );
    let flagged: usize = records
        .iter()
        .filter(|r| r.reply.is_some_and(|f| f.estimate.flags.0 != 0))
        .count();
    let counters = format!(
        "sent {}, answered {}, lost {}, corrupt rejected {}, deadline misses {}, flagged {} | link: {} B lost, {} bits flipped",
        s.frames_sent,
        s.frames_answered,
        s.frames_lost,
        s.frames_corrupt_rejected,
        s.deadline_misses,
        flagged,
        s.uplink.bytes_lost + s.downlink.bytes_lost,
        s.uplink.bits_flipped + s.downlink.bits_flipped,
    );
    let (head, body) = root.split_vertically(78);
    head.draw(&Text::new(title, (12, 8), ("sans-serif", 22).into_font()))
        .map_err(plot_err)?;
    head.draw(&Text::new(
        counters,
        (12, 36),
        ("sans-serif", 15).into_font(),
    ))
    .map_err(plot_err)?;
    // The legend, in the header rather than on the data.
    let legend: [(&str, RGBColor, bool); 6] = [
        ("truth", TRUTH, false),
        ("estimate", ESTIMATE, false),
        ("error", ERROR, false),
        ("10 s rolling MAE", ROLLING, false),
        ("a flag raised", FLAGGED, true),
        ("scripted fault", FAULT, true),
    ];
    let mut x = 12;
    for (name, c, filled) in legend {
        let y = 62;
        if filled {
            head.draw(&Rectangle::new([(x, y - 6), (x + 24, y + 6)], c.filled()))
                .map_err(plot_err)?;
        } else {
            head.draw(&PathElement::new([(x, y), (x + 24, y)], c.stroke_width(3)))
                .map_err(plot_err)?;
        }
        head.draw(&Text::new(
            name,
            (x + 30, y - 8),
            ("sans-serif", 15).into_font(),
        ))
        .map_err(plot_err)?;
        x += 46 + 8 * name.chars().count() as i32;
    }
    let t_end = records.last().map_or(1.0, |r| r.time_s.max(1e-3));
    let t_start = records.first().map_or(0.0, |r| r.time_s.min(t_end - 1e-3));
    let alpha = series(records, super::alpha_deg);
    let beta = series(records, super::beta_deg);
    let (alpha_roll, beta_roll) = (rolling_mae(&alpha.2), rolling_mae(&beta.2));
    let spans = flagged_spans(records);
    let faults: Vec<(f64, f64)> = p
        .faults
        .iter()
        .filter_map(|f| f.parse::<crate::faults::Fault>().ok())
        .map(|f| (f.start_s, f.start_s + f.duration_s))
        .collect();
    let panels = [
        Panel {
            label: "α (deg)",
            lines: vec![(&alpha.0, TRUTH, 5), (&alpha.1, ESTIMATE, 1)],
        },
        Panel {
            label: "β (deg)",
            lines: vec![(&beta.0, TRUTH, 5), (&beta.1, ESTIMATE, 1)],
        },
        Panel {
            label: "α error (deg)",
            lines: vec![(&alpha.2, ERROR, 1), (&alpha_roll, ROLLING, 2)],
        },
        Panel {
            label: "β error (deg)",
            lines: vec![(&beta.2, ERROR, 1), (&beta_roll, ROLLING, 2)],
        },
    ];
    for (area, panel) in body.split_evenly((4, 1)).iter().zip(panels.iter()) {
        let all: Vec<&Points> = panel.lines.iter().map(|l| l.0).collect();
        let (lo, hi) = range(&all);
        let mut chart = ChartBuilder::on(area)
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(60)
            .build_cartesian_2d(t_start..t_end, lo..hi)
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc("flight time (s)")
            .y_desc(panel.label)
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(plot_err)?;
        // Faults under flags: a fault window that the estimator flagged shows the flag.
        for (shade, c, mix) in [(&faults, FAULT, 0.5), (&spans, FLAGGED, 0.8)] {
            chart
                .draw_series(
                    shade
                        .iter()
                        .map(|&(a, b)| Rectangle::new([(a, lo), (b, hi)], c.mix(mix).filled())),
                )
                .map_err(plot_err)?;
        }
        for (pts, color, width) in &panel.lines {
            chart
                .draw_series(LineSeries::new(
                    pts.iter().copied(),
                    color.stroke_width(*width),
                ))
                .map_err(plot_err)?;
        }
    }
    root.present().map_err(plot_err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rolling_mae_averages_the_last_ten_seconds() {
        let err: Points = (0..400)
            .map(|k| (k as f64 * 0.05, if k < 200 { 1.0 } else { -3.0 }))
            .collect();
        let r = rolling_mae(&err);
        assert_eq!(r[0].1, 1.0);
        assert_eq!(r[199].1, 1.0);
        // 10 s after the change, every frame in the window is off by 3.
        assert!((r[399].1 - 3.0).abs() < 1e-12, "{}", r[399].1);
    }
}

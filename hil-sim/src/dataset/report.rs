//! Dataset pictures and `dataset.md`: flight envelope, α/β histograms, one sample flight, and the
//! coverage numbers the trainer depends on (share of samples per α band, ranges of α, β, Mach).

use std::fmt::Write as _;
use std::path::Path;

use plotters::prelude::*;

use super::{DatasetError, Flight, Manifest, Split};

/// α bands of the report, deg: (label, low, high).
pub const ALPHA_BANDS: [(&str, f64, f64); 7] = [
    ("< 0", f64::NEG_INFINITY, 0.0),
    ("0–5", 0.0, 5.0),
    ("5–10", 5.0, 10.0),
    ("10–15", 10.0, 15.0),
    ("15–20", 15.0, 20.0),
    ("20–25", 20.0, 25.0),
    ("> 25", 25.0, f64::INFINITY),
];

/// Coverage of one split.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Coverage {
    pub flights: usize,
    pub samples: usize,
    pub duration_min: f64,
    /// Share of samples per [`ALPHA_BANDS`] entry, 0–1.
    pub alpha_band_share: [f64; ALPHA_BANDS.len()],
    pub alpha_deg: (f64, f64),
    pub beta_deg: (f64, f64),
    pub mach: (f64, f64),
    pub alt_m: (f64, f64),
    /// Share of samples with |β| > 5°.
    pub beta_over_5_share: f64,
}

impl Coverage {
    /// Share of samples above 15° α (the bands from 15° up), 0–1.
    pub fn above_15_share(&self) -> f64 {
        self.alpha_band_share
            .get(4..)
            .map_or(0.0, |s| s.iter().sum())
    }
}

/// (min, max) of `values`; (+∞, −∞) when there are none.
fn min_max(values: impl IntoIterator<Item = f64>) -> (f64, f64) {
    values
        .into_iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
}

fn coverage(flights: &[&Flight]) -> Coverage {
    let mut c = Coverage {
        flights: flights.len(),
        alpha_deg: (f64::INFINITY, f64::NEG_INFINITY),
        beta_deg: (f64::INFINITY, f64::NEG_INFINITY),
        mach: (f64::INFINITY, f64::NEG_INFINITY),
        alt_m: (f64::INFINITY, f64::NEG_INFINITY),
        ..Coverage::default()
    };
    let mut counts = [0usize; ALPHA_BANDS.len()];
    let mut beta5 = 0usize;
    let mm = |r: &mut (f64, f64), v: f64| {
        r.0 = r.0.min(v);
        r.1 = r.1.max(v);
    };
    for f in flights {
        c.duration_min += f.samples.len() as f64 / f64::from(crate::flight::SAMPLE_HZ) / 60.0;
        for s in &f.samples {
            let t = &s.truth;
            c.samples += 1;
            if let Some(b) = ALPHA_BANDS
                .iter()
                .position(|(_, lo, hi)| t.alpha_deg >= *lo && t.alpha_deg < *hi)
            {
                counts[b] += 1;
            }
            beta5 += usize::from(t.beta_deg.abs() > 5.0);
            mm(&mut c.alpha_deg, t.alpha_deg);
            mm(&mut c.beta_deg, t.beta_deg);
            mm(&mut c.mach, t.mach);
            mm(&mut c.alt_m, t.alt_msl_m);
        }
    }
    let n = c.samples.max(1) as f64;
    for (share, k) in c.alpha_band_share.iter_mut().zip(counts) {
        *share = k as f64 / n;
    }
    c.beta_over_5_share = beta5 as f64 / n;
    c
}

fn draw_err<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> DatasetError + '_ {
    move |e| DatasetError::Csv {
        path: path.to_path_buf(),
        message: format!("plot: {e}"),
    }
}

const TRAIN: RGBColor = RGBColor(31, 119, 180);
const TEST: RGBColor = RGBColor(214, 39, 40);

fn envelope(path: &Path, flights: &[(&Flight, Split)]) -> Result<(), DatasetError> {
    let e = draw_err(path);
    let root = BitMapBackend::new(path, (1000, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    let max_alt_kft = flights
        .iter()
        .flat_map(|(f, _)| {
            f.samples
                .iter()
                .map(|s| s.truth.alt_msl_m / crate::flight::FT_TO_M / 1000.0)
        })
        .fold(10.0f64, f64::max);
    let max_mach = flights
        .iter()
        .flat_map(|(f, _)| f.samples.iter().map(|s| s.truth.mach))
        .fold(1.0f64, f64::max);
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Flight envelope (blue: training flights, red: test flights, drawn on top)",
            ("sans-serif", 26),
        )
        .margin(15)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..max_mach * 1.05, 0.0..max_alt_kft * 1.05)
        .map_err(&e)?;
    chart
        .configure_mesh()
        .x_desc("Mach")
        .y_desc("altitude MSL, 1000 ft")
        .label_style(("sans-serif", 18))
        .draw()
        .map_err(&e)?;
    // Training points first and faint, test flights on top as a line of larger dots: the test
    // flights are few and must stay visible in the training cloud.
    let mut ordered: Vec<&(&Flight, Split)> = flights.iter().collect();
    ordered.sort_by_key(|(_, split)| *split == Split::Test);
    for (f, split) in ordered {
        let (color, size, alpha) = if *split == Split::Train {
            (TRAIN, 1, 0.25)
        } else {
            (TEST, 2, 0.9)
        };
        chart
            .draw_series(f.samples.iter().step_by(10).map(|s| {
                Circle::new(
                    (
                        s.truth.mach,
                        s.truth.alt_msl_m / crate::flight::FT_TO_M / 1000.0,
                    ),
                    size,
                    color.mix(alpha).filled(),
                )
            }))
            .map_err(&e)?;
    }
    root.present().map_err(&e)?;
    Ok(())
}

fn histogram(
    path: &Path,
    title: &str,
    xlabel: &str,
    split: &str,
    values: &[f64],
    bin: f64,
    range: (f64, f64),
) -> Result<(), DatasetError> {
    let e = draw_err(path);
    let lo = (range.0 / bin).floor() * bin;
    let hi = (range.1 / bin).ceil() * bin;
    let nbins = (((hi - lo) / bin).round() as usize).max(1);
    let mut counts = vec![0usize; nbins];
    for v in values {
        let k = ((v - lo) / bin).floor();
        if k >= 0.0 && (k as usize) < nbins {
            counts[k as usize] += 1;
        }
    }
    let n = values.len().max(1) as f64;
    let max_pct = counts
        .iter()
        .map(|c| *c as f64 / n * 100.0)
        .fold(1.0, f64::max);
    let root = BitMapBackend::new(path, (1000, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 26))
        .margin(15)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(lo..hi, 0.0..max_pct * 1.1)
        .map_err(&e)?;
    chart
        .configure_mesh()
        .x_desc(xlabel)
        .y_desc(format!("% of {split} samples"))
        .label_style(("sans-serif", 18))
        .draw()
        .map_err(&e)?;
    chart
        .draw_series(counts.iter().enumerate().map(|(k, c)| {
            let x0 = lo + k as f64 * bin;
            Rectangle::new(
                [(x0, 0.0), (x0 + bin, *c as f64 / n * 100.0)],
                TRAIN.filled(),
            )
        }))
        .map_err(&e)?;
    root.present().map_err(&e)?;
    Ok(())
}

fn sample_flight(path: &Path, f: &Flight) -> Result<(), DatasetError> {
    let e = draw_err(path);
    let root = BitMapBackend::new(path, (1200, 1000)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    let (title, body) = root.split_vertically(40);
    title
        .draw(&Text::new(
            format!("Sample flight {} ({:.0} s)", f.name, f.duration_s()),
            (15, 8),
            ("sans-serif", 24),
        ))
        .map_err(&e)?;
    let panels = body.split_evenly((4, 1));
    let t_end = f.duration_s().max(1.0);
    type Get = fn(&super::Sample) -> f64;
    let series: [(&str, Get); 4] = [
        ("altitude, 1000 ft", |s| {
            s.truth.alt_msl_m / crate::flight::FT_TO_M / 1000.0
        }),
        ("Mach", |s| s.truth.mach),
        ("α, deg", |s| s.truth.alpha_deg),
        ("β, deg", |s| s.truth.beta_deg),
    ];
    for (area, (label, get)) in panels.iter().zip(series) {
        let (lo, hi) = min_max(f.samples.iter().map(get));
        let pad = ((hi - lo) * 0.05).max(0.1);
        let mut chart = ChartBuilder::on(area)
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..t_end, (lo - pad)..(hi + pad))
            .map_err(&e)?;
        chart
            .configure_mesh()
            .y_desc(label)
            .x_desc("time, s")
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(&e)?;
        chart
            .draw_series(LineSeries::new(
                f.samples.iter().map(|s| (s.time_s, get(s))),
                TRAIN,
            ))
            .map_err(&e)?;
    }
    root.present().map_err(&e)?;
    Ok(())
}

/// North and east offsets, m, of `(lat_deg, lon_deg)` from `(lat0_deg, lon0_deg)` on the WGS84
/// ellipsoid, with the meridian and normal radii of curvature at the mean latitude. A flat-earth
/// approximation for plots: about 0.1 % of the distance within 100 km.
pub fn north_east_m(lat0_deg: f64, lon0_deg: f64, lat_deg: f64, lon_deg: f64) -> (f64, f64) {
    const A_M: f64 = 6_378_137.0;
    const E2: f64 = 6.694_379_990_14e-3;
    let mean_lat = (0.5 * (lat_deg + lat0_deg)).to_radians();
    let s = mean_lat.sin();
    let w = (1.0 - E2 * s * s).sqrt();
    let r_meridian = A_M * (1.0 - E2) / (w * w * w);
    let r_normal = A_M / w;
    // Across the antimeridian the short way round.
    let dlon = (lon_deg - lon0_deg + 540.0).rem_euclid(360.0) - 180.0;
    (
        (lat_deg - lat0_deg).to_radians() * r_meridian,
        dlon.to_radians() * r_normal * mean_lat.cos(),
    )
}

/// Paper Fig. 4: the path of one flight in 3-D (east, north, altitude) beside its ground track,
/// both in km from the first sample; green dot = start, red = end.
fn flight_path(path: &Path, f: &Flight) -> Result<(), DatasetError> {
    let e = draw_err(path);
    let (Some(first), Some(last)) = (f.samples.first(), f.samples.last()) else {
        return Ok(());
    };
    let ne = |s: &super::Sample| {
        let (n, e) = north_east_m(
            first.truth.lat_deg,
            first.truth.lon_deg,
            s.truth.lat_deg,
            s.truth.lon_deg,
        );
        (e / 1000.0, n / 1000.0, s.truth.alt_msl_m / 1000.0)
    };
    let pts: Vec<(f64, f64, f64)> = f.samples.iter().map(ne).collect();
    let range = |k: fn(&(f64, f64, f64)) -> f64| min_max(pts.iter().map(k));
    let (e0, e1) = range(|p| p.0);
    let (n0, n1) = range(|p| p.1);
    let (a0, a1) = range(|p| p.2);
    // Same scale on both horizontal axes, so turns look like turns.
    let half = ((e1 - e0).max(n1 - n0) * 0.55).max(1.0);
    let (ec, nc) = (0.5 * (e0 + e1), 0.5 * (n0 + n1));
    let (ex, nx) = ((ec - half)..(ec + half), (nc - half)..(nc + half));
    let ax = 0.0f64.min(a0)..(a1 * 1.05).max(1.0);

    let root = BitMapBackend::new(path, (1500, 750)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    let (title, body) = root.split_vertically(40);
    title
        .draw(&Text::new(
            format!(
                "Flight path of {} ({:.0} s, {:.0} km flown over ground)",
                f.name,
                f.duration_s(),
                pts.windows(2)
                    .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
                    .sum::<f64>()
            ),
            (15, 8),
            ("sans-serif", 24),
        ))
        .map_err(&e)?;
    let (left, right) = body.split_horizontally(800);

    let mut c3 = ChartBuilder::on(&left)
        .margin(20)
        .caption("3-D path (km)", ("sans-serif", 18))
        .build_cartesian_3d(nx.clone(), ax.clone(), ex.clone())
        .map_err(&e)?;
    c3.with_projection(|mut p| {
        p.pitch = 0.45;
        p.yaw = 0.6;
        p.scale = 0.8;
        p.into_matrix()
    });
    c3.configure_axes()
        .label_style(("sans-serif", 13))
        .max_light_lines(3)
        .draw()
        .map_err(&e)?;
    // (north, up, east) is right-handed, as plotters' projection is: (east, up, north) would draw
    // the path mirrored. Shadow on the ground first, then the path.
    c3.draw_series(LineSeries::new(
        pts.iter().map(|p| (p.1, ax.start, p.0)),
        RGBColor(190, 190, 190),
    ))
    .map_err(&e)?;
    c3.draw_series(LineSeries::new(pts.iter().map(|p| (p.1, p.2, p.0)), TRAIN))
        .map_err(&e)?;
    let (s, z) = (ne(first), ne(last));
    c3.draw_series([
        Circle::new((s.1, s.2, s.0), 6, RGBColor(44, 160, 44).filled()),
        Circle::new((z.1, z.2, z.0), 6, TEST.filled()),
    ])
    .map_err(&e)?;
    // The 3-D axes carry no titles in plotters: say which is which.
    left.draw(&Text::new(
        "x: north, y: altitude, z: east (km)",
        (20, 680),
        ("sans-serif", 15),
    ))
    .map_err(&e)?;

    let mut c2 = ChartBuilder::on(&right)
        .margin(20)
        .caption("Ground track", ("sans-serif", 18))
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(ex, nx)
        .map_err(&e)?;
    c2.configure_mesh()
        .x_desc("east, km")
        .y_desc("north, km")
        .label_style(("sans-serif", 15))
        .draw()
        .map_err(&e)?;
    c2.draw_series(LineSeries::new(pts.iter().map(|p| (p.0, p.1)), TRAIN))
        .map_err(&e)?;
    c2.draw_series([
        Circle::new((s.0, s.1), 6, RGBColor(44, 160, 44).filled()),
        Circle::new((z.0, z.1), 6, TEST.filled()),
    ])
    .map_err(&e)?;
    root.present().map_err(&e)?;
    Ok(())
}

/// Coverage of the training and test splits.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Report {
    pub train: Coverage,
    pub test: Coverage,
}

/// Reads the dataset in `dir`, writes `envelope.png`, `alpha_hist.png`, `beta_hist.png`,
/// `sample_flight.png`, `flight_path.png` and `dataset.md` there, and returns the numbers.
pub fn write_report(dir: &Path) -> Result<Report, DatasetError> {
    let manifest = Manifest::read(dir)?;
    // Parsing the CSVs is most of the report's time: one reader per core.
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get());
    let read = super::par_map(
        &manifest.flights,
        workers,
        || {},
        |entry| manifest.read_flight(dir, &entry.file),
    );
    let flights = read.into_iter().collect::<Result<Vec<_>, _>>()?;
    write_report_of(dir, manifest, flights)
}

/// [`write_report`] from the flights already in memory, one per manifest entry in its order (as
/// `generate` holds them after writing the CSVs): the same files, without parsing the CSVs again.
/// The CSVs read back to the very same numbers (`csv_round_trip_is_exact`).
pub fn write_report_of(
    dir: &Path,
    manifest: Manifest,
    flights: Vec<Flight>,
) -> Result<Report, DatasetError> {
    crate::font::register();
    if flights.len() != manifest.flights.len() {
        return Err(DatasetError::Manifest {
            path: dir.join("manifest.json"),
            message: format!(
                "the report got {} flights for {} manifest entries",
                flights.len(),
                manifest.flights.len()
            ),
        });
    }
    let flights: Vec<(Flight, Split, String)> = flights
        .into_iter()
        .zip(&manifest.flights)
        .map(|(mut f, entry)| {
            f.cut = entry.cut.clone();
            f.zones = entry.zones;
            (f, entry.split, entry.profile.clone())
        })
        .collect();
    let of = |split| -> Vec<&Flight> {
        flights
            .iter()
            .filter(|(_, s, _)| *s == split)
            .map(|(f, _, _)| f)
            .collect()
    };
    let report = Report {
        train: coverage(&of(Split::Train)),
        test: coverage(&of(Split::Test)),
    };
    let all: Vec<(&Flight, Split)> = flights.iter().map(|(f, s, _)| (f, *s)).collect();
    envelope(&dir.join("envelope.png"), &all)?;
    // The pictures show the training split, or the test split of a dataset without training
    // samples (a `hil-sim fly` flight); nothing when there are no samples at all.
    let (shown, r, split) = if report.train.samples > 0 {
        (of(Split::Train), &report.train, "training")
    } else {
        (of(Split::Test), &report.test, "test")
    };
    if r.samples > 0 {
        let values = |get: fn(&super::Truth) -> f64| -> Vec<f64> {
            shown
                .iter()
                .flat_map(|f| f.samples.iter().map(move |s| get(&s.truth)))
                .collect()
        };
        histogram(
            &dir.join("alpha_hist.png"),
            "Angle of attack α (truth)",
            "α, deg",
            split,
            &values(|t| t.alpha_deg),
            1.0,
            r.alpha_deg,
        )?;
        histogram(
            &dir.join("beta_hist.png"),
            "Sideslip β (truth)",
            "β, deg",
            split,
            &values(|t| t.beta_deg),
            0.5,
            r.beta_deg,
        )?;
    }
    // The sample flight: the most varied one in α (the most informative picture).
    let spread = |f: &Flight| {
        let (lo, hi) = min_max(f.samples.iter().map(|s| s.truth.alpha_deg));
        hi - lo
    };
    if let Some(f) = shown
        .iter()
        .filter(|f| !f.samples.is_empty())
        .max_by(|a, b| spread(a).total_cmp(&spread(b)))
    {
        sample_flight(&dir.join("sample_flight.png"), f)?;
        flight_path(&dir.join("flight_path.png"), f)?;
    }
    let md = markdown(&manifest, &report, &flights);
    let path = dir.join("dataset.md");
    std::fs::write(&path, md).map_err(|source| DatasetError::Io {
        action: "write",
        path,
        source,
    })?;
    // Record the pictures and the report in the manifest too, so every file of the dataset is hashed.
    let mut manifest = manifest;
    for name in [
        "envelope.png",
        "alpha_hist.png",
        "beta_hist.png",
        "sample_flight.png",
        "flight_path.png",
        "dataset.md",
    ] {
        let p = dir.join(name);
        if p.is_file() {
            manifest
                .files
                .insert(name.to_string(), super::sha256_file(&p)?);
        }
    }
    manifest.write(dir)?;
    Ok(report)
}

fn markdown(m: &Manifest, r: &Report, flights: &[(Flight, Split, String)]) -> String {
    let mut s = String::new();
    match m.config.get("seed") {
        Some(seed) => {
            let _ = writeln!(s, "# Dataset `{}` (seed {seed})\n", m.preset);
        }
        None => {
            let _ = writeln!(s, "# Dataset `{}`\n", m.preset);
        }
    }
    let _ = writeln!(
        s,
        "JSBSim {} · git {} · 20 Hz · generated by `hil-sim {}`. Numbers below are measured \
         from the CSVs by `hil_sim::dataset::report`.\n",
        m.jsbsim_version,
        m.git_rev,
        if m.preset == "fly" { "fly" } else { "generate" }
    );
    let _ = writeln!(
        s,
        "| split | flights | samples | minutes | α min/max, ° | β min/max, ° | Mach min/max | alt min/max, m | share of abs(β) > 5° |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
    for (name, c) in [("train", &r.train), ("test", &r.test)] {
        if c.samples == 0 {
            continue;
        }
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {:.1} | {:.1} / {:.1} | {:.1} / {:.1} | {:.2} / {:.2} | {:.0} / {:.0} | {:.1}% |",
            c.flights,
            c.samples,
            c.duration_min,
            c.alpha_deg.0,
            c.alpha_deg.1,
            c.beta_deg.0,
            c.beta_deg.1,
            c.mach.0,
            c.mach.1,
            c.alt_m.0,
            c.alt_m.1,
            c.beta_over_5_share * 100.0
        );
    }
    let _ = writeln!(s, "\n## Share of samples per α band\n");
    let _ = writeln!(s, "| α band, ° | train | test |");
    let _ = writeln!(s, "|---|---|---|");
    for (k, (label, _, _)) in ALPHA_BANDS.iter().enumerate() {
        let _ = writeln!(
            s,
            "| {label} | {:.1}% | {:.1}% |",
            r.train.alpha_band_share[k] * 100.0,
            r.test.alpha_band_share[k] * 100.0
        );
    }
    let over15 = r.train.above_15_share();
    if r.train.flights > 0 {
        let _ = writeln!(s, "\nTraining samples above 15° α: {:.1}%.", over15 * 100.0);
    }
    let _ = writeln!(s);
    let _ = writeln!(s, "## Flights\n");
    let _ = writeln!(
        s,
        "Zones: time in the maneuver generator's Flight Zone (random maneuvers), Danger Zone \
         (recovery from a hazard) and Re-climb Zone (attitude controller climbing back), from the \
         script's `maneuver/zone` at every 120 Hz step (— for a script without zone state).\n"
    );
    let _ = writeln!(
        s,
        "| flight | split | profile | duration, s | α max, ° | Flight Zone | Danger Zone | Re-climb Zone | cut |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
    for (f, split, profile) in flights {
        let amax = f
            .samples
            .iter()
            .map(|x| x.truth.alpha_deg)
            .fold(f64::NEG_INFINITY, f64::max);
        let zone = |get: fn(&super::ZoneTimes) -> f64| match f.zones {
            Some(z) if z.total_s() > 0.0 => {
                format!("{:.0} s ({:.1}%)", get(&z), 100.0 * get(&z) / z.total_s())
            }
            _ => "—".to_string(),
        };
        let _ = writeln!(
            s,
            "| {} | {:?} | {profile} | {:.0} | {amax:.1} | {} | {} | {} | {} |",
            f.name,
            split,
            f.duration_s(),
            zone(|z| z.flight_s),
            zone(|z| z.danger_s),
            zone(|z| z.reclimb_s),
            f.cut.as_deref().unwrap_or("—")
        );
    }
    let _ = writeln!(
        s,
        "\nPictures: `envelope.png` (altitude vs Mach), `alpha_hist.png`, `beta_hist.png`, \
         `sample_flight.png` (time histories), `flight_path.png` (3-D path and ground track of the \
         same flight)."
    );
    s
}

#[cfg(test)]
mod tests {
    use super::north_east_m;

    /// One degree of latitude at 45° is 111,132.95 m and one of longitude 78,846.84 m (WGS84
    /// tables); across the antimeridian the offset is the short way.
    #[test]
    fn north_east_matches_wgs84_degree_lengths() {
        let (n, e) = north_east_m(44.5, 10.0, 45.5, 10.0);
        assert!((n - 111_132.95).abs() < 2.0, "north {n}");
        assert!(e.abs() < 1e-9);
        let (n, e) = north_east_m(45.0, 10.0, 45.0, 11.0);
        assert!(n.abs() < 1e-9);
        assert!((e - 78_846.84).abs() < 1.0, "east {e}");
        let (_, e) = north_east_m(0.0, 179.9, 0.0, -179.9);
        assert!((e - 22_263.9).abs() < 1.0, "east {e}");
    }
}

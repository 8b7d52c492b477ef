//! How much sideslip the F-16 reaches when the maneuver generator uses more rudder: one 300 s flight
//! (maneuver seed 7) per variant, the share of samples beyond 2° and 5° of |β|. The experiment
//! behind the sideslip note in `docs/results/dataset-paper.md`:
//!
//!     cargo run --release -p hil-sim --example beta_probe

use anyhow::Result;
use hil_sim::fly::{self, FlyConfig};
use hil_sim::maneuver::{self, Profile, ProfileKind};

fn main() -> Result<()> {
    let dir = std::env::temp_dir().join("hil-beta-probe");
    std::fs::create_dir_all(&dir)?;
    println!(
        "| variant | rudder amplitude | hold, s | start KCAS | abs(β) > 2° | abs(β) > 5° | max abs(β), ° |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (label, kind, amp, hold, vc) in [
        ("gentle (preset)", ProfileKind::Gentle, None, None, None),
        (
            "gentle, full rudder",
            ProfileKind::Gentle,
            Some(1.0),
            Some((3.0, 10.0)),
            None,
        ),
        (
            "gentle, full rudder, slow",
            ProfileKind::Gentle,
            Some(1.0),
            Some((3.0, 10.0)),
            Some((200.0, 260.0)),
        ),
        (
            "high-alpha (preset)",
            ProfileKind::HighAlpha,
            None,
            None,
            None,
        ),
        (
            "high-alpha, full rudder",
            ProfileKind::HighAlpha,
            Some(1.0),
            Some((3.0, 10.0)),
            None,
        ),
    ] {
        let mut p = Profile::preset(kind);
        p.rudder_amp = amp.unwrap_or(p.rudder_amp);
        p.rudder_hold_s = hold.unwrap_or(p.rudder_hold_s);
        p.init_vc_kts = vc.unwrap_or(p.init_vc_kts);
        let name = format!("probe_{}", kind.name());
        let script = maneuver::generate(&p, 7, &name, 300.0)?.write(&dir)?;
        let f = fly::fly_script(&script, &FlyConfig::default())?;
        let n = f.samples.len().max(1) as f64;
        let share = |lim: f64| {
            f.samples
                .iter()
                .filter(|s| s.truth.beta_deg.abs() > lim)
                .count() as f64
                / n
                * 100.0
        };
        let max = f
            .samples
            .iter()
            .map(|s| s.truth.beta_deg.abs())
            .fold(0.0, f64::max);
        println!(
            "| {label}{} | {:.1} | {:.0}–{:.0} | {:.0}–{:.0} | {:.1} % | {:.1} % | {max:.1} |",
            if f.cut.is_some() { " (cut)" } else { "" },
            p.rudder_amp,
            p.rudder_hold_s.0,
            p.rudder_hold_s.1,
            p.init_vc_kts.0,
            p.init_vc_kts.1,
            share(2.0),
            share(5.0),
        );
    }
    Ok(())
}

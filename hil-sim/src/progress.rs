//! Progress of long work on stderr, the same for every command: a bar with ETA on a terminal, and
//! otherwise (CI logs, `nohup`, a pipe) one plain line every few seconds, so a run that is not
//! watched live still shows how far it got and when it will end.

use std::io::IsTerminal;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Seconds between two progress lines when stderr is not a terminal.
pub const LOG_EVERY_S: u64 = 5;

/// A bar over `len` items named `unit` ("flights", "frames", "epochs"), with elapsed time and ETA,
/// drawn on stderr; `prefix` names the work.
pub fn bar(len: u64, unit: &str) -> ProgressBar {
    let pb = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    style(&pb, unit);
    log_when_not_a_terminal(&pb, unit);
    pb
}

/// The common style: `{prefix} {elapsed} [bar] pos/len unit, ETA {eta} {msg}`, the ETA from the
/// mean rate so far ([`eta`]).
pub fn style(pb: &ProgressBar, unit: &str) {
    let template = format!(
        "{{prefix}} {{elapsed_precise}} [{{bar:30}}] {{pos}}/{{len}} {unit}, ETA {{eta}} {{msg}}"
    );
    pb.set_style(
        ProgressStyle::with_template(&template)
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .with_key(
                "eta",
                |s: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                    let _ = w.write_str(&eta(s.pos(), s.len().unwrap_or(0), s.elapsed()));
                },
            )
            .progress_chars("=> "),
    );
}

/// The time left at the mean rate so far: `elapsed` · (`len` − `pos`) / `pos` (`-` before the
/// first item and after the last). indicatif's own estimate weights the recent rate, which decays
/// while no item ends: for items a minute long (training epochs) it read hours between two ticks.
pub fn eta(pos: u64, len: u64, elapsed: Duration) -> String {
    if pos == 0 || pos >= len {
        return "-".to_string();
    }
    duration(elapsed.mul_f64((len - pos) as f64 / pos as f64))
}

/// When stderr is not a terminal (indicatif then draws nothing), prints the bar's state as one
/// line every [`LOG_EVERY_S`] seconds until the bar is finished or dropped.
pub fn log_when_not_a_terminal(pb: &ProgressBar, unit: &str) {
    if std::io::stderr().is_terminal() {
        return;
    }
    let weak = pb.downgrade();
    let unit = unit.to_string();
    std::thread::spawn(move || {
        loop {
            std::thread::sleep(Duration::from_secs(LOG_EVERY_S));
            let Some(pb) = weak.upgrade() else { return };
            if pb.is_finished() {
                return;
            }
            eprintln!("{}", line(&pb, &unit));
        }
    });
}

/// One progress line: `prefix: pos/len unit, 1m 05s elapsed, ETA 2m 10s; msg`.
pub fn line(pb: &ProgressBar, unit: &str) -> String {
    let len = pb.length().unwrap_or(0);
    let pos = pb.position();
    let eta = eta(pos, len, pb.elapsed());
    let prefix = pb.prefix();
    let msg = pb.message();
    format!(
        "{}{pos}/{len} {unit}, {} elapsed, ETA {eta}{}",
        if prefix.is_empty() {
            String::new()
        } else {
            format!("{prefix}: ")
        },
        duration(pb.elapsed()),
        if msg.is_empty() {
            String::new()
        } else {
            format!("; {msg}")
        }
    )
}

/// `1h 02m 03s`, `2m 05s`, `7s`: whole seconds, as a person reads a duration.
pub fn duration(d: Duration) -> String {
    let s = d.as_secs();
    match (s / 3600, s / 60 % 60, s % 60) {
        (0, 0, s) => format!("{s}s"),
        (0, m, s) => format!("{m}m {s:02}s"),
        (h, m, s) => format!("{h}h {m:02}m {s:02}s"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_as_whole_seconds() {
        assert_eq!(duration(Duration::from_millis(999)), "0s");
        assert_eq!(duration(Duration::from_secs(65)), "1m 05s");
        assert_eq!(duration(Duration::from_secs(3723)), "1h 02m 03s");
    }

    #[test]
    fn the_eta_is_the_mean_rate_so_far() {
        assert_eq!(eta(4, 30, Duration::from_secs(160)), "17m 20s");
        assert_eq!(eta(0, 30, Duration::from_secs(160)), "-");
        assert_eq!(eta(30, 30, Duration::from_secs(160)), "-");
    }

    #[test]
    fn a_line_names_the_position_and_the_message() {
        let pb = ProgressBar::hidden();
        pb.set_length(10);
        pb.set_position(4);
        pb.set_prefix("train α");
        pb.set_message("val 0.135");
        let l = line(&pb, "epochs");
        assert!(l.starts_with("train α: 4/10 epochs, "), "{l}");
        assert!(l.ends_with("; val 0.135"), "{l}");
    }
}

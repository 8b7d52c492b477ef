//! What a user gets wrong on the command line is refused: a non-zero exit that is not a panic, a
//! message that names the problem, and nothing half-written. One test per mistake, run against the
//! built `hil-sim` and `trainer` binaries (beside this test's executable), on a `ci` dataset they
//! generate.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

/// A binary of the workspace, built with this test (`target/<profile>/NAME`).
fn bin(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    let dir = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile>/deps");
    dir.join(name)
}

fn run(program: &str, args: &[&str]) -> Output {
    Command::new(bin(program))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("RUST_BACKTRACE")
        .output()
        .unwrap_or_else(|e| panic!("cannot start {program}: {e}"))
}

/// Refused: exit code 1 (an error) or 2 (clap's usage error), never 101 (a panic); the message
/// holds `needle`.
fn refused(o: &Output, needle: &str) {
    let stderr = String::from_utf8_lossy(&o.stderr);
    let code = o.status.code();
    assert!(
        code == Some(1) || code == Some(2),
        "exit {code:?}, wanted a refusal; stderr:\n{stderr}"
    );
    assert!(
        stderr.contains(needle),
        "stderr lacks `{needle}`:\n{stderr}"
    );
    assert!(!stderr.contains("panicked"), "a panic:\n{stderr}");
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "exit {:?}; stderr:\n{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
}

fn scratch(tag: &str) -> PathBuf {
    tests::scratch(env!("CARGO_TARGET_TMPDIR"), &format!("cli-{tag}"))
}

/// The `ci` preset (5 flights of 3 minutes), generated once for every test here.
fn ci() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = scratch("ci").join("data");
        ok(&run(
            "hil-sim",
            &["generate", "--preset", "ci", "--out", d.to_str().unwrap()],
        ));
        d
    })
}

fn test_csv() -> PathBuf {
    ci().join("test_aggressive_00.csv")
}

/// The flight CSV with `edit` applied to its rows (header first) and only the columns `keep` says.
fn rewrite(out: &Path, keep: impl Fn(&str) -> bool, edit: impl Fn(&mut Vec<Vec<String>>)) {
    let text = std::fs::read_to_string(test_csv()).unwrap();
    let mut rows: Vec<Vec<String>> = text
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    let cols: Vec<usize> = (0..rows[0].len()).filter(|&i| keep(&rows[0][i])).collect();
    rows = rows
        .into_iter()
        .map(|r| cols.iter().map(|&i| r[i].clone()).collect())
        .collect();
    edit(&mut rows);
    let body: Vec<String> = rows.iter().map(|r| r.join(",")).collect();
    std::fs::write(out, body.join("\n") + "\n").unwrap();
}

/// Sensed columns only: time and everything from the first sensor channel on.
fn sensed_only(h: &str) -> bool {
    h == "time_s" || !hil_sim::flight::TRUTH_COLUMNS.contains(&h)
}

/// An aircraft description of this tree that is not the build's.
fn other_aircraft() -> &'static str {
    estimator_core::aircraft::descriptions()
        .find(|n| *n != estimator_core::aircraft::AIRCRAFT.name)
        .expect("the tree describes more than one aircraft")
}

/// `--aircraft` on every command of both binaries: this build's aircraft is accepted, another one
/// refused before anything runs, with how to build for it; a name no description has is refused
/// with the names there are.
#[test]
fn another_aircraft_is_refused_with_how_to_build_for_it() {
    let other = other_aircraft();
    for (b, args) in [
        ("hil-sim", &["run", "--script", "nowhere.xml"][..]),
        (
            "hil-sim",
            &["fly", "--script", "nowhere.xml", "--out", "nowhere"][..],
        ),
        ("trainer", &["eval", "--data", "nowhere"][..]),
    ] {
        let o = run(b, &[args, &["--aircraft", other]].concat());
        refused(&o, "this build is for `f16`");
        refused(&o, &format!("ESTIMATOR_AIRCRAFT={other}"));
        let o = run(b, &[args, &["--aircraft", "f61"]].concat());
        refused(&o, "no aircraft is described as `f61`");
        refused(
            &o,
            &estimator_core::aircraft::DESCRIPTIONS.replace(',', ", "),
        );
        // The build's own aircraft passes the flag, and the command goes on (to its own error).
        let o = run(b, &[args, &["--aircraft", "f16"]].concat());
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!stderr.contains("this build is for"), "{stderr}");
    }
}

/// A dataset's flight whose manifest names another aircraft is not streamed to this build's
/// estimator: its frames would carry this build's aircraft and be read with its networks.
#[test]
fn run_refuses_a_dataset_flight_of_another_aircraft() {
    let other = other_aircraft();
    let d = scratch("other-aircraft");
    std::fs::create_dir_all(&d).unwrap();
    std::fs::copy(test_csv(), d.join("test_aggressive_00.csv")).unwrap();
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(ci().join("manifest.json")).unwrap())
            .unwrap();
    m["aircraft"]["name"] = other.into();
    std::fs::write(d.join("manifest.json"), m.to_string()).unwrap();
    let out = d.join("run");
    let o = run(
        "hil-sim",
        &[
            "run",
            "--dataset",
            d.join("test_aggressive_00.csv").to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
    );
    refused(&o, &format!("flew the aircraft `{other}`"));
    refused(&o, &format!("ESTIMATOR_AIRCRAFT={other}"));
    assert!(!out.exists(), "a refused run wrote {}", out.display());
}

#[test]
fn both_binaries_have_a_version() {
    for b in ["hil-sim", "trainer"] {
        let o = run(b, &["--version"]);
        ok(&o);
        assert!(String::from_utf8_lossy(&o.stdout).starts_with(b));
    }
}

/// Output piped into a reader that has stopped (`trainer … | head`) ends the binary quietly by
/// SIGPIPE, as any Unix tool, never by a panic on the closed pipe. Here the pipe's read end is
/// closed before the binary starts, so its first line meets it closed.
#[cfg(unix)]
#[test]
fn both_binaries_stop_quietly_on_a_closed_pipe() {
    use std::os::unix::process::ExitStatusExt;
    let out = scratch("closed-pipe");
    for (program, args) in [
        (
            "trainer",
            vec!["sweep", "--list", "--data", "no-such-data", "--out"],
        ),
        ("hil-sim", vec!["generate", "--help"]),
    ] {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let mut cmd = Command::new(bin(program));
        cmd.args(&args).env_remove("RUST_BACKTRACE");
        if program == "trainer" {
            cmd.arg(&out);
        }
        let o = cmd.stdout(writer).output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!stderr.contains("panicked"), "{program}: {stderr}");
        // Killed by SIGPIPE (13 on Linux and the BSDs).
        assert_eq!(
            o.status.signal(),
            Some(13),
            "{program}: {:?}, {stderr}",
            o.status
        );
    }
}

#[test]
fn fly_refuses_a_duration_that_is_not_positive_and_writes_nothing() {
    let d = scratch("fly-time");
    let out = d.join("fly");
    for bad in ["0", "-5", "nan", "inf"] {
        let o = run(
            "hil-sim",
            &[
                "fly",
                "--script",
                "../flights/f16_test_flight.xml",
                "--out",
                out.to_str().unwrap(),
                "--max-time-s",
                bad,
            ],
        );
        refused(&o, "positive number of seconds");
        assert!(!out.exists(), "--max-time-s {bad} left {}", out.display());
    }
}

#[test]
fn a_campaign_needs_its_hours() {
    let out = scratch("campaign").join("c");
    let o = run(
        "hil-sim",
        &[
            "generate",
            "--preset",
            "campaign",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    refused(&o, "--preset campaign needs --hours");
    assert!(!out.exists());
}

#[test]
fn generate_refuses_to_overwrite_a_dataset_without_force() {
    let manifest = std::fs::read(ci().join("manifest.json")).unwrap();
    let o = run(
        "hil-sim",
        &[
            "generate",
            "--preset",
            "ci",
            "--out",
            ci().to_str().unwrap(),
        ],
    );
    refused(&o, "pass --force to replace it");
    assert_eq!(std::fs::read(ci().join("manifest.json")).unwrap(), manifest);
}

#[test]
fn generate_with_force_replaces_a_dataset_and_leaves_no_partial_directory() {
    let d = scratch("force");
    let out = d.join("data");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("stale.txt"), "old").unwrap();
    ok(&run(
        "hil-sim",
        &[
            "generate",
            "--preset",
            "ci",
            "--seed",
            "3",
            "--force",
            "--out",
            out.to_str().unwrap(),
        ],
    ));
    assert!(out.join("manifest.json").is_file());
    assert!(
        !out.join("stale.txt").exists(),
        "the old dataset's files stayed"
    );
    let left: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert_eq!(left, vec![std::ffi::OsString::from("data")], "{left:?}");
}

#[test]
fn a_killed_generate_leaves_nothing_at_out() {
    let d = scratch("killed");
    let out = d.join("data");
    let mut child = Command::new(bin("hil-sim"))
        .args(["generate", "--preset", "ci", "--out", out.to_str().unwrap()])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(700));
    let _ = child.kill();
    let _ = child.wait();
    // Killed mid-way: nothing at --out. Finished before the kill: a whole dataset.
    assert!(
        !out.exists() || out.join("manifest.json").is_file(),
        "a half-written dataset at {}",
        out.display()
    );
}

#[test]
fn run_refuses_a_suite_the_compiled_in_model_cannot_read() {
    let Some(shipped) = estimator_core::Estimator::shipped().suite() else {
        return; // no model: nothing to refuse
    };
    // Every suite whose frames lack what the model reads (none for a table1 model).
    for smaller in estimator_core::Suite::ALL
        .into_iter()
        .filter(|s| !s.delivers(shipped))
    {
        let o = run(
            "hil-sim",
            &[
                "run",
                "--dataset",
                test_csv().to_str().unwrap(),
                "--suite",
                smaller.name(),
            ],
        );
        refused(&o, &format!("pass --suite {}", shipped.name()));
    }
}

#[test]
fn run_refuses_a_port_with_a_firmware_that_is_not_a_board() {
    let o = run(
        "hil-sim",
        &[
            "run",
            "--dataset",
            test_csv().to_str().unwrap(),
            "--firmware",
            "host",
            "--port",
            "/dev/ttyUSB0",
        ],
    );
    refused(&o, "--port /dev/ttyUSB0 goes with a flashed board");
}

#[test]
fn run_refuses_a_fault_after_the_flight() {
    let o = run(
        "hil-sim",
        &[
            "run",
            "--dataset",
            test_csv().to_str().unwrap(),
            "--fault",
            "gps-loss@900+10",
            "--out",
            scratch("fault").to_str().unwrap(),
        ],
    );
    refused(&o, "after the flight's last sample");
}

#[test]
fn run_refuses_a_log_that_is_not_20_hz() {
    let d = scratch("10hz");
    let csv = d.join("log.csv");
    rewrite(&csv, sensed_only, |rows| {
        let header = rows.remove(0);
        let every_other: Vec<_> = rows.iter().step_by(2).cloned().collect();
        *rows = std::iter::once(header).chain(every_other).collect();
    });
    let o = run(
        "hil-sim",
        &[
            "run",
            "--dataset",
            csv.to_str().unwrap(),
            "--out",
            d.join("run").to_str().unwrap(),
        ],
    );
    refused(&o, "(10.0 Hz); the estimator runs at 20 Hz");
    assert!(!d.join("run").exists());
}

#[test]
fn run_refuses_a_log_whose_time_runs_backwards() {
    let d = scratch("back");
    let csv = d.join("log.csv");
    rewrite(&csv, sensed_only, |rows| rows.swap(10, 11));
    let o = run(
        "hil-sim",
        &[
            "run",
            "--dataset",
            csv.to_str().unwrap(),
            "--out",
            d.join("run").to_str().unwrap(),
        ],
    );
    refused(&o, "time_s does not increase at row 12");
    // Streamed as they are on request (the firmware's own time handling under test).
    ok(&run(
        "hil-sim",
        &[
            "run",
            "--dataset",
            csv.to_str().unwrap(),
            "--any-time-base",
            "--out",
            d.join("run").to_str().unwrap(),
        ],
    ));
}

#[test]
fn a_log_of_sensed_channels_only_runs_and_writes_estimates() {
    let d = scratch("log");
    let csv = d.join("my_flight.csv");
    rewrite(&csv, sensed_only, |_| {});
    let out = d.join("run");
    let o = run(
        "hil-sim",
        &[
            "run",
            "--dataset",
            csv.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--json",
        ],
    );
    ok(&o);
    let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(s["frames_sent"], 3600);
    assert_eq!(s["frames_with_truth"], 0);
    assert!(s["alpha_mae_deg"].is_null() && s["beta_mae_deg"].is_null());
    assert_eq!(s["provenance"]["flight"], "my_flight");
    let est = std::fs::read_to_string(out.join("estimates.csv")).unwrap();
    let mut lines = est.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert!(header.contains(&"alpha_deg") && header.contains(&"flag_turbulence"));
    let first: Vec<&str> = lines.next().unwrap().split(',').collect();
    // No truth: empty truth cells, a computed estimate.
    assert_eq!((first[2], first[3], first[4]), ("", "", "1"));
    assert!(first[5].parse::<f64>().is_ok());
}

#[test]
fn train_refuses_settings_that_cannot_train() {
    for (flag, needle) in [
        ("--batch=0", "must be at least 1"),
        ("--epochs=0", "must be at least 1"),
        ("--lr=-1", "positive number"),
        ("--lr=nan", "positive number"),
        ("--val-fraction=1.5", "strictly between 0 and 1"),
        ("--val-fraction=0", "strictly between 0 and 1"),
    ] {
        let o = run("trainer", &["train", "--data", "no-such-dir", flag]);
        refused(&o, needle);
    }
    let o = run("trainer", &["bench-train", "--data", "d", "--seeds", "3,3"]);
    refused(&o, "a seed is repeated");
}

#[test]
fn a_missing_manifest_is_said_once() {
    let o = run("trainer", &["eval", "--data", "no-such-dataset"]);
    refused(&o, "no-such-dataset/manifest.json");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(stderr.matches("No such file").count(), 1, "{stderr}");
}

#[test]
fn eval_refuses_a_truth_column_that_is_not_a_number() {
    let d = scratch("nan-truth");
    let data = d.join("data");
    std::fs::create_dir_all(&data).unwrap();
    for e in std::fs::read_dir(ci()).unwrap().flatten() {
        std::fs::copy(e.path(), data.join(e.file_name())).unwrap();
    }
    let csv = data.join("test_aggressive_00.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let col = lines[0].split(',').position(|h| h == "alpha_deg").unwrap();
    let mut cells: Vec<&str> = lines[5].split(',').collect();
    cells[col] = "NaN";
    lines[5] = cells.join(",");
    std::fs::write(&csv, lines.join("\n") + "\n").unwrap();
    let o = run("trainer", &["eval", "--data", data.to_str().unwrap()]);
    refused(&o, "line 6: the truth column `alpha_deg` is `NaN`");
}

#[test]
fn eval_reads_a_one_flight_dataset_from_fly() {
    let d = scratch("fly-eval");
    let fly = d.join("fly");
    ok(&run(
        "hil-sim",
        &[
            "fly",
            "--script",
            "../flights/f16_test_flight.xml",
            "--max-time-s",
            "20",
            "--out",
            fly.to_str().unwrap(),
        ],
    ));
    let o = run(
        "trainer",
        &["eval", "--data", fly.to_str().unwrap(), "--json"],
    );
    if estimator_core::model::HAS_MODEL {
        ok(&o);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["alpha"]["overall"]["n"], 400);
    }
    let o = run(
        "trainer",
        &["eval", "--data", fly.to_str().unwrap(), "--split", "train"],
    );
    refused(&o, "has no train flight; pass --split test");
}

/// A path as the `&str` an argument list takes.
fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `--hours inf` once panicked planning an endless campaign, `1e15` aborted allocating it.
#[test]
fn a_campaign_of_endless_hours_is_refused_and_writes_nothing() {
    let d = scratch("hours");
    let out = d.join("c");
    for hours in ["inf", "1e15", "NaN", "10000.5"] {
        let o = run(
            "hil-sim",
            &[
                "generate",
                "--preset",
                "campaign",
                "--hours",
                hours,
                "--out",
                s(&out),
            ],
        );
        refused(&o, "more than 0 and at most 10000");
    }
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0);
}

/// Values of ±1e308 once made the axis code spin forever; no panel once left a 12-byte PNG.
#[test]
fn a_plot_that_cannot_be_drawn_is_refused_and_writes_nothing() {
    let d = scratch("plots");
    let png = d.join("x.png");
    let spec = d.join("spec.json");
    for (cmd, text, needle) in [
        (
            "lines",
            r#"{"panels":[{"title":"t","xlabel":"x","ylabel":"y","series":[{"name":"s","points":[[0,1e308],[1,-1e308]]}]}]}"#,
            "too wide for an axis",
        ),
        (
            "bars",
            r#"{"series":["a"],"panels":[{"title":"t","xlabel":"x","rows":[["r1",[1e308]],["r2",[-1e308]]]}]}"#,
            "too wide for an axis",
        ),
        (
            "bars",
            r#"{"series":["a"],"panels":[]}"#,
            "no panel to draw",
        ),
    ] {
        std::fs::write(&spec, text).unwrap();
        refused(
            &run("trainer", &[cmd, "--spec", s(&spec), "--out", s(&png)]),
            needle,
        );
        assert!(!png.exists(), "{cmd}: {text} left {}", png.display());
    }
    for out in ["x.txt", "x"] {
        let o = run(
            "trainer",
            &["bars", "--spec", s(&spec), "--out", s(&d.join(out))],
        );
        refused(&o, "give a file name ending in .png");
    }
}

/// An --out that names a file is refused before the dataset is read or anything trains.
#[test]
fn an_out_that_is_a_file_is_refused_before_any_work() {
    let d = scratch("outfile");
    let file = d.join("afile");
    std::fs::write(&file, "x").unwrap();
    let missing = d.join("no-dataset");
    for args in [
        &["train", "--data", s(&missing), "--out", s(&file)][..],
        &["bench-epoch", "--data", s(&missing), "--out", s(&file)],
        &[
            "finetune",
            "--model",
            s(&missing),
            "--flight-test",
            s(&missing),
            "--out",
            s(&file),
        ],
    ] {
        refused(&run("trainer", args), "is a file, not a directory");
    }
    refused(
        &run(
            "hil-sim",
            &["generate", "--preset", "ci", "--out", s(&file)],
        ),
        "is a file, not a directory",
    );
    assert_eq!(std::fs::read(&file).unwrap(), b"x");
}

/// `hil-sim run`: a flag of another firmware and a board without a port are refused alike.
#[test]
fn run_refuses_flags_of_another_firmware() {
    let csv = "no-such-log.csv";
    for (extra, needle) in [
        (
            &["--firmware", "serial"][..],
            "--firmware serial needs --port",
        ),
        (
            &["--firmware", "host", "--elf", "x.elf"],
            "--elf x.elf goes with QEMU (--firmware qemu), not --firmware host",
        ),
        (
            &["--firmware", "host", "--qemu-link", "usart"],
            "--qemu-link usart goes with QEMU",
        ),
        (&["--firmware", "host", "--baud", "0"], "give a baud rate"),
    ] {
        let mut args = vec!["run", "--dataset", csv];
        args.extend_from_slice(extra);
        refused(&run("hil-sim", &args), needle);
    }
}

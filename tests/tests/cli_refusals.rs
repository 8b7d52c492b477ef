//! Mistakes refused before any work, against the built `hil-sim` and `trainer` binaries (beside
//! this test's executable; `cargo build --release -p hil-sim -p trainer` first): a non-zero exit
//! that is not a panic, a message that says what to do, and nothing left at the output. None of
//! these needs a dataset: each is refused before one would be read.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

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

/// Exit 1 or 2, never a panic, and the message holds `needle`.
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

fn scratch(tag: &str) -> PathBuf {
    tests::scratch(env!("CARGO_TARGET_TMPDIR"), &format!("refusals-{tag}"))
}

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

//! Shared by the aero parity tests: a runscript flown by stock JSBSim (`scripts/jsbsim-stock`),
//! with named properties read at every step.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The repository root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every step of `script` (initialised by `init`) flown by stock JSBSim: each of `props` by name.
pub fn fly(script: &Path, init: &Path, props: &[String]) -> Vec<HashMap<String, f64>> {
    let stem = script
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let dir = std::env::temp_dir().join(format!("aero-parity-{stem}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("flight.tsv");
    let mut cmd = std::process::Command::new(root().join("scripts/jsbsim-stock"));
    cmd.arg(script).arg(init).arg("--out").arg(&out);
    for n in props {
        cmd.arg("--prop").arg(n);
    }
    // JSBSim's banner and <notify/> lines go to stdout.
    let status = cmd.stdout(std::process::Stdio::null()).status().unwrap();
    assert!(
        status.success(),
        "scripts/jsbsim-stock failed on {}",
        script.display()
    );
    let text = std::fs::read_to_string(&out).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    text.lines()
        .map(|l| {
            // jsbsim-stock writes sim time, α and β (deg) first, then the --prop columns.
            let vals: Vec<f64> = l.split('\t').skip(3).map(|x| x.parse().unwrap()).collect();
            assert_eq!(vals.len(), props.len(), "{l}");
            props.iter().cloned().zip(vals).collect()
        })
        .collect()
}

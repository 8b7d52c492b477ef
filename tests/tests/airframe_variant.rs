//! `scripts/airframe-variant`'s counterfactual `[turbulence] body_rates_in` (docs/airframes.md):
//! the named sections of the build's aircraft's model read the body rates in place of the
//! air-relative ones, and nothing else of the model changes; a section it does not know is refused
//! with a non-zero exit, a message that names the key, and no output.

// Host test code: the flight-code lints of `[workspace.lints]` do not apply (a panic is how it fails).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The build's aircraft's model written by `scripts/airframe-variant` from a spec whose
/// `[turbulence]` table is `turbulence`, into `dir/out`.
fn variant(dir: &Path, tag: &str, turbulence: &str) -> (Output, PathBuf) {
    let spec = dir.join(format!("{tag}.toml"));
    std::fs::write(
        &spec,
        format!("name = \"{tag}\"\n[turbulence]\n{turbulence}\n"),
    )
    .unwrap();
    let out = dir.join(tag);
    let o = Command::new(root().join("scripts/airframe-variant"))
        .arg(&spec)
        .args([
            "--model",
            estimator_core::aircraft::AIRCRAFT.jsbsim_model,
            "--out",
        ])
        .arg(&out)
        .output()
        .expect("run scripts/airframe-variant");
    (o, out)
}

/// The model XML the variant in `out` holds, without the provenance comment the script puts first
/// (it names the spec).
fn model_xml(out: &Path) -> String {
    let m = estimator_core::aircraft::AIRCRAFT.jsbsim_model;
    let text = std::fs::read_to_string(out.join(m).join(format!("{m}.xml"))).unwrap();
    let start = text.find("<!--").expect("provenance comment");
    let end = start + text[start..].find("-->").expect("end of the comment") + 3;
    format!("{}{}", &text[..start], &text[end..])
}

/// The text of the `<aerodynamics>` section and everything around it.
fn split_aerodynamics(xml: &str) -> (&str, &str, &str) {
    let a = xml.find("<aerodynamics").expect("<aerodynamics>");
    let b = xml.find("</aerodynamics>").expect("</aerodynamics>");
    (&xml[..a], &xml[a..b], &xml[b..])
}

#[test]
fn body_rates_in_the_aerodynamics_change_their_rate_terms_and_nothing_else() {
    let dir = tests::scratch(env!("CARGO_TARGET_TMPDIR"), "airframe-variant-rates");
    let (o, model) = variant(&dir, "model", "body_rates_in = []");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (o, changed) = variant(&dir, "changed", "body_rates_in = [\"aerodynamics\"]");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (before, after) = (model_xml(&model), model_xml(&changed));
    let (b0, b_aero, b1) = split_aerodynamics(&before);
    let (a0, a_aero, a1) = split_aerodynamics(&after);
    // Outside the aerodynamics the model is the same, the flight controls' rates included.
    assert!(
        (b0, b1) == (a0, a1),
        "the model changed outside its aerodynamics"
    );
    // Inside, every air-relative rate became the body rate, and only that changed.
    let n = b_aero.matches("-aero-rad_sec").count();
    assert!(n > 0, "the model's aerodynamics read no air-relative rate");
    assert_eq!(a_aero.matches("-aero-rad_sec").count(), 0);
    assert_eq!(
        a_aero.matches("-rad_sec").count(),
        b_aero.matches("-rad_sec").count()
    );
    assert!(
        b_aero.replace("-aero-rad_sec", "-rad_sec") == a_aero,
        "the aerodynamics changed beyond their rates"
    );
    assert!(
        String::from_utf8_lossy(&o.stdout).contains(&format!("aerodynamics {n}")),
        "the script names what it changed: {}",
        String::from_utf8_lossy(&o.stdout)
    );
}

#[test]
fn an_unknown_section_is_refused_with_nothing_written() {
    let dir = tests::scratch(env!("CARGO_TARGET_TMPDIR"), "airframe-variant-refused");
    for (tag, table) in [
        ("unknown", "body_rates_in = [\"wings\"]"),
        ("not-a-list", "body_rates_in = \"aerodynamics\""),
        ("unknown-key", "rotation = false"),
    ] {
        let (o, out) = variant(&dir, tag, table);
        assert!(!o.status.success(), "{tag}: accepted");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("[turbulence]"), "{tag}: {err}");
        assert!(!out.exists(), "{tag}: {} written", out.display());
        assert!(
            !out.with_extension("partial").exists(),
            "{tag}: partial left"
        );
    }
}

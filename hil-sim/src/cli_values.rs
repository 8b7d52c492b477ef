//! Value parsers of the command lines, shared by `hil-sim` and `trainer`: a value that cannot mean
//! anything (a zero count, a negative duration, NaN) is refused where it is parsed, with what to
//! give instead.

/// A duration in seconds: finite and > 0 (`--max-time-s`).
pub fn positive_seconds(s: &str) -> std::result::Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        Ok(_) => Err(format!(
            "`{s}`: give a positive number of seconds, e.g. 120"
        )),
        Err(_) => Err(format!("`{s}` is not a number of seconds")),
    }
}

/// A count that must be at least 1 (`--workers`, `--repeats`).
pub fn at_least_one(s: &str) -> std::result::Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(0) => Err("must be at least 1".into()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!("`{s}` is not a whole number")),
    }
}

/// `--aircraft NAME`: the aircraft this build is for (its description `aircraft/NAME.toml`). A
/// build carries one aircraft; another described one is refused with how to build for it, a name
/// no description has with the names there are.
pub fn this_builds_aircraft(s: &str) -> std::result::Result<String, String> {
    let ours = estimator_core::aircraft::AIRCRAFT;
    if s == ours.name {
        return Ok(s.to_string());
    }
    if !estimator_core::aircraft::is_described(s) {
        return Err(format!(
            "no aircraft is described as `{s}`: this tree describes {} (aircraft/NAME.toml); to \
             add one, docs/aircraft.md",
            estimator_core::aircraft::descriptions()
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    Err(format!(
        "this build is for `{}` ({}), not `{s}`: a build carries one aircraft. Build for `{s}` with \
         ESTIMATOR_AIRCRAFT={s} (its description aircraft/{s}.toml, docs/aircraft.md), e.g. \
         `ESTIMATOR_AIRCRAFT={s} CARGO_TARGET_DIR=target/{s} cargo build --release`",
        ours.name, ours.title
    ))
}

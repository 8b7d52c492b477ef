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

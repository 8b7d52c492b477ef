#![cfg_attr(target_os = "none", no_std, no_main)]
//! Being written (issue 6).
#[cfg(not(target_os = "none"))]
fn main() {}

//! Logging shim: `defmt` on the Cortex-M4F; on the host, the `log` facade with target `"firmware"`
//! (`hil-sim run --firmware-log` prints them). The format strings use only plain `{}` holes, which
//! both read the same way.
#![allow(unused_macros)]

#[cfg(target_os = "none")]
macro_rules! info {
    ($($t:tt)*) => { ::defmt::info!($($t)*) };
}
#[cfg(target_os = "none")]
macro_rules! warn {
    ($($t:tt)*) => { ::defmt::warn!($($t)*) };
}

#[cfg(not(target_os = "none"))]
macro_rules! info {
    ($($t:tt)*) => { ::log::info!(target: "firmware", $($t)*) };
}
#[cfg(not(target_os = "none"))]
macro_rules! warn {
    ($($t:tt)*) => { ::log::warn!(target: "firmware", $($t)*) };
}

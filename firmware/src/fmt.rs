//! Logging shim: `defmt` on the Cortex-M4F, nothing on the host (the host tools report through the
//! estimate frames instead). Arguments are still evaluated by reference on the host so both builds
//! see the same uses and warnings.
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
    ($fmt:literal $(, $arg:expr)* $(,)?) => {{ $( let _ = &$arg; )* }};
}
#[cfg(not(target_os = "none"))]
macro_rules! warn {
    ($fmt:literal $(, $arg:expr)* $(,)?) => {{ $( let _ = &$arg; )* }};
}

//! The one plot font of the project: DejaVu Sans (Bitstream Vera license,
//! assets/DejaVuSans-LICENSE.txt), embedded so PNGs do not depend on system fonts (CI containers have
//! none). hil-sim's plots and the trainer's call [`register`].
use plotters::style::FontStyle;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Registers the embedded font as plotters' `sans-serif` (once per process).
pub fn register() {
    REGISTER.call_once(|| {
        // The embedded font is a valid TTF; if registration failed, text drawing reports the error.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

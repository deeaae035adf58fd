//! The font every picture's text is drawn and measured with.
//!
//! plotters draws text in PNG, and measures it in SVG too, with a font
//! registered by name. DejaVu Sans (Bitstream Vera licence, `fonts/`) ships
//! inside the binary, so pictures look the same on every machine and need
//! no system font or font library.

/// Register DejaVu Sans as plotters' `sans-serif` (once per process).
pub fn register() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../fonts/DejaVuSans.ttf");
        // NOTE: cannot fail for this font; if it did, text would be missing
        // from the pictures and nothing else, so the error is not fatal.
        let _ =
            plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, bytes);
    });
}

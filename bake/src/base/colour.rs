//! Colour encodings: sRGB-encoded components to linear and back, and the stored form of a
//! linear RGBA colour. Importers decode sRGB colours to linear; the `.clod` file and the
//! out-of-core soup store them as sRGB bytes.

/// sRGB-encoded component in 0..=1 to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear colour component in 0..=1 to sRGB8.
pub fn linear_to_srgb8(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// sRGB8 to linear, for all 256 values.
pub fn srgb8_table() -> [f32; 256] {
    std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0))
}

/// A linear RGBA colour as stored: sRGB8 colour, linear 8-bit alpha.
pub fn encode_colour(c: [f32; 4]) -> [u8; 4] {
    [
        linear_to_srgb8(c[0]),
        linear_to_srgb8(c[1]),
        linear_to_srgb8(c[2]),
        (c[3].clamp(0.0, 1.0) * 255.0).round() as u8,
    ]
}

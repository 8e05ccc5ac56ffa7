//! Colours for surfaces without materials: distinct hues, so surface boundaries show.

/// Colour of surface `s`: hues a golden angle apart, fully opaque.
pub fn palette(s: usize) -> [f32; 4] {
    let h = (s as f32 * 0.618_034 + 0.08).fract() * 6.0;
    let x = 1.0 - ((h % 2.0) - 1.0).abs();
    let (r, g, b) = match h as u32 {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        4 => (x, 0.0, 1.0),
        _ => (1.0, 0.0, x),
    };
    // Pastel: mix with white so lighting stays readable.
    [0.35 + 0.65 * r, 0.35 + 0.65 * g, 0.35 + 0.65 * b, 1.0]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_are_opaque_pastels_that_differ() {
        let colours: Vec<[f32; 4]> = (0..8).map(palette).collect();
        for (i, c) in colours.iter().enumerate() {
            assert_eq!(c[3], 1.0);
            assert!(c[..3].iter().all(|&x| (0.35..=1.0).contains(&x)), "{c:?}");
            for d in &colours[..i] {
                assert_ne!(c, d);
            }
        }
    }
}

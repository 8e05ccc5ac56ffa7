//! Colours for surfaces without materials: distinct hues, so surface boundaries show; and
//! hues for colour scales.

/// Colour of surface `s`: hues a golden angle apart, fully opaque, pastel so lighting stays
/// readable.
pub fn palette(s: usize) -> [f32; 4] {
    let turn = (s as f32 * 0.618_034 + 0.08).fract();
    hue(360.0 * turn, 0.35)
}

/// The opaque colour of hue `degrees` (0 red, 120 green, 240 blue), mixed with white so that
/// no channel is below `floor` (0 for saturated, towards 1 for paler).
pub fn hue(degrees: f32, floor: f32) -> [f32; 4] {
    let h = (degrees / 60.0).rem_euclid(6.0);
    let x = 1.0 - ((h % 2.0) - 1.0).abs();
    let (r, g, b) = match h as u32 {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        4 => (x, 0.0, 1.0),
        _ => (1.0, 0.0, x),
    };
    let soft = |c: f32| floor + (1.0 - floor) * c;
    [soft(r), soft(g), soft(b), 1.0]
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

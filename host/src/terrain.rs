//! Colours for a terrain without materials, as a shaded relief map draws one: a tint by
//! height (valley green, olive and brown slopes, bare rock, scree, snow), with steep faces
//! turned to rock, so the relief reads at a glance and no texture pattern crosses it.

use caveclod_core::format::Vertex;

/// The height ramp: (share of the height range, linear colour). The colours are light, as
/// the surface palette's are, because lighting takes up to three quarters of them away.
const RAMP: [(f32, [f32; 3]); 6] = [
    (0.00, [0.42, 0.56, 0.30]),
    (0.25, [0.62, 0.66, 0.38]),
    (0.50, [0.74, 0.63, 0.46]),
    (0.72, [0.70, 0.65, 0.60]),
    (0.88, [0.84, 0.83, 0.81]),
    (1.00, [1.00, 1.00, 1.00]),
];

/// Bare rock, which steep faces turn to (linear).
const ROCK: [f32; 3] = [0.60, 0.56, 0.52];

/// Shares of the vertices below the ramp's ends: a few outliers (a spike, a pit) must not
/// squeeze the ramp for the rest.
const LOW_SHARE: f32 = 0.01;
const HIGH_SHARE: f32 = 0.995;

/// Steepness (one minus the normal's `y`) where faces start and finish turning to rock.
const ROCK_FROM: f32 = 0.25;
const ROCK_TO: f32 = 0.6;

/// One RGBA8 colour per vertex for a terrain whose `y` is up: the height ramp between the
/// low and high shares of the heights, mixed towards rock on steep faces; linear colours
/// stored sRGB-encoded, as vertex colours are (the shaders decode them). Draw them with a
/// white material (`caveclod_vulkan::VertexBuffer::coloured`).
pub fn terrain_colours(vertices: &[Vertex]) -> Vec<[u8; 4]> {
    let (low, high) = height_range(vertices);
    let span = (high - low).max(f32::MIN_POSITIVE);
    vertices
        .iter()
        .map(|v| {
            let height = ((v.position[1] - low) / span).clamp(0.0, 1.0);
            let steep = 1.0 - v.normal[1].abs();
            let rock = smoothstep(ROCK_FROM, ROCK_TO, steep);
            let c = mix(ramp(height), ROCK, rock * (1.0 - height * height));
            [
                byte(encode(c[0])),
                byte(encode(c[1])),
                byte(encode(c[2])),
                255,
            ]
        })
        .collect()
}

/// The heights at the low and high shares of the vertices.
fn height_range(vertices: &[Vertex]) -> (f32, f32) {
    let mut heights: Vec<f32> = vertices
        .iter()
        .map(|v| v.position[1])
        .filter(|y| y.is_finite())
        .collect();
    if heights.is_empty() {
        return (0.0, 1.0);
    }
    heights.sort_unstable_by(f32::total_cmp);
    let at = |share: f32| heights[((heights.len() - 1) as f32 * share) as usize];
    (at(LOW_SHARE), at(HIGH_SHARE))
}

/// The ramp's colour at `t` in `0..=1`.
fn ramp(t: f32) -> [f32; 3] {
    for pair in RAMP.windows(2) {
        let ((t0, c0), (t1, c1)) = (pair[0], pair[1]);
        if t <= t1 {
            return mix(c0, c1, (t - t0) / (t1 - t0));
        }
    }
    RAMP[RAMP.len() - 1].1
}

fn mix(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    let t = t.clamp(0.0, 1.0);
    [0, 1, 2].map(|k| a[k] + (b[k] - a[k]) * t)
}

fn smoothstep(from: f32, to: f32, x: f32) -> f32 {
    let t = ((x - from) / (to - from)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A linear channel in `0..=1` in the sRGB encoding (the inverse of the shaders' decoding).
fn encode(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        x * 12.92
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

fn byte(x: f32) -> u8 {
    (x.clamp(0.0, 1.0) * 255.0).round() as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex(y: f32, normal: [f32; 3]) -> Vertex {
        Vertex {
            position: [0.0, y, 0.0],
            normal,
            uv: [0.0; 2],
        }
    }

    #[test]
    fn valleys_are_green_peaks_white_and_cliffs_rock() {
        let up = [0.0, 1.0, 0.0];
        let mut vertices: Vec<Vertex> = (0..=100).map(|i| vertex(i as f32, up)).collect();
        vertices.push(vertex(50.0, [1.0, 0.0, 0.0]));
        let c = terrain_colours(&vertices);
        let (valley, peak, cliff) = (c[0], c[100], c[101]);
        assert!(valley[1] > valley[0] && valley[1] > valley[2], "{valley:?}");
        assert!(peak.iter().all(|&x| x > 230), "{peak:?}");
        let rock = ROCK.map(|x| byte(encode(x)));
        assert!((0..3).all(|k| cliff[k].abs_diff(rock[k]) < 12), "{cliff:?}");
        assert!(c.iter().all(|x| x[3] == 255));
    }

    #[test]
    fn an_outlier_does_not_flatten_the_ramp() {
        let up = [0.0, 1.0, 0.0];
        let mut vertices: Vec<Vertex> = (0..1000).map(|i| vertex(i as f32, up)).collect();
        vertices.push(vertex(1e9, up));
        let c = terrain_colours(&vertices);
        // The middle of the terrain is in the middle of the ramp, not at its green end.
        assert_ne!(c[500], c[0]);
        assert_ne!(c[500], c[990]);
    }
}

//! The screenshot of `--frames N --screenshot FILE`: the last frame read back, written as
//! PNG, and how much of each camera's viewport shows something other than the background
//! (outside egui's panel), which `--min-coverage` checks.

use std::path::Path;

use caveclod_vulkan::{RgbaImage, Viewport};

use crate::frame::{Capture, BACKGROUND_SRGB};

/// Channels within this of the background's count as background (sRGB rounding).
const BACKGROUND_SLACK: u8 = 2;

/// Writes the image through a temporary file and a rename.
pub fn write(capture: &Capture, path: &Path) -> Result<(), String> {
    caveclod_host::write_png(&capture.image, path).map_err(|e| e.to_string())
}

/// Per viewport, the fraction of its pixels outside the panel that are not background.
pub fn coverage(capture: &Capture) -> Vec<f64> {
    capture
        .viewports
        .iter()
        .map(|vp| viewport_coverage(&capture.image, *vp, capture.panel))
        .collect()
}

fn viewport_coverage(image: &RgbaImage, vp: Viewport, panel: Option<egui::Rect>) -> f64 {
    let (mut counted, mut covered) = (0u64, 0u64);
    for y in vp.y..vp.y + vp.height {
        for x in vp.x..vp.x + vp.width {
            let centre = egui::pos2(x as f32 + 0.5, y as f32 + 0.5);
            if panel.is_some_and(|r| r.contains(centre)) {
                continue;
            }
            let Some(p) = image.pixel(x, y) else {
                continue;
            };
            counted += 1;
            if !is_background(p) {
                covered += 1;
            }
        }
    }
    covered as f64 / counted.max(1) as f64
}

fn is_background(p: [u8; 4]) -> bool {
    p.iter()
        .zip(BACKGROUND_SRGB)
        .all(|(&c, b)| c.abs_diff(b) <= BACKGROUND_SLACK)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coverage_counts_non_background_pixels_outside_the_panel() {
        let [r, g, b] = BACKGROUND_SRGB;
        let mut pixels = [r, g, b, 255].repeat(8);
        // Left viewport: pixel (0, 0) lit (under the panel), (1, 1) lit, (1, 0) within slack.
        pixels[..4].copy_from_slice(&[255, 0, 0, 255]);
        pixels[4 * 5..4 * 6].copy_from_slice(&[255, 255, 255, 255]);
        pixels[4..8].copy_from_slice(&[r + 1, g, b.saturating_sub(2), 255]);
        let capture = Capture {
            image: RgbaImage {
                width: 4,
                height: 2,
                pixels,
            },
            viewports: Viewport::split_screen(4, 2, 2).unwrap(),
            panel: Some(egui::Rect::from_min_max(
                egui::pos2(0.0, 0.0),
                egui::pos2(1.0, 1.0),
            )),
        };
        assert_eq!(coverage(&capture), vec![1.0 / 3.0, 0.0]);
    }
}

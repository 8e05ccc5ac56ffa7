//! A resize storm (`--resize-every N` with `--frames`): the viewer asks its own window for
//! a new size every N drawn frames, through a fixed cycle of shapes, and back to the size it
//! opened with before the last frames, so the swapchain goes out of date (or suboptimal)
//! again and again while frames are in flight and the final screenshot has its usual size.
//! The run fails unless the swapchain was recreated for the sizes asked for.

use winit::dpi::PhysicalSize;

/// Window shapes as quarters of the opening size (width, height): wider, taller, small,
/// full width, full height.
const SHAPES: [(u32, u32); 5] = [(3, 2), (2, 3), (1, 1), (4, 3), (3, 4)];

/// The storm's plan and what it asked for.
#[derive(Debug)]
pub struct ResizeStorm {
    every: u64,
    frames: u64,
    base: PhysicalSize<u32>,
    /// Sizes asked for so far (the return to `base` included).
    pub requested: u64,
    /// The drawn-frame count at the last request.
    last_at: Option<u64>,
}

impl ResizeStorm {
    /// A storm every `every` (at least 1) of `frames` frames, around `base`.
    pub fn new(every: u64, frames: u64, base: PhysicalSize<u32>) -> Self {
        Self {
            every: every.max(1),
            frames,
            base,
            requested: 0,
            last_at: None,
        }
    }

    /// The size to ask for before drawing frame `drawn` (counted from 0), if any: the next
    /// shape every `every` frames; once, `base` again, when the frames left are too few
    /// for another round (two periods before the end).
    pub fn next(&mut self, drawn: u64) -> Option<PhysicalSize<u32>> {
        if drawn == 0 || !drawn.is_multiple_of(self.every) || self.last_at == Some(drawn) {
            return None;
        }
        let calm_from = self.frames.saturating_sub(2 * self.every);
        if drawn > calm_from {
            return None;
        }
        self.last_at = Some(drawn);
        let round = drawn / self.every;
        let size = if drawn + self.every > calm_from {
            self.base
        } else {
            let (w, h) = SHAPES[(round as usize - 1) % SHAPES.len()];
            PhysicalSize::new(
                (self.base.width * w / 4).max(64),
                (self.base.height * h / 4).max(64),
            )
        };
        self.requested += 1;
        Some(size)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn storms_through_the_shapes_and_ends_at_the_opening_size() {
        let base = PhysicalSize::new(1280, 720);
        let mut storm = ResizeStorm::new(5, 60, base);
        let mut asked = Vec::new();
        for drawn in 0..60 {
            if let Some(s) = storm.next(drawn) {
                asked.push((drawn, s));
            }
            // A frame that is skipped asks nothing twice.
            assert_eq!(storm.next(drawn), None);
        }
        assert_eq!(storm.requested, asked.len() as u64);
        let frames: Vec<u64> = asked.iter().map(|a| a.0).collect();
        assert_eq!(frames, [5, 10, 15, 20, 25, 30, 35, 40, 45, 50]);
        assert_eq!(asked[0].1, PhysicalSize::new(960, 360));
        assert_eq!(asked[2].1, PhysicalSize::new(320, 180));
        assert_eq!(asked.last().map(|a| a.1), Some(base));
        assert!(asked[..asked.len() - 1].iter().all(|a| a.1 != base));
    }
}

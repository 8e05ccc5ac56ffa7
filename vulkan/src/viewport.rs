//! Rectangles of a target: one camera's viewport, and split screen.

use crate::error::{Error, Result};

/// A rectangle of a target, in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Viewport {
    /// Left edge.
    pub x: u32,
    /// Top edge.
    pub y: u32,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
}

impl Viewport {
    /// The whole of a `width` × `height` target.
    pub fn full(width: u32, height: u32) -> Self {
        Self {
            x: 0,
            y: 0,
            width,
            height,
        }
    }

    /// Split screen for `cameras` (1 to 4): one full view, two side by side, or quadrants
    /// (top left, top right, bottom left, bottom right) for three and four.
    pub fn split_screen(width: u32, height: u32, cameras: usize) -> Result<Vec<Self>> {
        let (hw, hh) = (width / 2, height / 2);
        let quad = |i: u32| Self {
            x: (i % 2) * hw,
            y: (i / 2) * hh,
            width: hw,
            height: hh,
        };
        match cameras {
            1 => Ok(vec![Self::full(width, height)]),
            2 => Ok(vec![
                Self {
                    x: 0,
                    y: 0,
                    width: hw,
                    height,
                },
                Self {
                    x: hw,
                    y: 0,
                    width: hw,
                    height,
                },
            ]),
            3 | 4 => Ok((0..cameras as u32).map(quad).collect()),
            n => Err(Error::InvalidArgument(format!(
                "split screen for {n} cameras: 1 to 4 supported"
            ))),
        }
    }

    /// Width over height.
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height.max(1) as f32
    }
}

//! LOD partitions of the global parameter `T` and the level / morph factor they select.
//!
//! A g-mesh with levels `0..=n` (level 0 the full mesh, level `n` the coarsest) divides
//! `T ∈ [0, 1]` into `n` ranges `r_0..r_{n-1}`; range `i` starts at
//! `R_i = r_0 + … + r_{i-1}` and ends at `R_{i+1}`. Inside `(R_i, R_{i+1}]` the instance draws
//! connectivity set `c_i` and morphs its attributes from `a_i` to `a_{i+1}` by the local
//! parameter `g_i(T) = (T - R_i) / (R_{i+1} - R_i)`. `T ≤ 0` selects level 0 unmorphed (full
//! detail) and `T > 1` the coarsest level. At `T = R_{i+1}` range `i` ends with `g = 1`
//! (attributes `a_{i+1}`) and range `i + 1` starts there with `g = 0` (the same attributes), so
//! the attribute function `F(T)` of the paper's Eq. 1 is continuous.
//!
//! [`Partitions`] borrows the `n + 1` boundaries `R_0 = 0 < R_1 < … < R_n = 1` from the caller
//! (a baked file or a caller array) and checks them once; [`even_boundaries`] and
//! [`volume_boundaries`] fill such an array. Volume-based partitions follow §5.3 of Southern &
//! Gain: `r_i ∝ V_i - V_{i+1}` with `V_i` the volume after batch `i` over the input's, so more
//! of the `T` range goes to the coarse levels, where each step changes the shape most.

/// Why partitions or controller inputs were refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GMeshError {
    /// A g-mesh needs at least two levels (one morph range).
    TooFewLevels {
        /// Levels given.
        levels: usize,
    },
    /// An output or input array has the wrong length.
    LengthMismatch {
        /// What the array is.
        what: &'static str,
        /// Its expected length.
        expected: usize,
        /// Its length.
        got: usize,
    },
    /// A value is NaN or infinite.
    NotFinite {
        /// What the array is.
        what: &'static str,
        /// Index of the value.
        index: usize,
    },
    /// Boundaries must start at 0, end at 1 and increase strictly.
    BadBoundary {
        /// Index of the first offending boundary.
        index: usize,
    },
    /// An instance names a model that does not exist.
    UnknownModel {
        /// The instance.
        instance: usize,
        /// The model index it names.
        model: u32,
    },
    /// The caller's scratch array is too small.
    ScratchTooSmall {
        /// Entries needed (one per instance).
        needed: usize,
        /// Entries given.
        got: usize,
    },
}

impl core::fmt::Display for GMeshError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::TooFewLevels { levels } => {
                write!(f, "a g-mesh needs at least 2 levels, got {levels}")
            }
            Self::LengthMismatch {
                what,
                expected,
                got,
            } => write!(f, "{what}: expected {expected} entries, got {got}"),
            Self::NotFinite { what, index } => write!(f, "{what}[{index}] is not finite"),
            Self::BadBoundary { index } => write!(
                f,
                "partition boundary {index}: boundaries must start at 0, end at 1 and increase \
                 strictly"
            ),
            Self::UnknownModel { instance, model } => {
                write!(
                    f,
                    "instance {instance} names model {model}, which does not exist"
                )
            }
            Self::ScratchTooSmall { needed, got } => {
                write!(
                    f,
                    "controller scratch: {needed} entries needed, {got} given"
                )
            }
        }
    }
}

impl core::error::Error for GMeshError {}

/// The level an instance draws and how far it has morphed towards the next one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelMorph {
    /// The connectivity set `c_level` to draw.
    pub level: usize,
    /// The local parameter `g_level(T)` in `[0, 1]`: attributes are
    /// `(1 - t) a_level + t a_{level+1}`. Always 0 at the coarsest level.
    pub t: f32,
}

/// `T` from the distance to the viewer: `(d - d_near) / (d_far - d_near)`.
///
/// Not clamped: `T < 0` means full detail (or behind the viewer), `T > 1` the coarsest level.
/// A degenerate range (`d_far <= d_near`) gives 0 up to `d_near` and 2 beyond it.
pub fn t_from_distance(d: f32, d_near: f32, d_far: f32) -> f32 {
    let range = d_far - d_near;
    if range > 0.0 {
        (d - d_near) / range
    } else if d <= d_near {
        0.0
    } else {
        2.0
    }
}

/// Writes the boundaries of even partitions (`r_i = 1 / n`) for `out.len() - 1` ranges.
pub fn even_boundaries(out: &mut [f32]) -> Result<(), GMeshError> {
    let levels = out.len();
    if levels < 2 {
        return Err(GMeshError::TooFewLevels { levels });
    }
    let n = (levels - 1) as f32;
    for (i, r) in out.iter_mut().enumerate() {
        *r = i as f32 / n;
    }
    Ok(())
}

/// Writes volume-based boundaries: `r_i ∝ |V_i - V_{i+1}|` for normalised volumes
/// `volumes[i] = V_i` (`V_0 = 1` for the input, one value per level), `out.len() ==
/// volumes.len()`.
///
/// The paper takes `r_i = V_i - V_{i+1}`, for shapes that shrink as they are simplified. A
/// batch can also grow the volume (concave regions, terrains): the change counts either way,
/// as a measure of how much the shape changes. Every range gets at least `min_share` of the
/// whole (e.g. 0.01) so every level stays reachable, and the ranges are normalised to sum to
/// 1. With no change at all the partitions are even.
pub fn volume_boundaries(
    volumes: &[f32],
    min_share: f32,
    out: &mut [f32],
) -> Result<(), GMeshError> {
    let levels = volumes.len();
    if levels < 2 {
        return Err(GMeshError::TooFewLevels { levels });
    }
    if out.len() != levels {
        return Err(GMeshError::LengthMismatch {
            what: "boundaries",
            expected: levels,
            got: out.len(),
        });
    }
    if let Some(index) = volumes.iter().position(|v| !v.is_finite()) {
        return Err(GMeshError::NotFinite {
            what: "volumes",
            index,
        });
    }
    let ranges = levels - 1;
    let floor = if min_share.is_finite() && min_share > 0.0 {
        min_share.min(1.0 / ranges as f32)
    } else {
        0.0
    };
    // Raw changes, each at least the floor share of the total change.
    let total: f32 = volumes.windows(2).map(|w| (w[0] - w[1]).abs()).sum();
    if total <= 0.0 {
        return even_boundaries(out);
    }
    let mut acc = 0.0f32;
    out[0] = 0.0;
    for i in 0..ranges {
        let r = ((volumes[i] - volumes[i + 1]).abs() / total).max(floor);
        acc += r;
        out[i + 1] = acc;
    }
    // Normalise (the floors may have added a little) and pin the end exactly at 1.
    for r in out.iter_mut() {
        *r /= acc;
    }
    out[ranges] = 1.0;
    // Strictly increasing: a zero-width range (floor 0, no decrease) would be unreachable.
    for i in 1..levels {
        if out[i] <= out[i - 1] {
            return Err(GMeshError::BadBoundary { index: i });
        }
    }
    Ok(())
}

/// Checked partition boundaries `R_0 = 0 < R_1 < … < R_n = 1` of a g-mesh with `n + 1`
/// levels.
#[derive(Clone, Copy, Debug)]
pub struct Partitions<'a> {
    boundaries: &'a [f32],
}

impl<'a> Partitions<'a> {
    /// Checks `boundaries` (at least 2; finite; first 0, last 1; strictly increasing).
    pub fn new(boundaries: &'a [f32]) -> Result<Self, GMeshError> {
        let levels = boundaries.len();
        if levels < 2 {
            return Err(GMeshError::TooFewLevels { levels });
        }
        if let Some(index) = boundaries.iter().position(|v| !v.is_finite()) {
            return Err(GMeshError::NotFinite {
                what: "boundaries",
                index,
            });
        }
        if boundaries[0] != 0.0 {
            return Err(GMeshError::BadBoundary { index: 0 });
        }
        if boundaries[levels - 1] != 1.0 {
            return Err(GMeshError::BadBoundary { index: levels - 1 });
        }
        if let Some(i) = (1..levels).find(|&i| boundaries[i] <= boundaries[i - 1]) {
            return Err(GMeshError::BadBoundary { index: i });
        }
        Ok(Self { boundaries })
    }

    /// Number of levels `n + 1`.
    pub fn levels(&self) -> usize {
        self.boundaries.len()
    }

    /// The coarsest level `n`.
    pub fn coarsest(&self) -> usize {
        self.boundaries.len() - 1
    }

    /// The boundaries `R_0..=R_n`.
    pub fn boundaries(&self) -> &'a [f32] {
        self.boundaries
    }

    /// `R_i` (`i` clamped to `0..=n`).
    pub fn boundary(&self, i: usize) -> f32 {
        self.boundaries[i.min(self.coarsest())]
    }

    /// The local parameter `g_i(T)`, unclamped (outside `[0, 1]` when `T` is outside range
    /// `i`); `i` clamped to the ranges `0..n`.
    pub fn local(&self, i: usize, t: f32) -> f32 {
        let i = i.min(self.coarsest() - 1);
        let (lo, hi) = (self.boundaries[i], self.boundaries[i + 1]);
        (t - lo) / (hi - lo)
    }

    /// The range `(R_i, R_{i+1}]` holding `T`, or level 0 for `T ≤ 0` and the coarsest for
    /// `T > 1` (NaN counts as full detail).
    pub fn level(&self, t: f32) -> usize {
        if t.is_nan() || t <= 0.0 {
            return 0;
        }
        if t > 1.0 {
            return self.coarsest();
        }
        // First boundary >= t, among R_1..=R_n; the range is the one ending there.
        let ends = &self.boundaries[1..];
        ends.partition_point(|&r| r < t)
    }

    /// The level and morph factor for `T`.
    pub fn level_morph(&self, t: f32) -> LevelMorph {
        let level = self.level(t);
        if level == self.coarsest() {
            return LevelMorph { level, t: 0.0 };
        }
        let g = if t.is_nan() || t <= 0.0 {
            0.0
        } else {
            self.local(level, t).clamp(0.0, 1.0)
        };
        LevelMorph { level, t: g }
    }

    /// The paper's `F(T)` for one scalar attribute with values `values[i] = a_i`
    /// (`values.len() == levels()`): what the geomorph evaluates, for tests and CPU paths.
    pub fn attribute(&self, values: &[f32], t: f32) -> Option<f32> {
        if values.len() != self.levels() {
            return None;
        }
        let m = self.level_morph(t);
        let a = values[m.level];
        if m.level == self.coarsest() {
            return Some(a);
        }
        let b = values[m.level + 1];
        Some(a + (b - a) * m.t)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn levels_follow_the_half_open_ranges() {
        let b = [0.0, 0.25, 0.5, 1.0];
        let p = Partitions::new(&b).unwrap();
        assert_eq!(p.level(-1.0), 0);
        assert_eq!(p.level(0.0), 0);
        assert_eq!(p.level(0.1), 0);
        assert_eq!(p.level(0.25), 0);
        assert_eq!(p.level(0.2500001), 1);
        assert_eq!(p.level(0.5), 1);
        assert_eq!(p.level(0.75), 2);
        assert_eq!(p.level(1.0), 2);
        assert_eq!(p.level(1.0001), 3);
        assert_eq!(p.level(f32::NAN), 0);
        assert_eq!(p.level_morph(0.375), LevelMorph { level: 1, t: 0.5 });
        assert_eq!(p.level_morph(0.25), LevelMorph { level: 0, t: 1.0 });
        assert_eq!(p.level_morph(5.0), LevelMorph { level: 3, t: 0.0 });
    }

    #[test]
    fn bad_boundaries_are_refused() {
        assert!(matches!(
            Partitions::new(&[0.0]),
            Err(GMeshError::TooFewLevels { levels: 1 })
        ));
        assert!(matches!(
            Partitions::new(&[0.0, 0.5, 0.5, 1.0]),
            Err(GMeshError::BadBoundary { index: 2 })
        ));
        assert!(matches!(
            Partitions::new(&[0.1, 1.0]),
            Err(GMeshError::BadBoundary { index: 0 })
        ));
        assert!(matches!(
            Partitions::new(&[0.0, f32::NAN, 1.0]),
            Err(GMeshError::NotFinite { index: 1, .. })
        ));
    }

    #[test]
    fn volume_partitions_give_coarse_levels_more_range() {
        // The dolphin-like shrinkage: small changes first, large ones at coarse levels.
        let v = [1.0, 0.99, 0.96, 0.88, 0.7];
        let mut out = [0.0; 5];
        volume_boundaries(&v, 0.01, &mut out).unwrap();
        let p = Partitions::new(&out).unwrap();
        let r: [f32; 4] = core::array::from_fn(|i| out[i + 1] - out[i]);
        assert!(r.windows(2).all(|w| w[0] <= w[1]), "{r:?}");
        assert_eq!(p.boundaries()[4], 1.0);
        // Growth counts as change; a flat step still gets a range.
        let v = [1.0, 1.01, 1.01, 0.5];
        let mut out = [0.0; 4];
        volume_boundaries(&v, 0.02, &mut out).unwrap();
        Partitions::new(&out).unwrap();
        // No decrease at all: even.
        let mut out = [0.0; 3];
        volume_boundaries(&[1.0, 1.0, 1.0], 0.0, &mut out).unwrap();
        assert_eq!(out, [0.0, 0.5, 1.0]);
    }

    #[test]
    fn distance_maps_linearly() {
        assert_eq!(t_from_distance(10.0, 10.0, 110.0), 0.0);
        assert_eq!(t_from_distance(60.0, 10.0, 110.0), 0.5);
        assert!(t_from_distance(5.0, 10.0, 110.0) < 0.0);
        assert_eq!(t_from_distance(5.0, 10.0, 10.0), 0.0);
        assert_eq!(t_from_distance(15.0, 10.0, 10.0), 2.0);
    }
}

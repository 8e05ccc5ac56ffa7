//! The rough terrain's fractal detail: octaves of 2D gradient noise (Perlin's, with the
//! quintic fade of "Improving Noise", SIGGRAPH 2002) from a quarter of the terrain down to two
//! grid cells, their relief growing with their scale as natural terrain's does.
//!
//! A sum of sines is smooth at every scale below its shortest wave, so a simplified terrain
//! stays within a pixel of it with a few thousand polygons: too little work for benchmarks
//! and acceptance flights. Fractal detail keeps a camera refining at every resolution: a
//! vertex split near the camera is worth making as long as the grid's finest octave is taller
//! than a pixel there.
//!
//! An octave's relief is its scale to the power [`HURST`] (fractional Brownian motion;
//! measured terrains have Hurst exponents around 0.7 to 0.8): below 1, the fine octaves are
//! rougher for their size than the coarse ones, so the detail that holds polygons near the
//! cameras is rough while the hills and valleys stay gentle. The roughness is the relief of
//! the octave at [`REFERENCE`] of the terrain's side, over that scale.
//!
//! Everything is integer hashing and `f64` arithmetic (no transcendental functions), so the
//! same seed gives the same heights, bit for bit, on every platform. Each octave's domain is
//! turned by the 3-4-5 triangle's angle and shifted by an offset drawn from the seed, so the
//! octaves' lattices never line up.

use super::rng::SplitMix64;

/// The coarsest octave's lattice spacing, as a fraction of the terrain's side.
const COARSEST: f64 = 0.25;
/// The finest octave's lattice spacing, in grid cells (at least).
const FINEST_CELLS: f64 = 2.0;
/// The most octaves (a grid of 2^32 vertices has fewer).
const MAX_OCTAVES: usize = 24;
/// The scale at which an octave's relief is the roughness times its lattice spacing, as a
/// fraction of the terrain's side (the fifth octave's spacing).
pub const REFERENCE: f64 = 1.0 / 64.0;
/// How an octave's relief grows with its scale: as the scale to this power.
pub const HURST: f64 = 0.7;
/// Relief over the next coarser octave's: `2^-HURST`.
const GAIN: f64 = 0.615_572_206_672_458_2;
/// The coarsest octave's relief over the reference octave's, for spacings `COARSEST /
/// REFERENCE = 2^4` apart: `2^(4 HURST)`.
const COARSEST_GAIN: f64 = 6.964_404_506_368_992;

/// Unit gradients at the lattice points: the axes and the diagonals.
const GRADIENTS: [(f64, f64); 8] = {
    const S: f64 = std::f64::consts::FRAC_1_SQRT_2;
    [
        (1.0, 0.0),
        (-1.0, 0.0),
        (0.0, 1.0),
        (0.0, -1.0),
        (S, S),
        (-S, S),
        (S, -S),
        (-S, -S),
    ]
};

/// Fractal noise over a square of side `size`, for a grid whose cells are at most `cell` wide.
#[derive(Clone, Debug)]
pub struct Fractal {
    /// Per octave: lattice spacing, amplitude, domain offset (in lattice units), hash seed.
    octaves: Vec<Octave>,
}

#[derive(Clone, Copy, Debug)]
struct Octave {
    spacing: f64,
    amplitude: f64,
    offset: (f64, f64),
    seed: u64,
}

impl Fractal {
    /// Octaves from a quarter of `size` down to two `cell`s, the one at [`REFERENCE`] of `size`
    /// `roughness` times its lattice spacing high (peak to peak about 1.4 times that), the
    /// others scaled by [`HURST`], drawn from `seed`.
    pub fn new(size: f64, cell: f64, roughness: f64, seed: u64) -> Self {
        let mut rng = SplitMix64::new(seed);
        let mut octaves = Vec::new();
        let mut spacing = COARSEST * size;
        let mut amplitude = roughness * REFERENCE * size * COARSEST_GAIN;
        while octaves.len() < MAX_OCTAVES && (octaves.is_empty() || spacing >= FINEST_CELLS * cell)
        {
            octaves.push(Octave {
                spacing,
                amplitude,
                offset: (1e3 * rng.unit_f64(), 1e3 * rng.unit_f64()),
                seed: rng.next_u64(),
            });
            spacing *= 0.5;
            amplitude *= GAIN;
        }
        Self { octaves }
    }

    /// The height at `(x, z)`, in the units of `size`.
    pub fn at(&self, x: f64, z: f64) -> f64 {
        let (mut x, mut z) = (x, z);
        let mut sum = 0.0;
        for o in &self.octaves {
            sum += o.amplitude
                * gradient_noise(
                    x / o.spacing + o.offset.0,
                    z / o.spacing + o.offset.1,
                    o.seed,
                );
            // The next octave's domain turned by the 3-4-5 triangle's angle (cos 0.8, sin 0.6).
            (x, z) = (0.8 * x - 0.6 * z, 0.6 * x + 0.8 * z);
        }
        sum
    }

    /// The number of octaves.
    pub fn octaves(&self) -> usize {
        self.octaves.len()
    }
}

/// Perlin's gradient noise at `(x, z)` in lattice units: about `-0.7..0.7`, zero at lattice
/// points, smooth (its second derivative continuous) everywhere.
fn gradient_noise(x: f64, z: f64, seed: u64) -> f64 {
    let (x0, z0) = (x.floor(), z.floor());
    let (fx, fz) = (x - x0, z - z0);
    let (ix, iz) = (x0 as i64, z0 as i64);
    let corner = |dx: i64, dz: i64| {
        let (gx, gz) = GRADIENTS[(lattice_hash(ix + dx, iz + dz, seed) & 7) as usize];
        gx * (fx - dx as f64) + gz * (fz - dz as f64)
    };
    let (u, v) = (fade(fx), fade(fz));
    let a = lerp(corner(0, 0), corner(1, 0), u);
    let b = lerp(corner(0, 1), corner(1, 1), u);
    lerp(a, b, v)
}

/// `6t^5 - 15t^4 + 10t^3`: zero first and second derivatives at 0 and 1.
fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a + (b - a) * t
}

/// 64 well-mixed bits for a lattice point.
fn lattice_hash(ix: i64, iz: i64, seed: u64) -> u64 {
    let key = seed
        ^ (ix as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (iz as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    SplitMix64::new(key).next_u64()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gains_are_powers_of_two() {
        assert!((GAIN - 2f64.powf(-HURST)).abs() < 1e-15);
        assert!((COARSEST_GAIN - (COARSEST / REFERENCE).powf(HURST)).abs() < 1e-12);
    }

    #[test]
    fn octaves_reach_two_cells_and_heights_stay_in_range() {
        let f = Fractal::new(1000.0, 1000.0 / 1200.0, 0.2, 7);
        // 250, 125, ..., 1.95: the last spacing at least two cells of 0.83.
        assert_eq!(f.octaves(), 8);
        let reference = f.octaves[4];
        assert_eq!(reference.spacing, 1000.0 * REFERENCE);
        assert!((reference.amplitude - 0.2 * reference.spacing).abs() < 1e-9);
        let mut rng = SplitMix64::new(1);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for _ in 0..10_000 {
            let h = f.at(1000.0 * rng.unit_f64(), 1000.0 * rng.unit_f64());
            (lo, hi) = (lo.min(h), hi.max(h));
        }
        // Within 0.71 of the amplitudes' sum (21.8, 13.4, ..., 0.3: 56) of zero.
        assert!(lo > -40.0 && hi < 40.0, "{lo}..{hi}");
        assert!(hi - lo > 10.0, "{lo}..{hi}");
    }

    #[test]
    fn noise_is_zero_at_lattice_points_and_continuous() {
        assert_eq!(gradient_noise(3.0, -2.0, 5), 0.0);
        let a = gradient_noise(3.0 - 1e-9, 0.5, 5);
        let b = gradient_noise(3.0 + 1e-9, 0.5, 5);
        assert!((a - b).abs() < 1e-6);
    }
}

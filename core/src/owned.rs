//! Owned forms for engines with an allocator (the `alloc` feature): a hierarchy that owns its
//! file's bytes and a camera that owns its memory, so an asset can hold both without
//! borrowing from elsewhere.
//!
//! The borrowed forms stay the runtime's: [`HierarchyBuf::hierarchy`] hands out the
//! [`Hierarchy`] view validated when the buffer was made, and [`OwnedCamera::camera`] hands
//! out the [`CameraState`] over the camera's own words, where it left off the frame before.

use alloc::vec;
use alloc::vec::Vec;
use core::ops::{Deref, DerefMut};

use bytemuck::{Pod, Zeroable};

use crate::camera::{CameraConfig, CameraError, CameraState, Layout, Scalars};
use crate::format::{FormatError, Meta};
use crate::hierarchy::Hierarchy;

/// One cache line of storage: sections start on multiples of 64 bytes, so in storage aligned
/// to 64 no record straddles two lines.
#[repr(C, align(64))]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Line([u8; 64]);

/// A `.clod` file's bytes in 64-byte aligned storage, validated once when the buffer is made.
///
/// ```no_run
/// # fn demo(path: &str) -> Result<(), Box<dyn std::error::Error>> {
/// use caveclod_core::{CameraState, HierarchyBuf};
/// let asset = HierarchyBuf::from_vec(std::fs::read(path)?)?;
/// let h = asset.hierarchy()?; // no validation again: the view is cheap
/// let mut memory = vec![0u32; CameraState::words_needed(&h)];
/// let cam = CameraState::new(&h, &mut memory)?;
/// # let _ = cam; Ok(()) }
/// ```
#[derive(Clone)]
pub struct HierarchyBuf {
    lines: Vec<Line>,
    len: usize,
    meta: Meta,
    checksum: u64,
}

impl HierarchyBuf {
    /// Copies `bytes` into aligned storage and validates them as
    /// [`Hierarchy::from_bytes`] does.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FormatError> {
        let mut lines = vec![Line([0; 64]); bytes.len().div_ceil(64)];
        bytemuck::cast_slice_mut::<Line, u8>(&mut lines)[..bytes.len()].copy_from_slice(bytes);
        let (meta, checksum) = {
            let h = Hierarchy::from_bytes(&bytemuck::cast_slice(&lines)[..bytes.len()])?;
            (*h.meta(), h.checksum())
        };
        Ok(Self {
            lines,
            len: bytes.len(),
            meta,
            checksum,
        })
    }

    /// [`from_bytes`](Self::from_bytes) for a file read into a `Vec<u8>` (whose storage has
    /// no alignment to reuse, so the bytes are copied once).
    pub fn from_vec(bytes: Vec<u8>) -> Result<Self, FormatError> {
        Self::from_bytes(&bytes)
    }

    /// The file's bytes, starting at a 64-byte aligned address.
    pub fn as_bytes(&self) -> &[u8] {
        &bytemuck::cast_slice(&self.lines)[..self.len]
    }

    /// The validated hierarchy. Finds the sections in the table again (a few comparisons
    /// per section) but neither checks the checksum nor validates the hierarchy again (only
    /// the few references of the materials, if any, from which their view is made). The bytes cannot
    /// change after [`from_bytes`](Self::from_bytes) validated them, so this succeeds; it
    /// returns the table check's error rather than panicking, as the crate never does.
    pub fn hierarchy(&self) -> Result<Hierarchy<'_>, FormatError> {
        Hierarchy::from_validated(self.as_bytes(), self.meta, self.checksum)
    }
}

impl core::fmt::Debug for HierarchyBuf {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("HierarchyBuf")
            .field("len", &self.len)
            .field("meta", &self.meta)
            .field("checksum", &self.checksum)
            .finish()
    }
}

impl TryFrom<&[u8]> for HierarchyBuf {
    type Error = FormatError;
    fn try_from(bytes: &[u8]) -> Result<Self, FormatError> {
        Self::from_bytes(bytes)
    }
}

impl TryFrom<Vec<u8>> for HierarchyBuf {
    type Error = FormatError;
    fn try_from(bytes: Vec<u8>) -> Result<Self, FormatError> {
        Self::from_vec(bytes)
    }
}

/// A camera with its own memory, which keeps its front from one frame to the next.
///
/// [`camera`](Self::camera) hands out the [`CameraState`] over the camera's words, as the
/// last guard left it; the guard writes the camera's state back when dropped. A guard that is
/// never dropped (`mem::forget`) loses that frame's state: the next `camera` call starts from
/// the base mesh.
///
/// ```no_run
/// # fn demo(asset: &caveclod_core::HierarchyBuf, views: &[caveclod_core::View])
/// # -> Result<(), Box<dyn std::error::Error>> {
/// use caveclod_core::{OwnedCamera, RefineParams};
/// let h = asset.hierarchy()?;
/// let mut owned = OwnedCamera::new(&h)?;
/// for view in views {
///     let mut cam = owned.camera(&h);
///     cam.refine(&h, view, &RefineParams::default())?;
///     let mut indices = vec![0u32; cam.total_index_count()];
///     let mut offsets = vec![0u32; h.surface_count() + 1];
///     cam.emit_indices_packed(&h, &mut indices, &mut offsets)?;
/// }
/// # Ok(()) }
/// ```
#[derive(Clone, Debug)]
pub struct OwnedCamera {
    words: Vec<u32>,
    layout: Layout,
    scalars: Scalars,
    /// A guard was handed out and has not written the state back.
    lent: bool,
}

impl OwnedCamera {
    /// A camera at the base mesh able to reach full resolution ([`CameraConfig::full`]).
    pub fn new(h: &Hierarchy<'_>) -> Result<Self, CameraError> {
        Self::with_config(h, &CameraConfig::full(h))
    }

    /// A camera at the base mesh with the given capacity, in
    /// [`CameraState::words_needed_for`] words of its own.
    pub fn with_config(h: &Hierarchy<'_>, config: &CameraConfig) -> Result<Self, CameraError> {
        let layout = CameraState::checked_layout(h, config)?;
        let mut words = vec![0u32; layout.words()];
        let scalars = CameraState::with_config(h, &mut words, config)?.scalars();
        Ok(Self {
            words,
            layout,
            scalars,
            lent: false,
        })
    }

    /// The camera, where the last guard left it, for the hierarchy `h` it was made for
    /// (operations with another hierarchy are refused, as [`CameraState`]'s are).
    pub fn camera(&mut self, h: &Hierarchy<'_>) -> CameraGuard<'_> {
        let lost = self.lent;
        self.lent = true;
        let mut state = CameraState::carve(&mut self.words, &self.layout, self.scalars);
        if lost && state.is_for(h) {
            state.reset(h);
        }
        CameraGuard {
            state,
            scalars: &mut self.scalars,
            lent: &mut self.lent,
        }
    }

    /// Words of memory the camera owns.
    pub fn words(&self) -> usize {
        self.words.len()
    }
}

/// An [`OwnedCamera`]'s [`CameraState`], lent for a frame: derefs to the state, and writes it
/// back into the owned camera when dropped.
#[derive(Debug)]
pub struct CameraGuard<'c> {
    state: CameraState<'c>,
    scalars: &'c mut Scalars,
    lent: &'c mut bool,
}

impl<'c> Deref for CameraGuard<'c> {
    type Target = CameraState<'c>;
    fn deref(&self) -> &CameraState<'c> {
        &self.state
    }
}

impl<'c> DerefMut for CameraGuard<'c> {
    fn deref_mut(&mut self) -> &mut CameraState<'c> {
        &mut self.state
    }
}

impl Drop for CameraGuard<'_> {
    fn drop(&mut self) {
        *self.scalars = self.state.scalars();
        *self.lent = false;
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used)]
mod tests {
    use super::*;
    use crate::params::RefineParams;
    use crate::view::View;
    use glam::Vec3;

    static GOLDEN: &[u8] = include_bytes!("../tests/data/terrain6.clod");

    fn views(h: &Hierarchy<'_>) -> [View; 3] {
        let m = h.meta();
        let lo = Vec3::from_array(m.bounds_min);
        let hi = Vec3::from_array(m.bounds_max);
        let centre = (lo + hi) * 0.5;
        let size = (hi - lo).length().max(1.0);
        [
            View::without_frustum(centre + size * 0.1, 1e6),
            View::without_frustum(centre + size * 2.0, 3e3),
            View::without_frustum(centre + Vec3::new(size * 0.3, size * 0.05, 0.0), 1e5),
        ]
    }

    fn emitted(cam: &CameraState<'_>, h: &Hierarchy<'_>) -> (Vec<u32>, Vec<u32>) {
        let mut indices = vec![0u32; cam.total_index_count()];
        let mut offsets = vec![0u32; h.surface_count() + 1];
        cam.emit_indices_packed(h, &mut indices, &mut offsets)
            .expect("emit");
        (indices, offsets)
    }

    #[test]
    fn buffer_views_the_hierarchy_it_validated() {
        let buf = HierarchyBuf::from_bytes(GOLDEN).expect("valid");
        assert_eq!(buf.as_bytes(), GOLDEN);
        assert_eq!(buf.as_bytes().as_ptr() as usize % 64, 0);
        let h = buf.hierarchy().unwrap();
        let direct = Hierarchy::from_bytes(buf.as_bytes()).expect("valid");
        assert_eq!(h.meta(), direct.meta());
        assert_eq!(h.checksum(), direct.checksum());
        assert_eq!(h.nodes(), direct.nodes());
        assert_eq!(h.polygons(), direct.polygons());
        let from_vec = HierarchyBuf::try_from(GOLDEN.to_vec()).expect("valid");
        assert_eq!(from_vec.hierarchy().unwrap().checksum(), h.checksum());
    }

    #[test]
    fn buffer_refuses_what_from_bytes_refuses() {
        let mut bad = GOLDEN.to_vec();
        let last = bad.len() - 1;
        bad[last] ^= 1;
        assert!(matches!(
            HierarchyBuf::from_vec(bad),
            Err(FormatError::ChecksumMismatch { .. })
        ));
        assert_eq!(
            HierarchyBuf::from_bytes(&GOLDEN[..10]).unwrap_err(),
            FormatError::Truncated {
                needed: 64,
                len: 10
            }
        );
    }

    #[test]
    fn owned_camera_keeps_its_front_across_frames() {
        let buf = HierarchyBuf::from_bytes(GOLDEN).expect("valid");
        let h = buf.hierarchy().unwrap();
        let mut owned = OwnedCamera::new(&h).expect("camera");
        assert_eq!(owned.words(), CameraState::words_needed(&h));
        let mut memory = vec![0u32; CameraState::words_needed(&h)];
        let mut borrowed = CameraState::new(&h, &mut memory).expect("camera");
        let params = RefineParams::default();
        for view in views(&h) {
            borrowed.refine(&h, &view, &params).expect("refine");
            {
                let mut cam = owned.camera(&h);
                let stats = cam.refine(&h, &view, &params).expect("refine");
                let _ = stats;
            }
            let cam = owned.camera(&h);
            assert_eq!(cam.active_polygon_count(), borrowed.active_polygon_count());
            assert_eq!(cam.split_count(), borrowed.split_count());
            assert_eq!(emitted(&cam, &h), emitted(&borrowed, &h));
        }
        assert!(owned.camera(&h).split_count() > 0);
    }

    #[test]
    fn owned_camera_keeps_its_morphs_across_frames() {
        let buf = HierarchyBuf::from_bytes(GOLDEN).expect("valid");
        let h = buf.hierarchy().unwrap();
        let config = CameraConfig::full(&h).with_morphs(16);
        let mut owned = OwnedCamera::with_config(&h, &config).expect("camera");
        let [near, ..] = views(&h);
        // A camera's first frame shows its cut at once; the splits of the next one morph.
        let first = View::without_frustum(near.eye, 0.0);
        let (count, slots) = {
            let mut cam = owned.camera(&h);
            let stats = cam.refine(&h, &first, &RefineParams::default()).unwrap();
            assert_eq!(stats.splits, 0, "{stats:?}");
            let stats = cam.refine(&h, &near, &RefineParams::default()).unwrap();
            assert!(stats.morphing > 0, "{stats:?}");
            (cam.morph_count(), cam.morph_vertices().to_vec())
        };
        let cam = owned.camera(&h);
        assert_eq!(cam.morph_count(), count);
        assert_eq!(cam.morph_vertices(), &slots[..]);
    }

    #[test]
    fn a_forgotten_guard_restarts_from_the_base_mesh() {
        let buf = HierarchyBuf::from_bytes(GOLDEN).expect("valid");
        let h = buf.hierarchy().unwrap();
        let mut owned = OwnedCamera::new(&h).expect("camera");
        let [near, ..] = views(&h);
        let mut cam = owned.camera(&h);
        cam.refine(&h, &near, &RefineParams::default())
            .expect("refine");
        assert!(cam.split_count() > 0);
        core::mem::forget(cam);
        let cam = owned.camera(&h);
        assert_eq!(cam.split_count(), 0);
        assert_eq!(cam.active_polygon_count(), h.base_polygon_count() as u32);
    }

    #[test]
    fn owned_camera_checks_its_config() {
        let buf = HierarchyBuf::from_bytes(GOLDEN).expect("valid");
        let h = buf.hierarchy().unwrap();
        let config = CameraConfig {
            max_pairs: h.splits().len() as u32 + 1,
            ..CameraConfig::full(&h)
        };
        assert_eq!(
            OwnedCamera::with_config(&h, &config).unwrap_err(),
            CameraError::TooManyPairs {
                max_pairs: config.max_pairs,
                split_count: h.splits().len() as u32,
            }
        );
        let small = CameraConfig::with_polygon_budget(&h, 100);
        let owned = OwnedCamera::with_config(&h, &small).expect("camera");
        assert_eq!(owned.words(), CameraState::words_needed_for(&h, &small));
    }
}

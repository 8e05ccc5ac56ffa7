//! Owned bytes in 64-byte aligned memory, as `Hierarchy::from_bytes` wants them: the tests'
//! baked files and the buffers they serialise into.

use caveclod_core::{FormatError, Hierarchy};

/// One cache line, the alignment every section of a `.clod` file keeps.
#[derive(Clone, Copy, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(64))]
struct Line([u8; 64]);

/// Owned bytes whose first byte starts a cache line.
#[derive(Clone, Default, PartialEq, Eq)]
pub struct AlignedBytes {
    lines: Vec<Line>,
    len: usize,
}

impl std::fmt::Debug for AlignedBytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "AlignedBytes({} bytes)", self.len)
    }
}

impl AlignedBytes {
    /// `len` zero bytes.
    pub fn zeroed(len: usize) -> Self {
        Self {
            lines: vec![Line([0; 64]); len.div_ceil(64)],
            len,
        }
    }

    /// A copy of `bytes`.
    pub fn from_slice(bytes: &[u8]) -> Self {
        let mut out = Self::zeroed(bytes.len());
        out.copy_from_slice(bytes);
        out
    }

    /// The bytes.
    pub fn bytes(&self) -> &[u8] {
        let all: &[u8] = bytemuck::cast_slice(&self.lines);
        &all[..self.len]
    }

    /// The hierarchy in the bytes (validated on each call).
    pub fn hierarchy(&self) -> Result<Hierarchy<'_>, FormatError> {
        Hierarchy::from_bytes(self.bytes())
    }
}

impl std::ops::Deref for AlignedBytes {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        self.bytes()
    }
}

impl std::ops::DerefMut for AlignedBytes {
    fn deref_mut(&mut self) -> &mut [u8] {
        let len = self.len;
        let all: &mut [u8] = bytemuck::cast_slice_mut(&mut self.lines);
        &mut all[..len]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_start_a_cache_line_and_keep_their_length() {
        let b = AlignedBytes::from_slice(&[1, 2, 3, 4, 5]);
        assert_eq!(b.as_ptr() as usize % 64, 0);
        assert_eq!(&b[..], &[1, 2, 3, 4, 5]);
    }
}

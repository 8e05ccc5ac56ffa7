//! The file checksum: a fast, non-cryptographic 64-bit hash.
//!
//! It guards against truncation, bit rot and bad copies, not against an adversary: a
//! malicious file that carries a matching checksum is still fully validated before use.
//! Four independent multiply-rotate lanes over little-endian 8-byte words keep it near memory
//! speed, so checking a large file costs little next to reading it.

const P1: u64 = 0x9E37_79B1_85EB_CA87;
const P2: u64 = 0xC2B2_AE3D_27D4_EB4F;
const P3: u64 = 0x1656_67B1_9E37_79F9;

#[inline]
fn round(acc: u64, word: u64) -> u64 {
    acc.wrapping_add(word.wrapping_mul(P2))
        .rotate_left(31)
        .wrapping_mul(P1)
}

#[inline]
fn word(bytes: &[u8]) -> u64 {
    let mut w = [0u8; 8];
    w[..bytes.len()].copy_from_slice(bytes);
    u64::from_le_bytes(w)
}

/// The 64-bit checksum of `bytes`: [`Checksum64`] fed all of them at once.
pub fn checksum64(bytes: &[u8]) -> u64 {
    let mut c = Checksum64::new();
    c.update(bytes);
    c.finish()
}

/// [`checksum64`] computed over bytes given in pieces, for data written or read as a stream:
/// any split of the same bytes gives the same value as `checksum64` of them all.
#[derive(Clone, Debug)]
pub struct Checksum64 {
    lanes: [u64; 4],
    /// Bytes of an unfinished 32-byte block.
    pending: [u8; 32],
    pending_len: usize,
    len: u64,
}

impl Default for Checksum64 {
    fn default() -> Self {
        Self::new()
    }
}

impl Checksum64 {
    /// The checksum of no bytes yet.
    pub const fn new() -> Self {
        Self {
            lanes: [P1 ^ P2, P2, 0, P1.wrapping_neg()],
            pending: [0; 32],
            pending_len: 0,
            len: 0,
        }
    }

    /// Feeds the next bytes.
    pub fn update(&mut self, mut bytes: &[u8]) {
        self.len = self.len.wrapping_add(bytes.len() as u64);
        if self.pending_len > 0 {
            let take = (32 - self.pending_len).min(bytes.len());
            self.pending[self.pending_len..self.pending_len + take].copy_from_slice(&bytes[..take]);
            self.pending_len += take;
            bytes = &bytes[take..];
            if self.pending_len < 32 {
                return;
            }
            let block = self.pending;
            self.block(&block);
            self.pending_len = 0;
        }
        let mut blocks = bytes.chunks_exact(32);
        for block in &mut blocks {
            self.block(block);
        }
        let rest = blocks.remainder();
        self.pending[..rest.len()].copy_from_slice(rest);
        self.pending_len = rest.len();
    }

    #[inline]
    fn block(&mut self, block: &[u8]) {
        for (lane, chunk) in self.lanes.iter_mut().zip(block.chunks_exact(8)) {
            *lane = round(*lane, word(chunk));
        }
    }

    /// The checksum of every byte fed so far.
    pub fn finish(&self) -> u64 {
        let lanes = &self.lanes;
        let mut h = lanes[0]
            .rotate_left(1)
            .wrapping_add(lanes[1].rotate_left(7))
            .wrapping_add(lanes[2].rotate_left(12))
            .wrapping_add(lanes[3].rotate_left(18));
        h = h.wrapping_add(self.len);
        for chunk in self.pending[..self.pending_len].chunks(8) {
            h ^= round(0, word(chunk));
            h = h.rotate_left(27).wrapping_mul(P1).wrapping_add(P3);
        }
        h ^= h >> 33;
        h = h.wrapping_mul(P2);
        h ^= h >> 29;
        h = h.wrapping_mul(P3);
        h ^ (h >> 32)
    }
}

#[cfg(test)]
mod tests {
    use super::{checksum64, Checksum64};

    /// The checksum as it was defined over one slice; the streamed one must equal it.
    fn reference(bytes: &[u8]) -> u64 {
        let mut lanes = [
            super::P1 ^ super::P2,
            super::P2,
            0,
            super::P1.wrapping_neg(),
        ];
        let mut blocks = bytes.chunks_exact(32);
        for block in &mut blocks {
            for (lane, chunk) in lanes.iter_mut().zip(block.chunks_exact(8)) {
                *lane = super::round(*lane, super::word(chunk));
            }
        }
        let mut h = lanes[0]
            .rotate_left(1)
            .wrapping_add(lanes[1].rotate_left(7))
            .wrapping_add(lanes[2].rotate_left(12))
            .wrapping_add(lanes[3].rotate_left(18));
        h = h.wrapping_add(bytes.len() as u64);
        for chunk in blocks.remainder().chunks(8) {
            h ^= super::round(0, super::word(chunk));
            h = h
                .rotate_left(27)
                .wrapping_mul(super::P1)
                .wrapping_add(super::P3);
        }
        h ^= h >> 33;
        h = h.wrapping_mul(super::P2);
        h ^= h >> 29;
        h = h.wrapping_mul(super::P3);
        h ^ (h >> 32)
    }

    #[test]
    fn any_split_of_the_bytes_gives_the_one_slice_checksum() {
        let mut data = [0u8; 150];
        for (i, b) in data.iter_mut().enumerate() {
            *b = (i * 131 + 17) as u8;
        }
        for len in [0, 1, 7, 8, 31, 32, 33, 64, 95, 150] {
            let bytes = &data[..len];
            let whole = reference(bytes);
            assert_eq!(checksum64(bytes), whole, "len {len}");
            for step in [1, 3, 8, 13, 32, 40] {
                let mut c = Checksum64::new();
                for piece in bytes.chunks(step) {
                    c.update(piece);
                    c.update(&[]);
                }
                assert_eq!(c.finish(), whole, "len {len} in pieces of {step}");
            }
            for cut in 0..=len {
                let mut c = Checksum64::new();
                c.update(&bytes[..cut]);
                c.update(&bytes[cut..]);
                assert_eq!(c.finish(), whole, "len {len} cut at {cut}");
            }
        }
    }

    #[test]
    fn every_single_bit_flip_changes_the_checksum() {
        let mut data = [0u8; 77];
        for (i, b) in data.iter_mut().enumerate() {
            *b = (i * 31 + 7) as u8;
        }
        let base = checksum64(&data);
        for i in 0..data.len() {
            for bit in 0..8 {
                data[i] ^= 1 << bit;
                assert_ne!(checksum64(&data), base, "byte {i} bit {bit}");
                data[i] ^= 1 << bit;
            }
        }
    }

    #[test]
    fn length_matters() {
        assert_ne!(checksum64(&[0; 8]), checksum64(&[0; 16]));
        assert_ne!(checksum64(&[]), checksum64(&[0]));
    }
}

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

/// The 64-bit checksum of `bytes`.
pub fn checksum64(bytes: &[u8]) -> u64 {
    let mut lanes = [P1 ^ P2, P2, 0, P1.wrapping_neg()];
    let mut blocks = bytes.chunks_exact(32);
    for block in &mut blocks {
        for (lane, chunk) in lanes.iter_mut().zip(block.chunks_exact(8)) {
            *lane = round(*lane, word(chunk));
        }
    }
    let mut h = lanes[0]
        .rotate_left(1)
        .wrapping_add(lanes[1].rotate_left(7))
        .wrapping_add(lanes[2].rotate_left(12))
        .wrapping_add(lanes[3].rotate_left(18));
    h = h.wrapping_add(bytes.len() as u64);
    for chunk in blocks.remainder().chunks(8) {
        h ^= round(0, word(chunk));
        h = h.rotate_left(27).wrapping_mul(P1).wrapping_add(P3);
    }
    h ^= h >> 33;
    h = h.wrapping_mul(P2);
    h ^= h >> 29;
    h = h.wrapping_mul(P3);
    h ^ (h >> 32)
}

#[cfg(test)]
mod tests {
    use super::checksum64;

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

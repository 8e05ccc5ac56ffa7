//! Memory for many cameras' states in one aligned buffer, huge pages where granted.

use crate::aligned::AlignedBytes;

/// Memory for several camera states (`CameraState::with_config`) in one [`AlignedBytes`]
/// buffer, so that many cameras' states, like a large hierarchy, get huge pages where the
/// system grants them. Each state starts on a cache line of its own, so cameras refined on
/// different threads share no line.
pub struct CameraPool {
    bytes: AlignedBytes,
    /// Words per state as asked for.
    words: usize,
    /// Words from one state's start to the next's (a whole number of cache lines).
    stride: usize,
}

impl CameraPool {
    /// Zeroed room for `count` states of `words` words each.
    pub fn new(words: usize, count: usize) -> Self {
        // At least a line, so that there are `count` memories even of no words.
        let stride = words.next_multiple_of(16).max(16);
        Self {
            bytes: AlignedBytes::zeroed(4 * stride * count),
            words,
            stride,
        }
    }

    /// The states' memories, in order, `words` words each.
    pub fn memories(&mut self) -> impl Iterator<Item = &mut [u32]> {
        let words = self.words;
        self.bytes.chunks_exact_mut(4 * self.stride).map(move |c| {
            // Each chunk starts a whole number of cache lines into 64-byte aligned bytes and
            // holds `stride >= words` words, so the cast is aligned and long enough.
            &mut bytemuck::cast_slice_mut::<u8, u32>(c)[..words]
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_state_starts_a_cache_line_and_keeps_its_words() {
        let mut pool = CameraPool::new(1001, 3);
        let mut n = 0;
        for (k, m) in pool.memories().enumerate() {
            assert_eq!(m.len(), 1001);
            assert_eq!(m.as_ptr() as usize % 64, 0);
            assert!(m.iter().all(|&w| w == 0));
            m.fill(k as u32 + 1);
            n += 1;
        }
        assert_eq!(n, 3);
        let firsts: Vec<u32> = pool.memories().map(|m| m[0] + m[1000]).collect();
        assert_eq!(firsts, [2, 4, 6]);
        assert_eq!(CameraPool::new(0, 2).memories().count(), 2);
    }
}

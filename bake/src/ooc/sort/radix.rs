//! The runs' sort: a stable least-significant-digit radix sort by a 64-bit key.

/// Bits of a radix-sort digit.
const DIGIT_BITS: u32 = 11;

/// Sorts `(key, index)` pairs with increasing indices by key (so by key, then index): a
/// stable least-significant-digit radix sort on 11-bit digits, skipping the digits every key
/// shares (the high digits of a run's keys, which come from one region of the input, mostly
/// are). Six passes at most, linear time, against the `n log n` comparisons of a sort.
pub(super) fn radix_sort(v: &mut Vec<(u64, u32)>) {
    radix_sort_by(v, |&(k, _)| k);
}

/// The radix sort of [`radix_sort`] on any items by `key` (stable).
pub(super) fn radix_sort_by<E: Copy + Default>(v: &mut Vec<E>, key: impl Fn(&E) -> u64) {
    let Some(first) = v.first().map(&key) else {
        return;
    };
    const DIGITS: usize = 64usize.div_ceil(DIGIT_BITS as usize);
    const RADIX: usize = 1 << DIGIT_BITS;
    let mask = RADIX as u64 - 1;
    let mut varying = 0u64;
    let mut counts = vec![[0usize; RADIX]; DIGITS];
    for e in v.iter() {
        let k = key(e);
        varying |= k ^ first;
        for (d, c) in counts.iter_mut().enumerate() {
            c[((k >> (d as u32 * DIGIT_BITS)) & mask) as usize] += 1;
        }
    }
    let mut other = vec![E::default(); v.len()];
    for (d, c) in counts.iter_mut().enumerate() {
        let shift = d as u32 * DIGIT_BITS;
        if (varying >> shift) & mask == 0 {
            continue;
        }
        let mut at = 0;
        for n in c.iter_mut() {
            let here = *n;
            *n = at;
            at += here;
        }
        for e in v.iter() {
            let b = ((key(e) >> shift) & mask) as usize;
            other[c[b]] = *e;
            c[b] += 1;
        }
        std::mem::swap(v, &mut other);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radix_sort_orders_by_key_then_index() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut v: Vec<(u64, u32)> = (0..5000u32)
            .map(|i| {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1);
                // High bits shared, a few distinct values repeated, and the full range.
                let k = match i % 3 {
                    0 => (7 << 50) | (state >> 40),
                    1 => (7 << 50) | (state >> 61),
                    _ => state,
                };
                (k, i)
            })
            .collect();
        let mut want = v.clone();
        want.sort_unstable();
        radix_sort(&mut v);
        assert_eq!(v, want);
        let mut same = vec![(5u64, 0u32), (5, 1), (5, 2)];
        radix_sort(&mut same);
        assert_eq!(same, [(5, 0), (5, 1), (5, 2)]);
        radix_sort(&mut Vec::new());
    }
}

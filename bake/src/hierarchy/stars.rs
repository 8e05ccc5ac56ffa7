//! The triangles around every node, every node's list in one pool: a start and a length
//! per node (8 bytes) instead of a vector per node (a 24-byte header and a block of its
//! own). A collapse's new node gets its children's lists, appended to the pool in turn;
//! the pool is compacted when what no list holds outgrows a quarter of what lists hold and
//! the number of nodes (a compaction goes through every node: so it costs a few steps per
//! entry it frees).

use super::prefetch::prefetch;

/// The triangles around every node: node `v`'s are `pool[start[v]..][..len[v]]`.
#[derive(Default)]
pub(super) struct Stars {
    /// Where each node's list starts in `pool`. The lists lie in the pool in node order.
    start: Vec<u32>,
    /// Each node's list's length.
    len: Vec<u32>,
    /// The lists.
    pool: Vec<u32>,
    /// Entries of `pool` that no list holds.
    waste: usize,
}

impl Stars {
    /// The lists of `positions` leaves from the triangles' corners: each position's
    /// triangles in triangle order.
    pub(super) fn of_triangles(
        positions: usize,
        corners: impl Iterator<Item = [u32; 3]> + Clone,
    ) -> Self {
        let mut len = vec![0u32; positions];
        for c in corners.clone() {
            for x in c {
                len[x as usize] += 1;
            }
        }
        let mut start = Vec::with_capacity(positions);
        let mut at = 0u32;
        for n in &mut len {
            start.push(at);
            at += std::mem::take(n);
        }
        let mut pool = vec![0u32; at as usize];
        for (f, c) in corners.enumerate() {
            for x in c {
                let x = x as usize;
                pool[(start[x] + len[x]) as usize] = f as u32;
                len[x] += 1;
            }
        }
        Self {
            start,
            len,
            pool,
            waste: 0,
        }
    }

    /// The triangles around node `v`.
    #[inline]
    pub(super) fn of(&self, v: u32) -> &[u32] {
        let s = self.start[v as usize] as usize;
        &self.pool[s..s + self.len[v as usize] as usize]
    }

    /// Room for `more` nodes.
    pub(super) fn reserve_nodes(&mut self, more: usize) {
        self.start.reserve_exact(more);
        self.len.reserve_exact(more);
    }

    /// Starts loading where node `v`'s list is (a hint, for
    /// [`super::work::Work::prefetch_around`]).
    #[inline]
    pub(super) fn prefetch_place(&self, v: u32) {
        prefetch(&self.start[v as usize]);
        prefetch(&self.len[v as usize]);
    }

    /// Starts loading node `v`'s list (a hint).
    #[inline]
    pub(super) fn prefetch_list(&self, v: u32) {
        if let Some(first) = self.pool.get(self.start[v as usize] as usize) {
            prefetch(first);
        }
    }

    /// Removes triangle `f` from node `v`'s list, keeping the order of the others.
    pub(super) fn remove(&mut self, v: u32, f: u32) {
        let s = self.start[v as usize] as usize;
        let list = &mut self.pool[s..s + self.len[v as usize] as usize];
        let mut kept = 0;
        for i in 0..list.len() {
            if list[i] != f {
                list[kept] = list[i];
                kept += 1;
            }
        }
        self.waste += list.len() - kept;
        self.len[v as usize] = kept as u32;
    }

    /// A new node whose list is `a`'s followed by `b`'s, but for the triangles `dropped`
    /// (as if removed from both first); theirs become empty. Returns how many of `a`'s it
    /// took.
    pub(super) fn push_merged(&mut self, a: u32, b: u32, dropped: [u32; 2]) -> usize {
        // A start past 32 bits: compacted, the pool holds the lists alone, at most three
        // entries a triangle, which the weld keeps within 32 bits.
        if self.pool.len() > u32::MAX as usize {
            self.compact();
        }
        let at = self.pool.len();
        let mut from_a = 0;
        for v in [a, b] {
            let s = self.start[v as usize] as usize;
            let n = std::mem::take(&mut self.len[v as usize]) as usize;
            for i in s..s + n {
                let f = self.pool[i];
                if f != dropped[0] && f != dropped[1] {
                    self.pool.push(f);
                }
            }
            self.waste += n;
            if v == a {
                from_a = self.pool.len() - at;
            }
        }
        self.start.push(at as u32);
        self.len.push((self.pool.len() - at) as u32);
        let held = self.pool.len() - self.waste;
        if self.waste > (held / 4).max(self.start.len()) {
            self.compact();
        }
        from_a
    }

    /// Moves every list down over the entries no list holds, in node order (the order
    /// they lie in). Most nodes are no longer live and hold none, and a live one a few:
    /// an entry at a time, which moves them down as a block copy would.
    fn compact(&mut self) {
        let mut to = 0usize;
        for v in 0..self.start.len() {
            let (s, n) = (self.start[v] as usize, self.len[v] as usize);
            for i in 0..n {
                self.pool[to + i] = self.pool[s + i];
            }
            self.start[v] = to as u32;
            to += n;
        }
        self.pool.truncate(to);
        self.waste = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::Stars;
    use crate::hierarchy::types::NONE;

    /// The pool holds what a vector per node would, through removals, merges (dropping a
    /// triangle or not) and the compactions they set off.
    #[test]
    fn the_pool_keeps_every_list_through_compactions() {
        // A strip of triangles over 40 positions: triangle f has corners f, f + 1, f + 2.
        let corners: Vec<[u32; 3]> = (0..38u32).map(|f| [f, f + 1, f + 2]).collect();
        let mut stars = Stars::of_triangles(40, corners.iter().copied());
        let mut model: Vec<Vec<u32>> = vec![Vec::new(); 40];
        for (f, c) in corners.iter().enumerate() {
            for &x in c {
                model[x as usize].push(f as u32);
            }
        }
        let mut compactions = 0;
        // Merge neighbours pairwise, removing a triangle of each pair first: from every
        // other list, and from the pair's through the merge on every other merge.
        let mut live: Vec<u32> = (0..40).collect();
        let mut merges = 0;
        while live.len() > 1 {
            let (a, b) = (live.remove(0), live.remove(0));
            let through_merge = merges % 2 == 0;
            let mut dropped = [NONE; 2];
            if let Some(&f) = model[a as usize].first() {
                for x in 0..model.len() as u32 {
                    if !(through_merge && (x == a || x == b)) {
                        stars.remove(x, f);
                    }
                    model[x as usize].retain(|&g| g != f);
                }
                if through_merge {
                    dropped[0] = f;
                }
            }
            let waste = stars.waste;
            let from_a = stars.push_merged(a, b, dropped);
            merges += 1;
            compactions += usize::from(stars.waste < waste);
            assert_eq!(from_a, model[a as usize].len());
            let mut merged = std::mem::take(&mut model[a as usize]);
            merged.append(&mut model[b as usize]);
            model.push(merged);
            live.push(model.len() as u32 - 1);
            for (v, list) in model.iter().enumerate() {
                assert_eq!(stars.of(v as u32), &list[..], "node {v}");
            }
        }
        assert!(compactions > 0, "no compaction happened");
    }
}

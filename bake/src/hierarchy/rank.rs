//! Ranking a pass's collapses: each edge slot's cheaper allowed direction, and the ranked
//! collapses handed out by cost through buckets sorted only when reached.

use super::geometry::{corner_of, next, prev};
use super::prefetch::prefetch;
use super::records::Tri;
use super::types::{NONE, PARALLEL_MIN};
use super::work::Work;
use rayon::prelude::*;

/// A collapse as a pass ranks it: `(cost, t, u)`.
pub(super) type Candidate = (f64, u32, u32);

/// The ranking of one edge slot (3 per triangle) in the current pass, as [`Slots`] holds it.
#[derive(Clone, Copy)]
pub(super) struct Slot {
    /// The edge's ends, first and second corner of the slot: as the triangle has them now,
    /// which are those of the start of the pass while either is free ([`Slots::get`]).
    pub(super) ends: [u32; 2],
    /// The cost of the cheaper allowed direction, infinite for none.
    pub(super) cost: f64,
    /// The cheaper allowed direction ([`dir`]): 1 moves the first end onto the second, 2 the
    /// reverse, 0 for none.
    pub(super) dir: u8,
}

/// The cheaper allowed direction of a slot's quadric costs `[cx, cy]` (direction 1 moves
/// the first end onto the second, direction 2 the reverse; infinite where not allowed):
/// the first on a tie, 0 for none.
#[inline]
pub(super) fn dir([cx, cy]: [f64; 2]) -> u8 {
    if cy < cx {
        2
    } else if cx.is_finite() {
        1
    } else {
        0
    }
}

/// Slot `k`'s direction ([`dir`]) out of a triangle's direction bits.
#[inline]
fn dir_of(dirs: u8, k: usize) -> u8 {
    (dirs >> (2 * k)) & 3
}

/// How many of a triangle's slots list a collapse (have a direction), from its direction
/// bits.
#[inline]
fn listed(dirs: u8) -> usize {
    // Bit 2k set when slot k has a direction.
    let any = (dirs | dirs >> 1) & 0b01_0101;
    usize::from(any & 1) + usize::from(any >> 2 & 1) + usize::from(any >> 4)
}

/// Sets slot `k` of a triangle's costs and direction bits from its two directions' costs.
/// A slot keeps the cheaper allowed direction's cost only: the other is ranked again where
/// a pass needs it ([`Work::other_cost`]), and comes out the same.
fn set_slot(cost: &mut [f64; 3], dirs: &mut u8, k: usize, costs: [f64; 2]) {
    let d = dir(costs);
    *dirs = (*dirs & !(3 << (2 * k))) | (d << (2 * k));
    cost[k] = if d == 0 {
        f64::INFINITY
    } else {
        costs[d as usize - 1]
    };
}

/// The rankings of the three edge slots of every live triangle, by the triangle's place in
/// the list of live triangles: slot `3 × i + k` is slot `k` of triangle `live[i]`. The
/// list keeps the triangles' order, so the slots' numbers are in the order of
/// `3 × triangle + k`, and the rankings of the triangles a pass removed are dropped before
/// the next pass ranks.
///
/// A triangle's rankings take 25 bytes: the three costs and the directions; the list of
/// live triangles is made when a pass first removes some (until then it is every triangle,
/// and the first pass, when the build's memory peaks, holds none). A slot's ends
/// are read from the triangle's current corners, and the slots to rank again from what the
/// collapses mark ([`Slots::mark_changed`]), rather than kept as the corners they were
/// ranked with.
pub(super) struct Slots {
    /// The live triangles, in order; `None` while they are all the mesh's.
    live: Option<Vec<u32>>,
    /// Their slots' costs: the cheaper allowed direction's, infinite for none.
    costs: Vec<[f64; 3]>,
    /// Their slots' directions, slot `k`'s in bits `2k..2k + 2`.
    dirs: Vec<u8>,
    /// By triangle: bit `k` set when a collapse changed an end of slot `k` since it was
    /// last ranked (all set before the first ranking).
    changed: Vec<u8>,
}

impl Slots {
    /// Slots of `triangles` triangles, all live, none ranked.
    pub(super) fn new(triangles: usize) -> Self {
        Self {
            live: None,
            costs: vec![[f64::INFINITY; 3]; triangles],
            dirs: vec![0; triangles],
            changed: vec![0b111; triangles],
        }
    }

    /// Drops the triangles no longer `alive` and their rankings, keeping the order; gives
    /// the memory back once a ninth of it is free (a large block's tail goes back to the
    /// system without a copy), so that the rankings shrink with the mesh pass by pass.
    pub(super) fn retain_alive(&mut self, alive: &[bool]) {
        let places = self.costs.len();
        let mut live = self.live.take();
        let mut kept = 0;
        for i in 0..places {
            let f = triangle_at(live.as_deref(), i);
            if alive[f as usize] {
                if let Some(live) = &mut live {
                    live[kept] = f;
                }
                self.costs[kept] = self.costs[i];
                self.dirs[kept] = self.dirs[i];
                kept += 1;
            }
        }
        let mut live = match live {
            Some(mut live) => {
                live.truncate(kept);
                live
            }
            None if kept == places => return,
            None => {
                let mut live = Vec::with_capacity(kept);
                live.extend((0..places as u32).filter(|&f| alive[f as usize]));
                live
            }
        };
        self.costs.truncate(kept);
        self.dirs.truncate(kept);
        if kept + kept / 8 < self.costs.capacity() {
            live.shrink_to_fit();
            self.costs.shrink_to_fit();
            self.dirs.shrink_to_fit();
        }
        self.live = Some(live);
    }

    /// Starts loading what [`Slots::get`] and the check of the ends will read for the
    /// slots a few entries after entry `j` of `list` (slot numbers), a step each: the
    /// slot's place in the lists, then its triangle, then (through `ends`) what the ends
    /// are checked by. The slots are spread over the whole mesh, so each step would
    /// otherwise wait for memory in turn.
    #[inline]
    fn prefetch(&self, tris: &[Tri], list: &[u32], j: usize, ends: impl Fn(u32)) {
        if let Some(&i) = list.get(j + 16) {
            let place = i as usize / 3;
            if let Some(live) = &self.live {
                prefetch(&live[place]);
            }
            prefetch(&self.costs[place]);
            prefetch(&self.dirs[place]);
        }
        if let Some(&i) = list.get(j + 8) {
            prefetch(&tris[self.triangle(i as usize / 3) as usize]);
        }
        if let Some(&i) = list.get(j + 4) {
            let (place, k) = (i as usize / 3, i as usize % 3);
            let c = tris[self.triangle(place) as usize].c;
            ends(c[k]);
            ends(c[next(k)]);
        }
    }

    /// The triangle at place `i` of the live list.
    #[inline]
    fn triangle(&self, i: usize) -> u32 {
        triangle_at(self.live.as_deref(), i)
    }

    /// Marks the slots whose ends the collapse that made node `s` changed: those of the
    /// triangles around `s` with `s` at one of their ends (every such corner was the
    /// collapse's `t` or `u`).
    pub(super) fn mark_changed(&mut self, work: &Work<'_>, s: u32) {
        for &f in work.faces_of.of(s) {
            let c = work.tris[f as usize].c;
            let j = corner_of(c, s);
            // Corner `j` is an end of slots `j` and `j − 1`.
            self.changed[f as usize] |= (1 << j) | (1 << prev(j));
        }
    }

    /// The number of slot `k` of the live triangle `f`.
    pub(super) fn number(&self, f: u32, k: usize) -> usize {
        let i = match &self.live {
            Some(live) => {
                let (Ok(i) | Err(i)) = live.binary_search(&f);
                i
            }
            None => f as usize,
        };
        3 * i + k
    }

    /// The triangle and slot of slot number `i`.
    pub(super) fn slot(&self, i: usize) -> (u32, usize) {
        (self.triangle(i / 3), i % 3)
    }

    /// Slot `i` (`3 × place + slot`), its ends read from the current corners `tris`.
    ///
    /// During a pass these are the ends it was ranked with unless both are stamped
    /// (taken): a collapse changes only the triangles around its ends `t` and `u`, so a
    /// changed triangle's corners, before and after, are `t`, `u`, the new node and
    /// their rings, which it stamps; and no later collapse of the pass has a stamped end.
    #[inline]
    pub(super) fn get(&self, tris: &[Tri], i: usize) -> Slot {
        let (place, k) = (i / 3, i % 3);
        let c = tris[self.triangle(place) as usize].c;
        Slot {
            ends: [c[k], c[next(k)]],
            cost: self.costs[place][k],
            dir: dir_of(self.dirs[place], k),
        }
    }

    /// Sets the slots of the live triangle at place `i` from their costs (for tests).
    #[cfg(test)]
    pub(super) fn set(&mut self, i: usize, costs: [[f64; 2]; 3]) {
        for (k, c) in costs.into_iter().enumerate() {
            set_slot(&mut self.costs[i], &mut self.dirs[i], k, c);
        }
        let f = self.triangle(i);
        self.changed[f as usize] = 0;
    }
}

/// The triangle at place `i` of the live triangles `live` (`None`: every triangle).
#[inline]
fn triangle_at(live: Option<&[u32]>, i: usize) -> u32 {
    live.map_or(i as u32, |live| live[i])
}

/// The bits of `x` as an unsigned number ordered as [`f64::total_cmp`] orders floats.
#[inline]
pub(super) fn order_key(x: f64) -> u64 {
    let bits = x.to_bits();
    // Negative numbers: all bits flipped; others: the sign bit set.
    bits ^ (((bits as i64 >> 63) as u64) | (1 << 63))
}

/// The ranked collapses of a pass, handed out by cost, equal costs in the order they were
/// ranked. They are bucketed by the top bits of their cost first, and a bucket is sorted
/// only when reached, after dropping those whose ends are taken by then (which the pass
/// would skip wherever they stood). The buckets hold slot numbers (`3 × triangle + slot`),
/// not the collapses: the slots hold the rest for the whole pass.
#[derive(Default)]
pub(super) struct Ranked {
    /// The candidates' slot numbers, bucket after bucket, each in ranking order.
    by_bucket: Vec<u32>,
    /// Where each bucket starts in `by_bucket`, and the end.
    bounds: Vec<u32>,
    /// The next bucket.
    bucket: usize,
    /// The current bucket's remaining candidates, sorted.
    chunk: Vec<Candidate>,
    /// The next one in `chunk`.
    pos: usize,
}

/// Bits of [`order_key`] that pick a bucket: sign, exponent and 4 bits of mantissa.
const BUCKET_BITS: u32 = 16;

/// The bucket of a cost: the top [`BUCKET_BITS`] of its [`order_key`].
#[inline]
fn bucket_of(cost: f64) -> u64 {
    order_key(cost) >> (64 - BUCKET_BITS)
}

/// Candidates below which a pass sorts them all at once.
const BUCKET_MIN: usize = 4096;

/// The ranked collapses of the live triangles in `slots`, in slot order, their ends read
/// from the current corners `tris`.
pub(super) fn candidates<'a>(
    slots: &'a Slots,
    tris: &'a [Tri],
) -> impl Iterator<Item = Candidate> + 'a {
    (0..3 * slots.costs.len()).filter_map(move |i| candidate(&slots.get(tris, i)))
}

/// The costs of the ranked collapses of `slots` with their slot numbers, in slot order: a
/// slot lists a collapse exactly when its cost is finite ([`set_slot`]).
fn costs(slots: &Slots) -> impl Iterator<Item = (u32, f64)> + '_ {
    slots.costs.iter().enumerate().flat_map(|(i, cost)| {
        (0..3)
            .map(move |k| ((3 * i + k) as u32, cost[k]))
            .filter(|(_, c)| c.is_finite())
    })
}

impl Ranked {
    /// Takes a pass's `count` candidates (those of the live triangles in `slots`, with
    /// their current corners `tris`), of
    /// which the pass means to apply the cheapest `share`; returns the [`order_key`] of the
    /// dearest cost in that share (for many candidates, rounded up to the end of its bucket),
    /// or `u64::MAX` when the share is every candidate. Only candidates up to it are handed
    /// out, and the pass cuts what is dearer, the other directions it queues included: a
    /// share of everything cuts nothing. Many candidates are counted by bucket on up to
    /// `threads` threads.
    pub(super) fn start(
        &mut self,
        slots: &Slots,
        tris: &[Tri],
        count: usize,
        share: f64,
        threads: usize,
    ) -> u64 {
        self.chunk.clear();
        self.pos = 0;
        let want = ((count as f64 * share).ceil() as usize).clamp(1, count.max(1));
        let everything = want >= count;
        if count < BUCKET_MIN {
            self.chunk.extend(candidates(slots, tris));
            self.chunk.sort_by(|a, b| a.0.total_cmp(&b.0));
            self.bucket = self.bounds.len().saturating_sub(1);
            return match self.chunk.get(want - 1) {
                Some(c) if !everything => order_key(c.0),
                _ => u64::MAX,
            };
        }
        self.count_buckets(slots, threads);
        for i in 0..1 << BUCKET_BITS {
            self.bounds[i + 1] += self.bounds[i];
        }
        // The bucket holding the `want`-th cheapest; those after it are left out.
        let last = self.bounds[1..].partition_point(|&n| (n as usize) < want);
        let limit = if everything || last + 1 >= 1 << BUCKET_BITS {
            u64::MAX
        } else {
            (((last + 1) as u64) << (64 - BUCKET_BITS)) - 1
        };
        let kept = self.bounds[last + 1] as usize;
        self.bounds.truncate(last + 2);
        self.by_bucket.clear();
        self.by_bucket.resize(kept, 0);
        let mut fill = self.bounds.clone();
        let bucket = |c: f64| bucket_of(c) as usize;
        for (i, c) in costs(slots) {
            let b = bucket(c);
            if b <= last {
                self.by_bucket[fill[b] as usize] = i;
                fill[b] += 1;
            }
        }
        self.bucket = 0;
        limit
    }

    /// Sets `bounds[b + 1]` to the number of ranked collapses of `slots` in bucket `b`
    /// (`bounds[0]` to 0), counting ranges of triangles on up to `threads` threads.
    fn count_buckets(&mut self, slots: &Slots, threads: usize) {
        let count = |costs: &[[f64; 3]], counts: &mut [u32]| {
            for cost in costs {
                for c in cost.iter().copied().filter(|c| c.is_finite()) {
                    counts[bucket_of(c) as usize + 1] += 1;
                }
            }
        };
        self.bounds.clear();
        self.bounds.resize((1 << BUCKET_BITS) + 1, 0);
        if threads <= 1 || slots.costs.len() < PARALLEL_MIN {
            count(&slots.costs, &mut self.bounds);
            return;
        }
        let per = slots.costs.len().div_ceil(threads);
        let parts: Vec<Vec<u32>> = slots
            .costs
            .par_chunks(per)
            .map(|costs| {
                let mut counts = vec![0u32; (1 << BUCKET_BITS) + 1];
                count(costs, &mut counts);
                counts
            })
            .collect();
        for part in parts {
            for (total, n) in self.bounds.iter_mut().zip(part) {
                *total += n;
            }
        }
    }

    /// The next candidate whose ends were free (not `taken`) when its bucket was reached.
    pub(super) fn peek(
        &mut self,
        slots: &Slots,
        tris: &[Tri],
        taken: impl Fn(u32) -> bool,
        ahead: impl Fn(u32),
    ) -> Option<Candidate> {
        while self.pos == self.chunk.len() {
            if self.bucket + 1 >= self.bounds.len() {
                return None;
            }
            let (a, b) = (
                self.bounds[self.bucket] as usize,
                self.bounds[self.bucket + 1] as usize,
            );
            self.bucket += 1;
            if a == b {
                continue;
            }
            self.chunk.clear();
            self.pos = 0;
            let bucket = &self.by_bucket[a..b];
            for (j, &i) in bucket.iter().enumerate() {
                slots.prefetch(tris, bucket, j, &ahead);
                let Some(c) = candidate(&slots.get(tris, i as usize)) else {
                    continue;
                };
                if !taken(c.1) && !taken(c.2) {
                    self.chunk.push(c);
                }
            }
            self.chunk.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        Some(self.chunk[self.pos])
    }

    pub(super) fn advance(&mut self) {
        self.pos += 1;
    }

    /// The ends of the candidate `k` after the next in the current bucket, if any (to
    /// start loading what its checks read).
    pub(super) fn upcoming(&self, k: usize) -> Option<[u32; 2]> {
        self.chunk.get(self.pos + k).map(|c| [c.1, c.2])
    }
}

impl Work<'_> {
    /// Ranks the slots of triangle `f` marked `changed` (bit `k` for slot `k`) in its
    /// `cost` and `dirs`; returns how many of its slots list a collapse.
    ///
    /// A ranking stands while the edge's ends are the same nodes: it reads their quadrics
    /// and positions (a node's never change), the groups of the triangles on the edge, and
    /// which those are (they change only by a collapse that also changes an end).
    fn rank_triangle(&self, f: u32, changed: u8, cost: &mut [f64; 3], dirs: &mut u8) -> usize {
        if changed != 0 {
            for k in 0..3 {
                if changed & (1 << k) != 0 {
                    set_slot(cost, dirs, k, self.rank(f, k));
                }
            }
        }
        listed(*dirs)
    }

    /// The costs of the edge in slot `k` of triangle `f` if the slot stands for its edge
    /// (the lower-numbered end first, or a border edge): the quadric costs of the directions
    /// the surface-group rules allow, infinite where not allowed (both, for a slot that does
    /// not stand for its edge).
    fn rank(&self, f: u32, k: usize) -> [f64; 2] {
        let tri = &self.tris[f as usize];
        let (a, b, g) = (tri.c[k], tri.c[next(k)], tri.o[k]);
        if !(a < b || g == NONE) {
            return [f64::INFINITY; 2];
        }
        // Direction 1 moves a onto b across g (t = b, u = a); direction 2 the reverse.
        let cx = if g != NONE && self.groups_ok(b, a, g, f) {
            self.cost(b, a)
        } else {
            f64::INFINITY
        };
        let cy = if self.groups_ok(a, b, f, g) {
            self.cost(a, b)
        } else {
            f64::INFINITY
        };
        [cx, cy]
    }

    /// The cost of the other direction than the cheaper of slot `k` of triangle `f`,
    /// infinite where not allowed, ranked again: during a pass, while neither end of the
    /// slot's edge is stamped, the edge, its ends and its triangles are those it was ranked
    /// with, so this is the cost the ranking found.
    pub(super) fn other_cost(&self, f: u32, k: usize) -> f64 {
        let costs = self.rank(f, k);
        match dir(costs) {
            0 => f64::INFINITY,
            d => costs[2 - d as usize],
        }
    }
}

/// Ranks the slots of the live triangles that collapses changed since they were last ranked
/// ([`Slots::mark_changed`]; a ranking stands while the edge's ends are the same nodes),
/// split into rayon tasks by ranges of triangles (each slot's ranking depends on the mesh
/// alone, so the split does not change it); returns how many slots list a collapse (have
/// an allowed direction), which [`candidates`] hands out in slot order.
pub(super) fn rank_all(work: &Work<'_>, slots: &mut Slots, threads: usize) -> usize {
    let Slots {
        live,
        costs,
        dirs,
        changed,
    } = slots;
    let (live, marked) = (live.as_deref(), &*changed);
    // Ranks the places from `first` on.
    let rank_part = |first: usize, costs: &mut [[f64; 3]], dirs: &mut [u8]| {
        let places = costs.len();
        costs
            .iter_mut()
            .zip(dirs)
            .enumerate()
            .map(|(j, (cost, dirs))| {
                // What the ranking of the places a few ahead reads, a step further each.
                for (ahead, step) in [(8, 0), (4, 1), (2, 2)] {
                    if j + ahead < places {
                        let f = triangle_at(live, first + j + ahead);
                        if marked[f as usize] != 0 {
                            work.prefetch_ends(f, step);
                        }
                    }
                }
                let f = triangle_at(live, first + j);
                work.rank_triangle(f, marked[f as usize], cost, dirs)
            })
            .sum::<usize>()
    };
    let count = if threads <= 1 || costs.len() < PARALLEL_MIN {
        rank_part(0, costs, dirs)
    } else {
        let per = costs.len().div_ceil(threads);
        costs
            .par_chunks_mut(per)
            .zip(dirs.par_chunks_mut(per))
            .enumerate()
            .map(|(i, (costs, dirs))| rank_part(i * per, costs, dirs))
            .sum()
    };
    changed.fill(0);
    count
}

/// The collapse a ranked slot lists: its cheaper allowed direction, if any.
fn candidate(slot: &Slot) -> Option<Candidate> {
    let [a, b] = slot.ends;
    match slot.dir {
        1 => Some((slot.cost, b, a)),
        2 => Some((slot.cost, a, b)),
        _ => None,
    }
}

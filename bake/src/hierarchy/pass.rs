//! The passes: each ranks the live edges, then applies, cheapest first, the legal
//! collapses whose neighbourhoods no earlier collapse of the pass took, up to its share.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::bounds::Points;
use super::geometry::corner_of;
use super::handover::Handover;
use super::legality::Verdict;
use super::prefetch::prefetch;
use super::rank::{order_key, rank_all, Ranked, Slots};
use super::types::{BuildError, BuildStage, Progress, NONE};
use super::work::Work;

/// Share of a pass's ranked collapses it may apply: the cheapest half. Applying every
/// independent collapse lets an expensive one take a neighbourhood that a cheaper one of
/// the next pass would have used; the cut costs passes, not depth to speak of.
pub(super) const PASS_SHARE: f64 = 0.5;

/// Collapses a pass applies between handing the ones before over to the settling of the
/// error bounds, which runs beside the next ones. While a run settles, the next is taken
/// beside it, so both count in the build's peak memory: short runs keep that to a few
/// hundred kilobytes (about 16 bytes a triangle of each new star), while their joins are
/// still too few to cost anything measurable.
pub(super) const SEGMENT: u64 = 1024;

/// Runs passes until one finds nothing to apply, reporting progress after each.
///
/// The loop ends: a pass that applies nothing ends it unless it stopped at its share, and
/// then the next pass goes through every ranked collapse (a full pass cuts nothing), so
/// that one applying nothing ends it too. Every other pass removes a node, so there are at
/// most `2 × positions` passes. A pass that breaks either invariant (a full pass cut
/// short, more passes than that) is a [`BuildError`] naming it, never a loop.
///
/// A pass hands its collapses over to the settling every `segment` collapses ([`SEGMENT`]
/// but in tests).
pub(super) fn collapse_all(
    work: &mut Work<'_>,
    (threads, segment): (usize, u64),
    stop_at: usize,
    progress: Progress<'_>,
) -> Result<(), BuildError> {
    let mut passes = Passes::new(work.tris.len(), segment);
    let mut points = Points::place(work);
    // The new nodes' errors the settling gives.
    let mut errors = Vec::new();
    // The last collapses of the pass before, settled beside this one's ranking.
    let mut carried = Handover::default();
    let most = work.positions().saturating_sub(1) as u64;
    let max_passes = 2 * (most + 1);
    // Whether this pass may apply every ranked collapse (after one that applied none of
    // its cheapest share).
    let mut full = false;
    loop {
        work.h.passes += 1;
        let pass = work.h.passes;
        let (applied, cut) = passes.run(work, (&mut points, &carried), pass, full, threads)?;
        carried = work.handover();
        work.merge_wedges(threads);
        work.release_removed_wedges();
        work.pass_start = work.h.collapses.len();
        let done = work.h.collapses.len() as u64;
        progress(done, most);
        let broken = |stage, invariant| BuildError {
            stage,
            pass,
            collapses: done,
            most,
            invariant,
        };
        if full && cut {
            return Err(broken(
                BuildStage::FullPass,
                "a pass over every ranked collapse stopped at a share",
            ));
        }
        if applied == 0 && (full || !cut) || stop_at > 0 && live_triangles(work) <= stop_at {
            points.settle(&carried, work.frame(), threads, &mut errors);
            work.record_errors(&mut errors);
            return Ok(());
        }
        if u64::from(pass) >= max_passes || done > most {
            return Err(broken(
                BuildStage::Passes,
                "more passes or collapses than the mesh has nodes to remove",
            ));
        }
        full = applied == 0;
    }
}

/// Triangles left: each collapse removes its `f_l`, and its `f_r` when it has one.
fn live_triangles(work: &Work<'_>) -> usize {
    let removed: usize = work
        .h
        .collapses
        .iter()
        .map(|c| 1 + usize::from(c.fr != NONE))
        .sum();
    work.tris.len() - removed
}

/// What the passes keep from one to the next.
struct Passes {
    /// The live triangles and the ranking of their three edge slots.
    slots: Slots,
    ranked: Ranked,
    /// Other directions of edges whose cheaper one was illegal: `(cost key, slot)`.
    later: BinaryHeap<Reverse<(u64, usize)>>,
    /// The rings of the ends of the collapse being checked.
    rings: [Vec<u32>; 2],
    /// Collapses between handovers to the settling.
    segment: u64,
}

/// Where a pass stands in its collapses.
struct Tries {
    /// The cost key of the dearest collapse of its share.
    limit: u64,
    /// Collapses applied.
    applied: u64,
    /// Collapses tried, and at most.
    tried: u64,
    most: u64,
}

/// The next collapse a pass tries, or why it stops.
enum Next {
    /// Nothing left to try.
    Done,
    /// The next one is dearer than the pass's share.
    Cut,
    /// Moving `u` onto `t`; `from_later` when it is an edge's other direction.
    Try { t: u32, u: u32, from_later: bool },
}

impl Passes {
    fn new(triangles: usize, segment: u64) -> Self {
        Self {
            segment,
            slots: Slots::new(triangles),
            ranked: Ranked::default(),
            later: BinaryHeap::new(),
            rings: [Vec::new(), Vec::new()],
        }
    }

    /// One pass; returns how many collapses it applied and whether it stopped at its share.
    /// Its last collapses are left taken ([`Work::handover`]), their points still to settle.
    ///
    /// The pass applies, in cost order, each edge's cheapest legal direction unless an
    /// earlier collapse of the pass took a neighbourhood its ends are in (stamped), or it
    /// lapsed since the start of the pass. A direction is checked only when reached with
    /// both ends free; when it was illegal at the start of the pass, the edge's other
    /// direction queues at its own cost (in the same order as if it had been ranked with
    /// the others).
    ///
    /// Every `segment` collapses ([`SEGMENT`]), those before are handed over
    /// ([`Work::handover`]) and their points settled beside the next ones, on the other
    /// threads: the settling reads nothing the pass changes, and moves the points after (in
    /// order, as if at the end). The last pass's last ones (`carried`) settle beside the
    /// ranking, and their nodes' errors are recorded before the first collapse, whose new
    /// node's error starts from its children's.
    fn run(
        &mut self,
        work: &mut Work<'_>,
        (points, carried): (&mut Points, &Handover),
        pass: u32,
        full: bool,
        threads: usize,
    ) -> Result<(u64, bool), BuildError> {
        let mut errors = Vec::new();
        // The last pass's last collapses settle beside the ranking, which reads no points.
        let frame = work.frame();
        let ((count, limit), ()) = rayon::join(
            || self.rank(work, full, threads),
            || points.settle(carried, frame, threads, &mut errors),
        );
        work.record_errors(&mut errors);
        let mut tries = Tries {
            limit,
            applied: 0,
            tried: 0,
            most: 2 * count as u64,
        };
        let mut pending = Handover::default();
        loop {
            let frame = work.frame();
            let until = tries.applied.saturating_add(self.segment);
            let (end, ()) = rayon::join(
                || self.apply_until(work, pass, &mut tries, until),
                || points.settle(&pending, frame, threads, &mut errors),
            );
            work.record_errors(&mut errors);
            let Some(cut) = end? else {
                pending = work.handover();
                continue;
            };
            return Ok((tries.applied, cut));
        }
    }

    /// Starts a pass: ranks the live slots and the bucket of its cheapest share (all of
    /// them when `full`); returns how many it ranked and the cost key of the dearest it
    /// may apply.
    fn rank(&mut self, work: &mut Work<'_>, full: bool, threads: usize) -> (usize, u64) {
        work.stamp.clear();
        work.shrunk.clear();
        // Drop the triangles the last pass removed (keeping the order).
        self.slots.retain_alive(&work.alive);
        // Each edge's cheaper allowed direction, by cost; equal costs in slot order (three
        // slots per triangle, in order).
        let count = rank_all(work, &mut self.slots, threads);
        // The pass stops at the first collapse dearer than its cheapest share.
        let share = if full { 1.0 } else { PASS_SHARE };
        let limit = self
            .ranked
            .start(&self.slots, &work.tris, count, share, threads);
        self.later.clear();
        (count, limit)
    }

    /// Applies the pass's collapses until `until` are applied (`None`) or the pass ends
    /// (whether it stopped at its share).
    ///
    /// Each ranked collapse is tried at most once and queues at most one other direction,
    /// so a pass tries at most twice as many collapses as it ranked; trying more is a
    /// [`BuildError`].
    fn apply_until(
        &mut self,
        work: &mut Work<'_>,
        pass: u32,
        tries: &mut Tries,
        until: u64,
    ) -> Result<Option<bool>, BuildError> {
        while tries.applied < until {
            let (t, u, from_later) = match self.next(work, tries.limit) {
                Next::Done => return Ok(Some(false)),
                Next::Cut => return Ok(Some(true)),
                Next::Try { t, u, from_later } => (t, u, from_later),
            };
            // What the next candidates' checks read, a step further for each.
            for (k, step) in [(0, 2), (1, 1), (2, 0)] {
                for v in self.ranked.upcoming(k).into_iter().flatten() {
                    work.prefetch_around(v, step);
                }
            }
            tries.tried += 1;
            if tries.tried > tries.most {
                return Err(BuildError {
                    stage: BuildStage::Pass,
                    pass,
                    collapses: work.h.collapses.len() as u64,
                    most: work.positions().saturating_sub(1) as u64,
                    invariant: "a pass tried more collapses than it ranked and queued",
                });
            }
            if stamped(work, t, u) {
                continue;
            }
            match work.verdict(t, u, &mut self.rings) {
                Verdict::Legal(col) => {
                    let s = work.apply_in_pass(col, &self.rings);
                    self.slots.mark_changed(work, s);
                    tries.applied += 1;
                }
                Verdict::Lapsed => {}
                Verdict::Illegal => {
                    if !from_later {
                        self.queue_other_direction(work, t, u);
                    }
                }
            }
        }
        Ok(None)
    }

    /// The next collapse to try: the cheaper of the next ranked one and the next queued
    /// other direction (on equal costs, the one of the earlier slot), unless it is dearer
    /// than `limit`.
    fn next(&mut self, work: &Work<'_>, limit: u64) -> Next {
        let next_cand = self.ranked.peek(
            &self.slots,
            &work.tris,
            |v| work.stamp.get(work.at_node(v)),
            |v| prefetch(&work.node_pos[v as usize]),
        );
        let later_first = match (next_cand, self.later.peek()) {
            (None, None) => return Next::Done,
            (None, Some(_)) => true,
            (Some(_), None) => false,
            (Some((c, t, u)), Some(&Reverse((key, i)))) => {
                let own = order_key(c);
                key < own
                    || (key == own && !stamped(work, t, u) && i < slot_of(work, &self.slots, t, u))
            }
        };
        let key = if later_first {
            self.later.peek().map(|r| r.0 .0)
        } else {
            next_cand.map(|c| order_key(c.0))
        };
        if key.is_some_and(|k| k > limit) {
            return Next::Cut;
        }
        if later_first {
            let Some(Reverse((_, i))) = self.later.pop() else {
                return Next::Done;
            };
            let slot = self.slots.get(&work.tris, i);
            let [a, b] = slot.ends;
            let (t, u) = if slot.dir == 1 { (a, b) } else { (b, a) };
            Next::Try {
                t,
                u,
                from_later: true,
            }
        } else {
            let Some((_, t, u)) = next_cand else {
                return Next::Done;
            };
            self.ranked.advance();
            Next::Try {
                t,
                u,
                from_later: false,
            }
        }
    }

    /// Queues the other direction of the edge `t`–`u` at its own cost, if allowed.
    fn queue_other_direction(&mut self, work: &Work<'_>, t: u32, u: u32) {
        let i = slot_of(work, &self.slots, t, u);
        let (f, k) = self.slots.slot(i);
        let other = work.other_cost(f, k);
        if other.is_finite() {
            self.later.push(Reverse((order_key(other), i)));
        }
    }
}

/// Whether an earlier collapse of the pass took a neighbourhood `t` or `u` is in.
fn stamped(work: &Work<'_>, t: u32, u: u32) -> bool {
    work.stamp.get(work.at_node(t)) || work.stamp.get(work.at_node(u))
}

/// The number of the slot standing for the edge of free ends `t`, `u`.
fn slot_of(work: &Work<'_>, slots: &Slots, t: u32, u: u32) -> usize {
    let (fl, jl) = work.dir_face(t, u).unwrap_or((0, 0));
    let fr = work.tris[fl as usize].o[jl];
    let (f, k) = if fr == NONE || t < u {
        (fl, jl)
    } else {
        (fr, corner_of(work.tris[fr as usize].c, u))
    };
    slots.number(f, k)
}

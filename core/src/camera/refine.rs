//! Selective refinement of one camera's front (Hoppe's `adapt_refinement`).
//!
//! One pass walks the active node list once. An active node that can be split, is visible
//! (bounding sphere against the frustum, normal cone against the eye) and whose projected
//! error exceeds the tolerance is force-split; an active stationary child whose sibling is
//! active and whose parent no longer needs its split is collapsed when legal. A node changed
//! by an operation is looked at again at once, so one pass settles refinement however deep;
//! coarsening can take a few passes, because a collapse waits while a child is still split
//! (as in Hoppe's). A pass may also be amortised ([`RefineParams::visit_fraction`],
//! [`RefineParams::max_visits`]): it looks at part of the list and the next one resumes where
//! it stopped, so a call's work is bounded by the caller. All other work is proportional to
//! the front, not the hierarchy (temporal coherence).
//!
//! A pass, step by step ([`CameraState::refine`]):
//! 1. **start**: the call's screen-space test from the view and the checked parameters
//!    (`screen`), the parameters the pass runs with (a camera at its base mesh settles in
//!    full passes), the criterion, and the odometers' readings for the certificates;
//! 2. **sweep the morphs**: every morph in progress steps first, so one this pass starts
//!    shows its start this frame (see `morph`);
//! 3. **walk the active list**: per record, does its node want its split (a certificate, or
//!    its bounds against the criterion)? Then try the split (forced, counted); else does its
//!    coarsening parent no longer want its split? Then try the collapse (remembered
//!    refusals, legality, a coarsen morph first);
//! 4. **finish**: report.
//!
//! Whether a node wants its split is the criterion's answer (see `criterion`); this module
//! holds the walk.

use super::certificate::{own_holds, parent_says, Readings};
use super::criterion::Criterion;
use super::ops::OpError;
use super::records::{ActiveVertex, FREE, NONE};
use super::state::{CameraState, Front};
use super::stats::RefineStats;
use crate::hierarchy::{Absent, HierarchyRecords};
use crate::ids::NodeId;
use crate::params::RefineParams;
use crate::prefetch;
use crate::screen::ScreenTest;
use crate::view::View;

/// How many active records ahead a pass asks for the bounds and pair-map entries it will read.
const PREFETCH_AHEAD: usize = 16;

/// One pass's inputs, fixed when it starts, and its running tally.
struct Pass {
    /// The call's screen-space test.
    test: ScreenTest,
    /// The criterion of `test`.
    c: Criterion,
    /// The parameters the pass runs with ([`Front::pass_params`]).
    params: RefineParams,
    /// The odometer readings the records' certificates are compared with.
    reading: Readings,
    /// Most operations the pass applies ([`ops_bound`]).
    max_ops: u32,
    /// Whether the camera has morph memory.
    morphing: bool,
    st: RefineStats,
}

/// What the walk does after a visit.
enum Next {
    /// Go on to the next record.
    Advance,
    /// Look at the same record again: an operation changed the node it holds.
    Again,
}

/// Where the walk over the active list stands. A full pass walks the list from its start;
/// an amortised one looks at `cap` records from where the previous one stopped, wrapping
/// round once at the end.
struct Walk {
    cap: Option<u32>,
    i: usize,
    start: usize,
    wrapped: bool,
    looked: u32,
}

impl Walk {
    fn new(cap: Option<u32>, cursor: u32) -> Self {
        let i = if cap.is_some() { cursor as usize } else { 0 };
        Self {
            cap,
            i,
            start: i,
            wrapped: false,
            looked: 0,
        }
    }

    /// The record to look at next in a list of `len` records, counted as looked at; `None`
    /// once the walk is done.
    #[inline(always)]
    fn next(&mut self, len: usize) -> Option<usize> {
        if self.i >= len {
            if self.cap.is_none() || self.wrapped {
                return None;
            }
            (self.i, self.wrapped) = (0, true);
        }
        if let Some(cap) = self.cap {
            if self.looked >= cap || (self.wrapped && self.i >= self.start) {
                return None;
            }
        }
        self.looked += 1;
        Some(self.i)
    }

    /// Where the next amortised pass starts in a list of `len` records.
    fn cursor(&self, len: usize) -> u32 {
        match self.cap {
            Some(_) if self.i < len => self.i as u32,
            _ => 0,
        }
    }
}

/// A hard bound on a pass's work, whatever the data: no pass applies more operations than
/// four per split record (within `params.max_ops`).
fn ops_bound(h: &impl HierarchyRecords, params: &RefineParams) -> u32 {
    params
        .max_ops
        .min(h.meta().split_count.saturating_mul(4).saturating_add(1024))
}

impl CameraState<'_> {
    /// One refinement pass of this camera against `view` (see the module docs of `refine`
    /// for its steps). Allocates nothing.
    ///
    /// [`OpError::InvalidParams`] for parameters out of range ([`RefineParams::validate`]),
    /// before anything changes.
    pub fn refine(
        &mut self,
        h: &impl HierarchyRecords,
        view: &View,
        params: &RefineParams,
    ) -> Result<RefineStats, OpError> {
        if !self.is_for(h) {
            return Err(OpError::WrongHierarchy);
        }
        let f = &mut self.front;
        let mut pass = f.start_pass(h, view, params)?;
        // Morphs move first, so a morph started by this pass shows its start this frame.
        if f.morphs.scalars.live > 0 {
            f.sweep_morphs(h, &pass.c, &pass.params, &mut pass.st, pass.max_ops)?;
        }
        f.walk(h, self.stack, &mut pass)?;
        Ok(f.finish_pass(pass.st))
    }
}

impl Front<'_> {
    /// The pass's inputs: the screen-space test of `view` and `params` (refused when the
    /// parameters are out of range), the parameters the pass runs with, and the odometers
    /// moved to the view.
    fn start_pass(
        &mut self,
        h: &impl HierarchyRecords,
        view: &View,
        params: &RefineParams,
    ) -> Result<Pass, OpError> {
        let morphing = self.morphs.capacity() > 0;
        let test = ScreenTest::new(view, params, morphing)?;
        let params = self.pass_params(params);
        let live = (self.active_len as usize).min(self.active.len());
        let reading = self.odometer.advance(h, &test, &mut self.active[..live]);
        Ok(Pass {
            c: Criterion::new(&test),
            test,
            max_ops: ops_bound(h, &params),
            params,
            reading,
            morphing,
            st: RefineStats::default(),
        })
    }

    /// The parameters a pass runs with: a camera at its base mesh settles in full passes
    /// (amortisation spreads coherent motion over calls, not a camera's first picture; a
    /// visit cap still holds), and its first pass since it was made or reset does not
    /// morph: nothing was drawn before it to morph from.
    fn pass_params(&self, params: &RefineParams) -> RefineParams {
        if self.refined && self.pairs != 0 {
            return *params;
        }
        let full = RefineParams {
            visit_fraction: 1.0,
            ..*params
        };
        if self.refined {
            full
        } else {
            full.without_morphs()
        }
    }

    /// Visits the active list (all of it, or the pass's share from where the last stopped)
    /// until the walk or the pass's operations run out.
    fn walk(
        &mut self,
        h: &impl HierarchyRecords,
        stack: &mut [NodeId],
        pass: &mut Pass,
    ) -> Result<(), OpError> {
        let mut walk = Walk::new(pass.params.visit_cap(self.active_len), self.visit_cursor);
        while pass.st.operations() < pass.max_ops {
            let Some(i) = walk.next(self.active_len as usize) else {
                break;
            };
            if let Next::Advance = self.visit(h, stack, pass, i)? {
                walk.i += 1;
            }
        }
        self.visit_cursor = walk.cursor(self.active_len as usize);
        Ok(())
    }

    /// One visit of record `i`: split its node if wanted, else collapse its coarsening
    /// parent if that is no longer wanted.
    #[inline(always)]
    fn visit(
        &mut self,
        h: &impl HierarchyRecords,
        stack: &mut [NodeId],
        pass: &mut Pass,
        i: usize,
    ) -> Result<Next, OpError> {
        let a = self.active[i];
        if a.node & FREE != 0 {
            return Ok(Next::Advance);
        }
        pass.st.nodes_visited += 1;
        self.prefetch_ahead(h, i + PREFETCH_AHEAD, pass.reading);
        if self.wants_own_split(h, pass, i, a) {
            return self.try_split(h, stack, pass, NodeId(a.node));
        }
        self.try_coarsen(h, pass, i, a)
    }

    /// Asks for the bounds of record `at`'s node and of its coarsening parent, so they are in
    /// the nearest cache when that record's turn comes: the visits of a pass are
    /// independent, but a miss on the record being decided stalls the branches that depend
    /// on it (see `crate::prefetch`). Certified questions read no bounds, so they ask for
    /// none.
    #[inline(always)]
    fn prefetch_ahead(&self, h: &impl HierarchyRecords, at: usize, reading: Readings) {
        // Past the live entries lie stale ones, whose pages may have gone.
        if at >= self.active_nodes as usize {
            return;
        }
        let Some(ahead) = self.active.get(at) else {
            return;
        };
        let own = if own_holds(ahead.own_cert, reading) {
            NONE
        } else {
            ahead.node
        };
        let says = parent_says(ahead.parent_cert, reading);
        let parent = if says.is_some() { NONE } else { ahead.coarsen };
        // A parent not certainly wanted may mean a refusal to look up.
        if says != Some(true) {
            self.pair_of.prefetch(ahead.coarsen as usize);
        }
        for n in [own, parent] {
            if let Some(b) = h.split_bounds(NodeId(n)) {
                prefetch::bounds(b);
            }
        }
    }

    /// Whether record `i`'s node wants its split. A certificate may say it still does not
    /// (its bounds are then not read); a fresh "no" writes a certificate.
    #[inline(always)]
    fn wants_own_split(
        &mut self,
        h: &impl HierarchyRecords,
        pass: &mut Pass,
        i: usize,
        a: ActiveVertex,
    ) -> bool {
        if own_holds(a.own_cert, pass.reading) {
            pass.st.certified += 1;
            return false;
        }
        let Some(b) = h.split_bounds(NodeId(a.node)) else {
            return false;
        };
        if pass.c.wants_split(b) {
            return true;
        }
        self.active[i].own_cert = self.odometer.unwanted_own(b);
        false
    }

    /// The wanted split of `v`, forced (its neighbours' creators split first) within the
    /// pass's operations; a full camera or forced-split stack is counted, not an error.
    fn try_split(
        &mut self,
        h: &impl HierarchyRecords,
        stack: &mut [NodeId],
        pass: &mut Pass,
        v: NodeId,
    ) -> Result<Next, OpError> {
        if self.pairs as usize >= self.owner.len() {
            pass.st.capacity_refusals += 1;
            return Ok(Next::Advance);
        }
        let mut applied = 0;
        let budget = pass.max_ops - pass.st.operations();
        let result = if pass.morphing {
            let (c, params, st) = (&pass.c, &pass.params, &mut pass.st);
            self.force_split_counted(h, v, stack, budget, &mut applied, |f, x| {
                f.morph_split(h, c, params, x, st)
            })
        } else {
            self.force_split_counted(h, v, stack, budget, &mut applied, |_, _| {})
        };
        let st = &mut pass.st;
        // Every split applied counts, also those forced before an error.
        st.splits += applied;
        match result {
            Ok(()) => {
                let done = self.is_split(v);
                st.forced_splits += applied.saturating_sub(u32::from(done));
                if done {
                    return Ok(Next::Again); // look at the stationary child in this record
                }
            }
            Err(e) => {
                st.forced_splits += applied;
                match e {
                    OpError::Absent { page, node } => {
                        st.deferred_splits += 1;
                        let excess = h.split_bounds(v).map_or(0.0, |b| pass.test.excess_px(b));
                        h.want(Absent { page, node }, excess);
                    }
                    OpError::StackFull { .. } => st.stack_overflows += 1,
                    OpError::CapacityFull { .. } => st.capacity_refusals += 1,
                    e => return Err(e),
                }
            }
        }
        Ok(Next::Advance)
    }

    /// Coarsens at record `i`: its node is a stationary child (it shares its parent's
    /// position, which its record says) whose parent no longer wants its split. A collapse
    /// refused before and not changed since is not checked again (see the `CameraState`
    /// docs); a visible one may wait for a coarsen morph.
    #[inline]
    fn try_coarsen(
        &mut self,
        h: &impl HierarchyRecords,
        pass: &mut Pass,
        i: usize,
        a: ActiveVertex,
    ) -> Result<Next, OpError> {
        if !self.parent_unwanted(h, pass, i, a) {
            return Ok(Next::Advance);
        }
        let parent = NodeId(a.coarsen);
        let pair = self.pair_of.get(parent.index()).unwrap_or(NONE);
        if pass.morphing && self.morphs.is_coarsening(pair) {
            return Ok(Next::Advance); // its coarsen morph runs: the sweep decides its collapse
        }
        if pair == NONE {
            return Ok(Next::Advance);
        }
        if self.refusal_remembered(pair) {
            pass.st.refusals_remembered += 1;
            return Ok(Next::Advance);
        }
        let Some(slots) = self.collapse_slots(h, parent) else {
            pass.st.collapses_refused += 1;
            self.remember_refusal(pair);
            return Ok(Next::Advance);
        };
        if pass.morphing && self.defers_collapse(h, &pass.c, &pass.params, parent, &mut pass.st) {
            return Ok(Next::Advance); // a coarsen morph runs first
        }
        self.apply_collapse(h, parent, slots)?;
        pass.st.collapses += 1;
        Ok(Next::Again) // the record now holds the parent
    }

    /// Whether record `i`'s coarsening parent no longer wants its split: only the parent's
    /// bounds are read unless a certificate answers, and a fresh answer writes one. `false`
    /// for a record without a coarsening parent.
    #[inline(always)]
    fn parent_unwanted(
        &mut self,
        h: &impl HierarchyRecords,
        pass: &mut Pass,
        i: usize,
        a: ActiveVertex,
    ) -> bool {
        if let Some(wanted) = parent_says(a.parent_cert, pass.reading) {
            pass.st.certified += 1;
            return !wanted;
        }
        let Some(pb) = h.split_bounds(NodeId(a.coarsen)) else {
            return false;
        };
        if pass.c.wants_split(pb) {
            let cone = (pass.c.backface && pb.cone_sin2 < 1.0).then(|| pb.cone_normal());
            self.active[i].parent_cert = self.odometer.wanted_parent(pb, cone);
            false
        } else {
            self.active[i].parent_cert = self.odometer.unwanted_parent(pb);
            true
        }
    }

    /// The pass's report; the camera counts as refined from now on.
    fn finish_pass(&mut self, mut st: RefineStats) -> RefineStats {
        st.active_nodes = self.active_nodes;
        st.active_polygons = self.active_polygons;
        st.morphing = self.morphs.scalars.live;
        self.refined = true;
        st
    }
}

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
//! it stopped, so a call's work is bounded by the caller. All other work is proportional to the front, not the hierarchy (temporal
//! coherence).
//!
//! Whether a node wants its split is the criterion's answer (see `criterion`); this module
//! holds the pass's parameters and statistics and the walk itself.

use super::certificate::{own_holds, parent_says};
use super::criterion::Criterion;
use super::{CameraState, OpError, FREE, NONE};
use crate::hierarchy::Hierarchy;
use crate::ids::NodeId;
use crate::prefetch;
use crate::view::View;

/// How many active records ahead a pass asks for the bounds and pair-map entries it will read.
const PREFETCH_AHEAD: usize = 16;

/// Knobs of [`CameraState::refine`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineParams {
    /// Screen-space tolerance in pixels: split while a node's error projects larger.
    pub tolerance_px: f32,
    /// Most splits + collapses in one call (amortisation over frames); `u32::MAX` for none.
    pub max_ops: u32,
    /// Share of the active list one call visits (Hoppe's amortised `adapt_refinement`, whose
    /// demos visit a third per frame). At 1, the default, a call walks the whole list from its
    /// start, so one call settles refinement. Below 1, a call looks at that share of the
    /// list's records (at least one) from where the camera's previous amortised call stopped,
    /// wrapping round at the end; the camera remembers the place in its own state. A camera
    /// visited so converges, while the view holds still, to the front full passes settle at;
    /// a moving view is followed a share per call, so parts of the front lag by up to
    /// `1 / visit_fraction` calls. A camera at its base mesh (new, reset, or coarsened all
    /// the way) visits its whole list whatever this share says (within
    /// [`max_visits`](Self::max_visits)): a new camera settles in one call.
    pub visit_fraction: f32,
    /// Most records of the active list one call looks at (a record looked at again after an
    /// operation counts again, and a call looks at no record twice but so), however large
    /// the share: a work budget per call; any cap makes calls resume where the last stopped. `u32::MAX`,
    /// the default, sets none. A time budget can be built on it by the caller: measure a
    /// call's time per [`RefineStats::nodes_visited`] and set this to the budget over that
    /// cost (the cost per visit is steady for a given hierarchy and machine). Operations are
    /// bounded separately by `max_ops`.
    pub max_visits: u32,
    /// Coarsen outside the view frustum.
    pub frustum_culling: bool,
    /// Coarsen where the normal cone faces away from the eye.
    pub backface_culling: bool,
    /// Seconds of the caller's clock since this camera's previous pass: how far its morphs
    /// move in this one. The default is one frame at 60 Hz, so a caller that does not set it
    /// gets morphs that count frames; pass the frame's real time for morphs that last the
    /// same at any frame rate (and 0 for a repeated pass within one frame).
    pub dt_s: f32,
    /// Seconds a refine morph takes (a split's floating child gliding out of its parent's
    /// position); 0 splits at once. Only a camera with morph memory
    /// ([`CameraConfig::max_morphs`](super::CameraConfig::max_morphs)) morphs, and not in
    /// its first pass since it was made or [reset](CameraState::reset): nothing was drawn
    /// before it to morph from.
    pub refine_morph_s: f32,
    /// Seconds a coarsen morph takes (the floating child gliding back before its collapse);
    /// 0 collapses at once.
    pub coarsen_morph_s: f32,
    /// Fastest a morphing vertex may glide across the screen, in pixels per second of the
    /// caller's clock (the view's pixels): a morph whose path is long on the screen then
    /// takes longer than its duration, so no vertex slides further per frame than this speed
    /// allows, however far its floating child lies from its parent. The path's screen length
    /// is taken at the larger magnification of its ends each pass, so a morph slows as the
    /// eye comes closer. 0, a negative value or infinity (the default) set no limit: the
    /// durations alone, as Hoppe's morphs. A limit trades popping for lag: near the eye,
    /// slow morphs leave the surface coarser for longer, and neighbouring morphs at
    /// different phases can fold triangles over (9 px/s, 0.15 px per frame at 60 Hz, keeps
    /// every vertex under a quarter pixel per frame over St. Helens, with visible folds).
    pub morph_speed_px_s: f32,
    /// How large on the screen a node of a morphing camera may stay, in tolerances: a
    /// visible node also wants its split while its bounding sphere's radius, at the
    /// sphere's distance, projects to more than this many times
    /// [`tolerance_px`](Self::tolerance_px) (its uniform error counts as at least its radius
    /// over this). A split's floating child and its parent both lie within the node's
    /// sphere, so a morph's path on the screen starts at about twice this many tolerances
    /// at most, and each frame of a morph moves a vertex a duration's share of that. Hoppe's
    /// criterion alone leaves large flat nodes near the eye unsplit until their small error
    /// projects to the tolerance, and their floating children then slide hundreds of pixels
    /// in one morph; the bound splits them sooner, at the cost of more polygons: over St.
    /// Helens at 1 px, against a camera with neither bound nor guard band, 32 tolerances
    /// (with a 6-degree band) take the worst camera's 99th-percentile vertex move per frame
    /// from 3.2 to 1.4 px for 1.6–1.9 times the polygons, 16 (with a 12-degree band) to
    /// 0.9 px for 3.6–4.6 times. Applies only to a camera with morph memory and a
    /// refine duration, and scales with the tolerance, so a regulator that moves the
    /// tolerance moves it too. Infinity (the default), 0, a negative value or NaN set no
    /// bound: Hoppe's criterion alone.
    pub morph_radius_tolerances: f32,
    /// How far beyond the view's sides a morphing camera refines, in radians: the frustum's
    /// side planes turn outwards by this angle ([`View::widened`]), so what turns into view
    /// was refined, and its morphs started, before it shows, instead of splitting from a
    /// coarse node at the screen's edge, where a turning view would otherwise see it pop or
    /// glide fast. Applies as [`morph_radius_tolerances`](Self::morph_radius_tolerances)
    /// does; 0 for none. The default, 0.15 (about 9 degrees), refines about a sixth more
    /// polygons and keeps the largest surface move per frame under a pixel on the demo's
    /// flights over St. Helens (the turning ones moved it by up to 3.3 px without it).
    pub morph_guard_rad: f32,
}

/// Hoppe's viewer defaults at 60 frames per second: 32 frames to refine, 16 to coarsen.
const REFINE_MORPH_S: f32 = 32.0 / 60.0;
const COARSEN_MORPH_S: f32 = 16.0 / 60.0;
/// The default screen speed limit of a morphing vertex: none.
const MORPH_SPEED_PX_S: f32 = f32::INFINITY;
/// The default bound on a morphing camera's nodes' screen radius, in tolerances: none.
const MORPH_RADIUS_TOLERANCES: f32 = f32::INFINITY;
/// The default guard band of a morphing camera, in radians.
const MORPH_GUARD_RAD: f32 = 0.15;

impl Default for RefineParams {
    fn default() -> Self {
        Self {
            tolerance_px: 1.0,
            max_ops: u32::MAX,
            visit_fraction: 1.0,
            max_visits: u32::MAX,
            frustum_culling: true,
            backface_culling: true,
            dt_s: 1.0 / 60.0,
            refine_morph_s: REFINE_MORPH_S,
            coarsen_morph_s: COARSEN_MORPH_S,
            morph_speed_px_s: MORPH_SPEED_PX_S,
            morph_radius_tolerances: MORPH_RADIUS_TOLERANCES,
            morph_guard_rad: MORPH_GUARD_RAD,
        }
    }
}

impl RefineParams {
    /// These parameters visiting `fraction` of the active list per call (see
    /// [`visit_fraction`](Self::visit_fraction)).
    pub fn amortised(self, fraction: f32) -> Self {
        Self {
            visit_fraction: fraction,
            ..self
        }
    }

    /// Records of an active list of `len` records one call may look at, or `None` for a full
    /// pass from the list's start (a share of 1 and no visit cap).
    fn visit_cap(&self, len: u32) -> Option<u32> {
        let share = if self.visit_fraction.is_nan() {
            1.0
        } else {
            self.visit_fraction.clamp(0.0, 1.0)
        };
        if share >= 1.0 && self.max_visits == u32::MAX {
            return None;
        }
        let by_share = libm::ceilf(share * len as f32) as u32;
        Some(by_share.min(self.max_visits).max(1))
    }

    /// The factor of a node's bounding radius that counts as uniform error for a camera
    /// that `morphs` (see [`morph_radius_tolerances`](Self::morph_radius_tolerances)): the
    /// reciprocal of that bound, or 0 for none.
    pub(super) fn radius_error(&self, morphs: bool) -> f32 {
        let r = self.morph_radius_tolerances;
        let on = morphs && self.refine_morph_s > 0.0 && r > 0.0 && r.is_finite();
        if on {
            1.0 / r
        } else {
            0.0
        }
    }

    /// The view a camera that `morphs` refines against: `view` widened by
    /// [`morph_guard_rad`](Self::morph_guard_rad) when that applies.
    pub(super) fn refined_view(&self, view: &View, morphs: bool) -> View {
        if morphs && self.refine_morph_s > 0.0 {
            view.widened(self.morph_guard_rad)
        } else {
            *view
        }
    }

    /// These parameters with morphs off: every split and collapse at once (what a camera
    /// without morph memory always does).
    pub fn without_morphs(self) -> Self {
        Self {
            refine_morph_s: 0.0,
            coarsen_morph_s: 0.0,
            ..self
        }
    }
}

/// What one refinement pass did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RefineStats {
    /// Splits applied, forced ones included.
    pub splits: u32,
    /// Splits applied only to make a wanted split legal.
    pub forced_splits: u32,
    /// Collapses applied.
    pub collapses: u32,
    /// Active-node visits.
    pub nodes_visited: u32,
    /// Active nodes after the pass.
    pub active_nodes: u32,
    /// Active polygons after the pass.
    pub active_polygons: u32,
    /// Wanted splits refused because the camera was full.
    pub capacity_refusals: u32,
    /// Wanted splits abandoned because the forced-split stack was full.
    pub stack_overflows: u32,
    /// Wanted collapses checked and found illegal (a neighbour finer than the split left
    /// it, or the floating child split).
    pub collapses_refused: u32,
    /// Wanted collapses not checked again: refused before, and neither of the pair's
    /// polygons nor its children changed since.
    pub refusals_remembered: u32,
    /// Questions a certificate answered without reading bounds: a node's own split still
    /// unwanted, or its coarsening parent's still wanted or still unwanted (see the module
    /// docs of `camera`).
    pub certified: u32,
    /// Morphs begun: refine morphs of splits of visible nodes, coarsen morphs of wanted
    /// collapses of visible parents (also one that turns a refine morph around).
    pub morphs_started: u32,
    /// Morphs ended: refine morphs that reached the fine position, coarsen morphs whose
    /// collapse was applied, and morphs whose pair refinement collapsed at once (its parent
    /// left the view, or coarsen morphs are off).
    pub morphs_finished: u32,
    /// Coarsen morphs turned back towards the fine position: the parent's split was wanted
    /// again, or a split nearby made the collapse illegal.
    pub morphs_aborted: u32,
    /// Splits and collapses that wanted a morph but happened at once: the morph memory was
    /// full (or the vertex cannot morph: a position with more than two surface groups).
    pub morphs_dropped: u32,
    /// Morphs in progress after the pass.
    pub morphing: u32,
}

impl RefineStats {
    /// Splits plus collapses.
    pub fn operations(&self) -> u32 {
        self.splits + self.collapses
    }
}
impl CameraState<'_> {
    /// One refinement pass of this camera against `view`. Allocates nothing.
    pub fn refine(
        &mut self,
        h: &Hierarchy<'_>,
        view: &View,
        params: &RefineParams,
    ) -> Result<RefineStats, OpError> {
        if !self.is_for(h) {
            return Err(OpError::WrongHierarchy);
        }
        let morphing = self.front.morphs.capacity() > 0;
        let view = &params.refined_view(view, morphing);
        let scale = if view.pixels_per_radian > 0.0 {
            params.tolerance_px / view.pixels_per_radian
        } else {
            f32::INFINITY
        };
        let tz2 = scale * scale;
        let radius_error = params.radius_error(morphing);
        // A camera at its base mesh settles in full passes (amortisation spreads coherent
        // motion over calls, not a camera's first picture; a visit cap still holds), and its
        // first pass since it was made or reset does not morph: nothing was drawn before it
        // to morph from.
        let settling;
        let params = if !self.front.refined || self.front.pairs == 0 {
            let full = RefineParams {
                visit_fraction: 1.0,
                ..*params
            };
            settling = if self.front.refined {
                full
            } else {
                full.without_morphs()
            };
            &settling
        } else {
            params
        };
        let c = Criterion::new(view, tz2, radius_error, params);
        // A hard bound on work, whatever the data: no pass applies more operations than four
        // per split record.
        let max_ops = params.max_ops.min(
            (h.splits().len() as u32)
                .saturating_mul(4)
                .saturating_add(1024),
        );
        let mut st = RefineStats::default();
        let f = &mut self.front;
        let live = (f.active_len as usize).min(f.active.len());
        let reading = f.odometer.advance(
            h,
            view,
            tz2,
            radius_error,
            params.frustum_culling,
            params.backface_culling,
            &mut f.active[..live],
        );
        // Morphs move first, so a morph started by this pass shows its start this frame.
        if f.morphs.scalars.live > 0 {
            f.sweep_morphs(h, &c, params, &mut st, max_ops)?;
        }
        // A full pass walks the list from its start; an amortised one looks at `cap` records
        // from where the previous one stopped, wrapping round once at the end.
        let cap = params.visit_cap(f.active_len);
        let mut i = if cap.is_some() {
            f.visit_cursor as usize
        } else {
            0
        };
        let start = i;
        let mut wrapped = false;
        let mut looked = 0u32;
        loop {
            if st.operations() >= max_ops {
                break;
            }
            if i >= f.active_len as usize {
                if cap.is_none() || wrapped {
                    break;
                }
                (i, wrapped) = (0, true);
            }
            if let Some(cap) = cap {
                if looked >= cap || (wrapped && i >= start) {
                    break;
                }
            }
            looked += 1;
            let a = f.active[i];
            if a.node & FREE != 0 {
                i += 1;
                continue;
            }
            let v = NodeId(a.node);
            st.nodes_visited += 1;
            // Ask for the bounds of the node and of its coarsening parent a few records
            // ahead, so they are in the nearest cache when that record's turn comes: the
            // visits of a pass are independent, but a miss on the record being decided stalls
            // the branches that depend on it (see `crate::prefetch`).
            if let Some(ahead) = f.active.get(i + PREFETCH_AHEAD) {
                let own = if own_holds(ahead.own_cert, reading) {
                    NONE
                } else {
                    ahead.node
                };
                let says = parent_says(ahead.parent_cert, reading);
                let parent = if says.is_some() { NONE } else { ahead.coarsen };
                // A parent not certainly wanted may mean a refusal to look up.
                if says != Some(true) {
                    f.pair_of.prefetch(ahead.coarsen as usize);
                }
                for n in [own, parent] {
                    if let Some(b) = h.split_bounds(NodeId(n)) {
                        prefetch::bounds(b);
                    }
                }
            }
            // A certificate may say the node's split is still unwanted: then skip its bounds.
            let bounds = if own_holds(a.own_cert, reading) {
                st.certified += 1;
                None
            } else {
                h.split_bounds(v)
            };
            if let Some(b) = bounds {
                if !c.wants_split(b) {
                    f.active[i].own_cert = f.odometer.unwanted_own(b);
                } else {
                    if f.pairs as usize >= f.owner.len() {
                        st.capacity_refusals += 1;
                        i += 1;
                        continue;
                    }
                    let mut applied = 0;
                    let budget = max_ops - st.operations();
                    let result = if morphing {
                        f.force_split_counted(h, v, self.stack, budget, &mut applied, |f, x| {
                            f.morph_split(h, &c, params, x, &mut st)
                        })
                    } else {
                        f.force_split_counted(h, v, self.stack, budget, &mut applied, |_, _| {})
                    };
                    // Every split applied counts, also those forced before an error.
                    st.splits += applied;
                    match result {
                        Ok(()) => {
                            st.forced_splits += applied.saturating_sub(u32::from(f.is_split(v)));
                            if f.is_split(v) {
                                continue; // look at the stationary child in this record again
                            }
                        }
                        Err(e) => {
                            st.forced_splits += applied;
                            match e {
                                OpError::StackFull { .. } => st.stack_overflows += 1,
                                OpError::CapacityFull { .. } => st.capacity_refusals += 1,
                                e => return Err(e),
                            }
                        }
                    }
                    i += 1;
                    continue;
                }
            }
            // Coarsen: v is a stationary child (it shares its parent's position, which its
            // record says) whose parent no longer wants its split. Only the parent's bounds
            // are read unless a certificate answers; a collapse refused before and not
            // changed since is not checked again (see the `CameraState` docs).
            let parent = NodeId(a.coarsen);
            let unwanted = match parent_says(a.parent_cert, reading) {
                Some(wanted) => {
                    st.certified += 1;
                    !wanted
                }
                None => match h.split_bounds(parent) {
                    Some(pb) if c.wants_split(pb) => {
                        let cone = (c.backface && pb.cone_sin2 < 1.0).then(|| pb.cone_normal());
                        f.active[i].parent_cert = f.odometer.wanted_parent(pb, cone);
                        false
                    }
                    Some(pb) => {
                        f.active[i].parent_cert = f.odometer.unwanted_parent(pb);
                        true
                    }
                    None => false,
                },
            };
            if unwanted {
                let pair = f.pair_of.get(parent.index()).unwrap_or(NONE);
                if morphing && f.morphs.is_coarsening(pair) {
                    // Its coarsen morph runs: the sweep decides its collapse.
                    i += 1;
                    continue;
                }
                if pair != NONE && f.refusal_remembered(pair) {
                    st.refusals_remembered += 1;
                } else if pair != NONE {
                    if let Some(slots) = f.collapse_slots(h, parent) {
                        if morphing && f.defers_collapse(h, &c, params, parent, &mut st) {
                            i += 1;
                            continue; // a coarsen morph runs first
                        }
                        f.apply_collapse(h, parent, slots)?;
                        st.collapses += 1;
                        continue; // the record now holds the parent: look again
                    }
                    st.collapses_refused += 1;
                    f.remember_refusal(pair);
                }
            }
            i += 1;
        }
        f.visit_cursor = match cap {
            Some(_) if i < f.active_len as usize => i as u32,
            _ => 0,
        };
        // Slots change only where a morph started, ended or a collapse ended one.
        let changed = st.morphs_started + st.morphs_finished + st.collapses > 0;
        if changed && f.morphs.scalars.live > 0 {
            f.link_morph_chains(h);
        }
        st.active_nodes = f.active_nodes;
        st.active_polygons = f.active_polygons;
        st.morphing = f.morphs.scalars.live;
        f.refined = true;
        Ok(st)
    }
}

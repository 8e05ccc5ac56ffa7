//! What a refinement pass did ([`RefineStats`]).

/// What one refinement pass did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RefineStats {
    /// Splits applied, forced ones included.
    pub splits: u32,
    /// Wanted splits deferred because they (or a split they force) need a page that is not
    /// resident; the page is wanted from the hierarchy (a streamed one).
    pub deferred_splits: u32,
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

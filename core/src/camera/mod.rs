//! Per-camera refinement state in caller-owned memory: [`CameraState`] and its operations;
//! the layout and the design decisions are in its docs.

mod certificate;
mod compact;
mod compact_step;
mod criterion;
mod emit;
mod index_cache;
mod lag;
mod layout;
mod morph;
mod morph_map;
mod morph_pool;
mod ops;
mod pair_map;
mod refine;

pub use compact_step::CompactProgress;
pub use emit::EmitError;
pub use lag::FrontLag;
pub use morph::MorphVertex;
pub use ops::OpError;
pub use refine::{RefineParams, RefineStats};

use bytemuck::{Pod, Zeroable};

use crate::hierarchy::Hierarchy;
use crate::ids::{NodeId, PolyId, PolyKey};
use certificate::{Odometer, UNKNOWN};
pub(crate) use layout::{Layout, Scalars};
use morph_pool::Morphs;
use pair_map::PairMap;

/// Absent link / empty entry.
pub(crate) const NONE: u32 = u32::MAX;
/// Tag of a free active-vertex record; the low bits chain the free list.
pub(crate) const FREE: u32 = 1 << 31;

/// The current state of one active polygon.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub(crate) struct PolySlot {
    /// Active-vertex records of the three corners.
    pub corners: [u32; 3],
    /// Slots of the neighbours; `neighbours[j]` lies across the edge opposite corner `j`.
    pub neighbours: [u32; 3],
}

const SLOT_WORDS: usize = core::mem::size_of::<PolySlot>() / 4;

/// An active-vertex record: the active node it holds and that node's coarsening parent.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub(crate) struct ActiveVertex {
    /// The node (a [`NodeId`]), or [`FREE`] with the free-list link in the low bits.
    pub node: u32,
    /// The node's parent if the node is the parent's stationary child (the collapse this
    /// node's visits may trigger), else `NONE`.
    pub coarsen: u32,
    /// Own certificate: while the camera's path odometer reads less (positive) or its sweep
    /// reads less than the magnitude (negative), the node's own split is certainly not
    /// wanted, and a visit need not read its bounds (see `certificate`); 0 when unknown.
    pub own_cert: f32,
    /// Parent certificate: while the camera's sweep reads less than the magnitude, the
    /// coarsening parent's split is certainly still wanted (positive: no collapse) or
    /// certainly not wanted (negative: collapse if legal); 0 when unknown.
    pub parent_cert: f32,
}

const ACTIVE_WORDS: usize = core::mem::size_of::<ActiveVertex>() / 4;

/// A slot's entry in the index cache: its polygon's vertex indices (`NONE` where a corner
/// has no vertex in the polygon's surface group), surface and surface group (`surface` is
/// [`NO_POLYGON`] for a slot without a polygon: the right side of a split on a border).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub(crate) struct SlotTriangle {
    pub indices: [u32; 3],
    pub surface: u16,
    pub group: u16,
}

/// The surface of a slot without a polygon (validation keeps surface ids below it).
pub(crate) const NO_POLYGON: u16 = u16::MAX;

const TRIANGLE_WORDS: usize = core::mem::size_of::<SlotTriangle>() / 4;

impl ActiveVertex {
    /// The record of `node`, with its coarsening parent read from the node records: its
    /// parent if that has a split and the two share a position.
    #[inline]
    pub fn of(h: &Hierarchy<'_>, node: NodeId) -> Self {
        let coarsen = h
            .node(node)
            .and_then(|n| {
                let p = h.node(n.parent)?;
                (p.position == n.position && h.split_bounds(n.parent).is_some())
                    .then_some(n.parent.0)
            })
            .unwrap_or(NONE);
        Self {
            node: node.0,
            coarsen,
            own_cert: UNKNOWN,
            parent_cert: UNKNOWN,
        }
    }
}

/// How much a camera can hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CameraConfig {
    /// Most splits that may be applied at once. Each adds one active node and one or two
    /// active polygons; the full hierarchy needs `split_count`.
    pub max_pairs: u32,
    /// Entries of the forced-split stack.
    pub stack_len: u32,
    /// Keep each active polygon's vertex indices between frames, so emission copies them
    /// instead of looking every polygon up in the hierarchy (16 bytes per polygon slot; see
    /// the [`CameraState`] docs). On in [`full`](Self::full) and
    /// [`with_polygon_budget`](Self::with_polygon_budget).
    pub index_cache: bool,
    /// Keep only the split nodes in the map from split to pair, hashed, where that is smaller
    /// than an array over every splittable node (a budget of fewer than about a sixth of the
    /// hierarchy's splits; see `pair_map`). Off in [`full`](Self::full) and
    /// [`with_polygon_budget`](Self::with_polygon_budget): it saves memory on a budgeted camera
    /// but makes refinement slower, because the array keeps the entries of nearby nodes
    /// together and the table scatters them.
    pub hashed_pair_map: bool,
    /// Most geomorphs at once ([`with_morphs`](Self::with_morphs); see the [`CameraState`]
    /// docs): each moves a split's floating child, one or two vertices, between its parent's
    /// position and its own over [`RefineParams::refine_morph_s`] or
    /// [`coarsen_morph_s`](RefineParams::coarsen_morph_s). 72 bytes per morph, and a bit per
    /// vertex of the hierarchy and per pair; 0 in
    /// [`full`](Self::full) and [`with_polygon_budget`](Self::with_polygon_budget), and a
    /// camera without morphs splits and collapses at once.
    pub max_morphs: u32,
}

impl CameraConfig {
    /// Room for every split of `h`: the camera can reach full resolution anywhere.
    pub fn full(h: &Hierarchy<'_>) -> Self {
        Self {
            max_pairs: h.splits().len() as u32,
            stack_len: Self::default_stack(h),
            index_cache: true,
            hashed_pair_map: false,
            max_morphs: 0,
        }
    }

    /// Room for at most `max_active_polygons` active polygons (at least the base mesh).
    pub fn with_polygon_budget(h: &Hierarchy<'_>, max_active_polygons: u32) -> Self {
        // Each split adds at most two polygons.
        let extra = max_active_polygons.saturating_sub(h.base_polygon_count() as u32) / 2;
        Self {
            max_pairs: extra.min(h.splits().len() as u32),
            stack_len: Self::default_stack(h),
            index_cache: true,
            hashed_pair_map: false,
            max_morphs: 0,
        }
    }

    /// This configuration with room for `max_morphs` geomorphs at once: enough for the
    /// splits and collapses of visible nodes the camera makes within one morph's duration.
    /// When the room is taken, a split happens at once ([`RefineStats::morphs_dropped`]).
    pub fn with_morphs(self, max_morphs: u32) -> Self {
        Self { max_morphs, ..self }
    }

    /// A forced split pushes at most a few nodes per level; 32 per level of depth (and at
    /// least 256) has never been exceeded in our tests. Overflow is reported, not fatal.
    pub fn default_stack(h: &Hierarchy<'_>) -> u32 {
        (h.meta().max_depth + 1).saturating_mul(32).max(256)
    }
}

/// Why a camera could not be created.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraError {
    /// The memory given is too small.
    Capacity {
        /// Words needed.
        needed: usize,
        /// Words given.
        given: usize,
    },
    /// The configuration asks for more splits than the hierarchy has.
    TooManyPairs {
        /// Asked for.
        max_pairs: u32,
        /// Splits in the hierarchy.
        split_count: u32,
    },
    /// The configuration asks for more morphs than indices can name: morphed emission
    /// writes `vertex_count + slot`, two slots per morph, which must stay below `u32::MAX`.
    TooManyMorphs {
        /// Asked for.
        max_morphs: u32,
        /// Vertices of the hierarchy.
        vertex_count: u32,
    },
}

impl core::fmt::Display for CameraError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Capacity { needed, given } => {
                write!(
                    f,
                    "camera memory too small: {needed} words needed, {given} given"
                )
            }
            Self::TooManyPairs {
                max_pairs,
                split_count,
            } => {
                write!(
                    f,
                    "max_pairs {max_pairs} exceeds the hierarchy's {split_count} splits"
                )
            }
            Self::TooManyMorphs {
                max_morphs,
                vertex_count,
            } => write!(
                f,
                "max_morphs {max_morphs}: two slots per morph after {vertex_count} vertices \
                 exceed 32-bit indices"
            ),
        }
    }
}

impl core::error::Error for CameraError {}

/// The active front of one camera over a shared hierarchy, in caller-owned memory.
///
/// One [`CameraState`] is the paper's "camera refinement" structure: the active front of one
/// camera over a shared [`Hierarchy`]. It lives in a `&mut [u32]` the caller provides (sized
/// by [`CameraState::words_needed`]), so a console-style runtime can place cameras in fixed
/// pools, and it never allocates.
///
/// # Layout (words)
///
/// | array | length | what |
/// |---|---|---|
/// | `pair_of` | splittable nodes (halved with 16-bit entries, when `max_pairs` < 65,535), or 1.5 × (2 × `max_pairs` + 1) hashed where [`CameraConfig::hashed_pair_map`] asks and that is smaller (see `pair_map`) | the face pair a split node's split created, or `NONE` |
/// | `owner` | `max_pairs` | the node whose split created each live pair |
/// | `active` | 4 × (roots + `max_pairs`) | the active node list: active-vertex records (node, coarsening parent, two certificates) with a free list |
/// | `slots` | 6 × (base polygons + 2 × `max_pairs`) | per active polygon its three corners and three neighbours |
/// | `surface_polygons` | surfaces | active polygons per surface (sizes the index lists) |
/// | `refused` | `max_pairs` / 32 | a bit per live pair: its collapse was refused and nothing it depends on changed since |
/// | `triangles` | 4 × slots (0 without the index cache) | per slot its polygon's three vertex indices, surface and surface group |
/// | `stack` | `stack_len` | the explicit stack of forced splits |
/// | `morph_vertices` | 8 × `max_morphs` | per morph two [`MorphVertex`] slots: persistent `from`, `to`, and `t`, what the GPU blends |
/// | `morph_states` | 2 × `max_morphs` | per morph the split whose floating child morphs, and its direction |
/// | `morph_map` | 2 × (4 × `max_morphs` + 1) + vertices / 32, 0 without morphs | a bit per vertex (it morphs), and the morph slot by morphing vertex, hashed, for morphed emission |
/// | `coarsening` | `max_pairs` / 32, 0 without morphs | a bit per pair: its floating child coarsen-morphs |
/// | `morph_free` | `max_morphs` / 32 | a bit per free morph (a new one takes the lowest) |
///
/// Design decisions:
/// - **Activity is one map from split node to pair.** Following Hoppe, a node is active iff
///   it has been created (its parent is split) and not split; a polygon is active iff its
///   creator is split. `pair_of` answers both in O(1) and doubles as the map from a split to
///   the slots of the two polygons it created, so there is no per-polygon or per-leaf array at
///   all. The map is an array by node, which keeps nearby nodes' entries together; a
///   runtime short of memory may keep only the split nodes, hashed.
/// - **Polygons live in slot pairs**, base polygons first, then two slots per live split,
///   kept dense (a collapse moves the last pair into the hole and patches the at most six
///   neighbour links that point at it), so emission is one linear scan.
/// - **Corners point at active-vertex records**, not at nodes, as in Hoppe's `SrAVertex`:
///   a split hands the record of `vs` to its stationary child, so only the polygons that move
///   to the floating child are touched. Records freed by collapses are reused through a free
///   list; the record array is the active node list that refinement walks.
/// - **A record carries its node's coarsening parent**: the parent when the node is the
///   parent's stationary child (it shares the parent's position), `NONE` otherwise. It is
///   set when the record is written (by a split, a collapse or a reset, which read the node
///   records anyway), so a refinement pass decides whether a node may trigger a collapse
///   from its own record, without reading the node records of the node and its parent on
///   every visit: those reads were a fifth of a pass's cache misses, and four cameras' worth
///   of them no longer fit the caches one camera's fit.
/// - **A refused collapse is remembered until something it depends on changes.** Most
///   collapses that refinement wants are illegal (a neighbour is still finer than the split
///   left it, or the floating child is split), and asking again costs a chain of dependent
///   reads across the hierarchy and the camera (split record, `pair_of`, both slots, the
///   neighbours' entries in `pair_of`): on the St. Helens flyover, about ten refused checks
///   per collapse applied, every frame. Legality depends only on the pair's two slots (their
///   links and corners) and on the children being unsplit, so one bit per pair, set on a
///   refusal, is cleared by every write to either slot and by the collapse of either child;
///   a set bit answers "refused" from 4 bytes per 32 pairs. Compaction and reset clear every
///   bit.
/// - **Settled answers are certified, not asked again.** A visit asks whether the node's
///   split is wanted and, for a stationary child, whether its parent's still is; the answer
///   rarely changes, yet each question reads a bounds record from wherever the hierarchy
///   keeps it. The record keeps, per question, the answer and the odometer reading up to
///   which it provably stands (the eye's path length, or that plus the frustum planes'
///   sweep), and a visit before then reads nothing but its record (see `certificate`): on
///   the St. Helens flyover about five questions in six of a moving pass are answered so,
///   and all but a handful of a settled pass. 8 bytes per record.
/// - **Emission copies; operations keep the copy exact.** A polygon's vertex indices change
///   only when a corner moves to another active-vertex record: a record keeps its position
///   for life (a split hands it to the stationary child, which shares the position). So the
///   index cache keeps each slot's three indices with its surface and group, and an
///   operation rewrites just the corners it moves (one vertex-table row for all of them:
///   every moved corner lands on the same position) and the pair it creates; a
///   pair filling a hole brings its entries. Emission then copies the cache in slot order.
///   Without it, every frame followed five dependent reads per polygon across the hierarchy,
///   which four cameras' emissions pushed out of each other's caches. 16 bytes per slot;
///   [`CameraConfig::index_cache`] turns it off for a runtime short of memory.
/// - **Capacity is a choice.** `max_pairs` bounds the live splits; a full camera refuses
///   further splits (counted in [`RefineStats`]) rather than failing, so a runtime with fixed
///   memory gets a hard polygon budget for free.
/// - **Geomorphs are data for the GPU, kept beside the front.** A split of a visible node
///   starts its floating child at the parent's vertex, and a wanted collapse of a visible
///   parent glides the child back first (Hoppe's refine and coarsen morphs; see `morph`).
///   The persistent vertex buffer is never written: the camera keeps per morphing vertex its
///   two persistent indices and `t` ([`morph_vertices`](Self::morph_vertices)), the GPU
///   blends them into a per-camera buffer, and morphed emission points a morphing corner
///   at `vertex_count + slot`. The front itself changes exactly when it would without morphs,
///   save that a collapse waits for its morph; a camera without morph memory never looks at
///   morphs at all. 72 bytes per morph, a bit per vertex that tells morphed emission which
///   corners morph without a probe of the map for the others, and a bit per pair that tells
///   refinement which collapses wait for their coarsen morph. A coarsening pair's
///   remembered-refusal bit remembers the opposite answer, "legal, nothing changed since",
///   so stepping a coarsen morph rarely asks the preconditions again.
#[derive(Debug)]
pub struct CameraState<'m> {
    pub(crate) front: Front<'m>,
    pub(crate) stack: &'m mut [NodeId],
}

/// Everything but the stack, so operations can borrow the stack separately.
#[derive(Debug)]
pub(crate) struct Front<'m> {
    pub hierarchy: u64,
    pub base: u32,
    pub pair_of: PairMap<'m>,
    pub owner: &'m mut [NodeId],
    pub active: &'m mut [ActiveVertex],
    pub slots: &'m mut [PolySlot],
    pub surface_polygons: &'m mut [u32],
    /// A bit per pair: its collapse was refused and neither slot nor child changed since.
    pub refused: &'m mut [u32],
    /// The index cache: per slot its triangle (empty when the camera keeps none).
    pub triangles: &'m mut [SlotTriangle],
    pub pairs: u32,
    /// High-water mark of `active`.
    pub active_len: u32,
    /// Head of the free list of `active` (`NONE` when empty).
    pub free_head: u32,
    pub active_nodes: u32,
    pub active_polygons: u32,
    /// Operations since the last [`compact`](CameraState::compact).
    pub churn: u32,
    /// The eye's path length, for the records' certificates.
    pub odometer: Odometer,
    /// The geomorphs in progress (empty arrays without morph memory).
    pub morphs: Morphs<'m>,
    /// Where the next amortised refinement pass starts in `active`.
    pub visit_cursor: u32,
    /// Whether a pass ran since the camera was made or reset: the first one has no picture
    /// to morph from.
    pub refined: bool,
    /// How far an incremental compaction has come (see `compact_step`).
    pub compaction: compact_step::Progress,
}

impl<'m> CameraState<'m> {
    /// Words of memory a camera needs for full resolution anywhere ([`CameraConfig::full`]).
    pub fn words_needed(h: &Hierarchy<'_>) -> usize {
        Layout::of(h, &CameraConfig::full(h)).words()
    }

    /// Words of memory a camera with `config` needs.
    pub fn words_needed_for(h: &Hierarchy<'_>, config: &CameraConfig) -> usize {
        Layout::of(h, config).words()
    }

    /// A camera at the base mesh, able to reach full resolution, in `memory`
    /// (at least [`words_needed`](Self::words_needed) words; extra words are left unused).
    pub fn new(h: &Hierarchy<'_>, memory: &'m mut [u32]) -> Result<Self, CameraError> {
        Self::with_config(h, memory, &CameraConfig::full(h))
    }

    /// A camera at the base mesh with the given capacity.
    pub fn with_config(
        h: &Hierarchy<'_>,
        memory: &'m mut [u32],
        config: &CameraConfig,
    ) -> Result<Self, CameraError> {
        let layout = Self::checked_layout(h, config)?;
        let needed = layout.words();
        if memory.len() < needed {
            return Err(CameraError::Capacity {
                needed,
                given: memory.len(),
            });
        }
        let mut cam = Self::carve(memory, &layout, Scalars::initial(h));
        cam.reset(h);
        Ok(cam)
    }

    /// The layout of a camera with `config` over `h`, if the hierarchy has the splits.
    pub(crate) fn checked_layout(
        h: &Hierarchy<'_>,
        config: &CameraConfig,
    ) -> Result<Layout, CameraError> {
        let ns = h.splits().len();
        if config.max_pairs as usize > ns {
            return Err(CameraError::TooManyPairs {
                max_pairs: config.max_pairs,
                split_count: ns as u32,
            });
        }
        let slots = 2 * u64::from(config.max_morphs);
        if h.vertices().len() as u64 + slots >= u64::from(NONE) {
            return Err(CameraError::TooManyMorphs {
                max_morphs: config.max_morphs,
                vertex_count: h.vertices().len() as u32,
            });
        }
        Ok(Layout::of(h, config))
    }

    /// Back to the base mesh.
    pub fn reset(&mut self, h: &Hierarchy<'_>) {
        let f = &mut self.front;
        f.pair_of.clear();
        f.pairs = 0;
        f.free_head = NONE;
        f.surface_polygons.fill(0);
        f.refused.fill(0);
        // Active-vertex record `i` of the base mesh is root `i`.
        for (i, r) in h.roots().iter().enumerate() {
            f.active[i] = ActiveVertex {
                node: r.0,
                coarsen: NONE,
                own_cert: UNKNOWN,
                parent_cert: UNKNOWN,
            };
        }
        f.active_len = h.roots().len() as u32;
        f.active_nodes = f.active_len;
        for (i, b) in h.base().iter().enumerate() {
            let mut corners = [NONE; 3];
            for (k, c) in b.corners.iter().enumerate() {
                // Validated at load: every corner is a root; roots are sorted.
                corners[k] = h.roots().binary_search(c).map_or(NONE, |x| x as u32);
            }
            f.slots[i] = PolySlot {
                corners,
                neighbours: b.neighbours.map(|n| n.0),
            };
            let s = h.polygons()[i].surface.index();
            f.surface_polygons[s] += 1;
        }
        f.active_polygons = f.base;
        f.churn = 0;
        f.visit_cursor = 0;
        f.refined = false;
        f.compaction = compact_step::Progress::IDLE;
        f.morphs.clear();
        f.cache_slots(h, 0, f.base as usize);
    }

    /// `true` if this camera was made for `h`.
    pub fn is_for(&self, h: &Hierarchy<'_>) -> bool {
        self.front.hierarchy == h.checksum()
    }

    /// Number of active nodes.
    pub fn active_node_count(&self) -> u32 {
        self.front.active_nodes
    }

    /// Number of active polygons.
    pub fn active_polygon_count(&self) -> u32 {
        self.front.active_polygons
    }

    /// Number of splits currently applied.
    pub fn split_count(&self) -> u32 {
        self.front.pairs
    }

    /// Most splits this camera can hold at once.
    pub fn max_pairs(&self) -> u32 {
        self.front.owner.len() as u32
    }

    /// Active polygons per surface: index list `s` needs `3 * surface_polygons()[s]` indices.
    pub fn surface_polygons(&self) -> &[u32] {
        self.front.surface_polygons
    }

    /// Bytes this camera occupies: its words plus the struct itself.
    pub fn bytes(&self) -> usize {
        let f = &self.front;
        f.pair_of.bytes()
            + 4 * (f.owner.len() + f.surface_polygons.len() + f.refused.len() + self.stack.len())
            + core::mem::size_of_val(&*f.active)
            + core::mem::size_of_val(&*f.slots)
            + core::mem::size_of_val(&*f.triangles)
            + core::mem::size_of_val(&*f.morphs.vertices)
            + core::mem::size_of_val(&*f.morphs.states)
            + f.morphs.map.bytes()
            + core::mem::size_of_val(&*f.morphs.coarsening)
            + core::mem::size_of_val(&*f.morphs.free)
            + core::mem::size_of::<Self>()
    }

    /// Bytes of this camera's morph memory (part of [`bytes`](Self::bytes)): 0 without
    /// morphs ([`CameraConfig::max_morphs`]).
    pub fn morph_bytes(&self) -> usize {
        let m = &self.front.morphs;
        core::mem::size_of_val(&*m.vertices)
            + core::mem::size_of_val(&*m.states)
            + m.map.bytes()
            + core::mem::size_of_val(&*m.coarsening)
            + core::mem::size_of_val(&*m.free)
    }

    /// `true` if `node` is on this camera's active front (O(1)).
    pub fn is_node_active(&self, h: &Hierarchy<'_>, node: NodeId) -> bool {
        self.front.is_node_active(h, node)
    }

    /// `true` if `node`'s split is applied in this camera (O(1)).
    pub fn is_split(&self, node: NodeId) -> bool {
        self.front.is_split(node)
    }

    /// `true` if `poly` is active in this camera (O(1)).
    pub fn is_polygon_active(&self, h: &Hierarchy<'_>, poly: PolyId) -> bool {
        self.front.slot_of(h, poly).is_some()
    }

    /// The active nodes, in active-list order.
    pub fn active_nodes(&self) -> impl Iterator<Item = NodeId> + '_ {
        self.front.active[..self.front.active_len as usize]
            .iter()
            .filter(|a| a.node & FREE == 0)
            .map(|a| NodeId(a.node))
    }

    /// The active polygons, in slot (emission) order.
    pub fn active_polygons<'s>(
        &'s self,
        h: &'s Hierarchy<'_>,
    ) -> impl Iterator<Item = PolyId> + 's {
        let f = &self.front;
        (0..f.base + 2 * f.pairs).filter_map(move |s| f.poly_at(h, s))
    }

    /// The current corners of an active polygon, in the polygon's order; `None` if inactive.
    pub fn polygon_corners(&self, h: &Hierarchy<'_>, poly: PolyId) -> Option<[NodeId; 3]> {
        let f = &self.front;
        let s = f.slots.get(f.slot_of(h, poly)? as usize)?;
        let mut out = [NodeId::NONE; 3];
        for k in 0..3 {
            out[k] = f.node_of(s.corners[k])?;
        }
        Some(out)
    }

    /// The current neighbours of an active polygon (`neighbours[j]` across the edge opposite
    /// corner `j`, `NONE` on a border); `None` if inactive.
    pub fn polygon_neighbours(&self, h: &Hierarchy<'_>, poly: PolyId) -> Option<[PolyId; 3]> {
        let f = &self.front;
        let s = f.slots.get(f.slot_of(h, poly)? as usize)?;
        let mut out = [PolyId::NONE; 3];
        for k in 0..3 {
            if s.neighbours[k] != NONE {
                out[k] = f.poly_at(h, s.neighbours[k])?;
            }
        }
        Some(out)
    }
}

impl Front<'_> {
    #[inline]
    pub fn is_split(&self, node: NodeId) -> bool {
        self.pair_of.get(node.index()).is_some_and(|p| p != NONE)
    }

    #[inline]
    pub fn is_created(&self, h: &Hierarchy<'_>, node: NodeId) -> bool {
        match h.node(node) {
            Some(n) => n.parent.is_none() || self.is_split(n.parent),
            None => false,
        }
    }

    #[inline]
    pub fn is_node_active(&self, h: &Hierarchy<'_>, node: NodeId) -> bool {
        self.is_created(h, node) && !self.is_split(node)
    }

    /// The slot of an active polygon: base polygons sit in the first slots, others in their
    /// creator's pair (two reads: the polygon's creator and the camera's `pair_of`).
    #[inline]
    pub fn slot_of(&self, h: &Hierarchy<'_>, poly: PolyId) -> Option<u32> {
        self.slot_of_key(h.key_of(poly)?)
    }

    /// The slot of an active polygon named by its [`PolyKey`]: a base polygon's key is its
    /// slot; any other's says its creator and side, so one read of the camera's `pair_of`
    /// answers.
    #[inline]
    pub fn slot_of_key(&self, key: PolyKey) -> Option<u32> {
        let Some((node, right)) = key.creator(self.base) else {
            // A base polygon's key is its slot (`NONE` is no base polygon's).
            return (key.0 < self.base).then_some(key.0);
        };
        let pair = self.pair_of.get(node.index())?;
        if pair == NONE {
            return None;
        }
        Some(self.base + 2 * pair + right as u32)
    }

    /// The polygon in a slot, if the slot is live.
    #[inline]
    pub fn poly_at(&self, h: &Hierarchy<'_>, slot: u32) -> Option<PolyId> {
        if slot < self.base {
            return Some(PolyId(slot));
        }
        let rel = slot - self.base;
        let (pair, side) = (rel / 2, rel % 2);
        if pair >= self.pairs {
            return None;
        }
        let s = h.split(*self.owner.get(pair as usize)?)?;
        let p = if side == 0 { s.f_l } else { s.f_r };
        p.get()
    }

    /// The node an active-vertex record holds.
    #[inline]
    pub fn node_of(&self, record: u32) -> Option<NodeId> {
        let a = self.active.get(record as usize)?.node;
        (a & FREE == 0).then_some(NodeId(a))
    }
}

//! Per-camera refinement state in caller-owned memory: [`CameraState`] and its operations;
//! the layout and the design decisions are in its docs.

mod certificate;
mod compact;
mod compact_step;
mod config;
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
mod queries;
mod refine;
mod stats;

pub use compact_step::CompactProgress;
pub use config::{CameraConfig, CameraError};
pub use emit::EmitError;
pub use lag::FrontLag;
pub use morph::MorphVertex;
pub use ops::OpError;
pub use stats::RefineStats;

use bytemuck::{Pod, Zeroable};

use crate::hierarchy::Hierarchy;
use crate::ids::NodeId;
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
}

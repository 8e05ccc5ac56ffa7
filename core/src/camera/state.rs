//! The state of one camera: [`CameraState`] and the [`Front`] it keeps in caller memory.
//! The operations on it live in the files beside this one, each an `impl` of these types.

use super::certificate::Odometer;
use super::compact_progress::Progress;
use super::morph_pool::Morphs;
use super::pair_map::PairMap;
use super::placement::Placement;
use super::records::{ActiveVertex, PolySlot, SlotTriangle};
use crate::ids::NodeId;
#[cfg(doc)]
use crate::{gpu::MorphVertex, CameraConfig, Hierarchy, RefineStats};

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
/// | `place` | slots (0 without index edits) | per slot its polygon's place in the device index buffer |
/// | `slot_of` | slots × surfaces (0 without) | per place the slot whose polygon lies there |
/// | `free`, `marked` | places / 32 each (0 without) | a bit per place: a hole; changed since the last edits |
/// | `list` | `edit_list` | the places changed since the last edits |
/// | `regions` | 3 × surfaces (0 without) | per surface its places' end, holes and lowest possible hole |
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
///   every visit: those are two reads at unrelated addresses per visit, and several cameras'
///   worth of them do not fit the caches one camera's fit.
/// - **A refused collapse is remembered until something it depends on changes.** Most
///   collapses that refinement wants are illegal (a neighbour is still finer than the split
///   left it, or the floating child is split), and asking again costs a chain of dependent
///   reads across the hierarchy and the camera (split record, `pair_of`, both slots, the
///   neighbours' entries in `pair_of`), and a coarsening front meets many refusals for each
///   collapse it applies, every frame. Legality depends only on the pair's two slots (their
///   links and corners) and on the children being unsplit, so one bit per pair, set on a
///   refusal, is cleared by every write to either slot and by the collapse of either child;
///   a set bit answers "refused" from 4 bytes per 32 pairs. Compaction and reset clear every
///   bit.
/// - **Settled answers are certified, not asked again.** A visit asks whether the node's
///   split is wanted and, for a stationary child, whether its parent's still is; the answer
///   rarely changes, yet each question reads a bounds record from wherever the hierarchy
///   keeps it. The record keeps, per question, the answer and the odometer reading up to
///   which it provably stands (the eye's path length, or that plus the frustum planes'
///   sweep), and a visit before then reads nothing but its record (see `certificate`): a
///   view that moves little between passes leaves most answers standing, and a view that
///   holds still leaves all of them. 8 bytes per record.
/// - **Emission copies; operations keep the copy exact.** A polygon's vertex indices change
///   only when a corner moves to another active-vertex record: a record keeps its position
///   for life (a split hands it to the stationary child, which shares the position). So the
///   index cache keeps each slot's three indices with its surface and group, and an
///   operation rewrites just the corners it moves (one vertex-table row for all of them:
///   every moved corner lands on the same position) and the pair it creates; a
///   pair filling a hole brings its entries. Emission then copies the cache in slot order.
///   Without it, every frame follows five dependent reads per polygon across the hierarchy,
///   which several cameras' emissions push out of each other's caches. 16 bytes per slot;
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
    pub compaction: Progress,
    /// Each polygon's place in the device index buffer, and the places changed since the
    /// host last took the edits (empty arrays without [`CameraConfig::edit_list`]).
    pub placement: Placement<'m>,
}

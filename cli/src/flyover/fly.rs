//! Flights of several cameras over one hierarchy, measured per frame: a state per camera
//! (one thread, or one thread per camera) or the paper's baseline of one shared state
//! re-refined to each camera's view in turn.
//!
//! What every flight shares is in `common`: the per-frame records and their summary, one
//! camera's frame, the index lists and the cores camera threads are pinned to. The flights
//! are in `per_camera`, `shared` and `interleaved` (several flights segment by segment).

mod common;
mod interleaved;
mod per_camera;
mod shared;

pub(crate) use common::{cameras, compact_now, index_lists, percentile};
pub use common::{
    frame, mean, state_bytes, summarise, Compaction, Flight, IndexBuffers, Record, Summary,
};
pub use interleaved::{fly_interleaved, Group};
pub use per_camera::fly_per_camera;
pub use shared::fly_shared;

//! Per-camera refinement state in caller-owned memory: [`CameraState`] and its operations;
//! the layout and the design decisions are in its docs.
//!
//! The files form layers, each importing only files listed before it:
//! - `records`: the records in a camera's words and the values that mark them;
//! - the parts a camera is made of and a pass's tools: `config`, `stats`,
//!   `compact_progress`, `pair_map`, `morph_map`, `morph_pool`, `placement`, `certificate`,
//!   `criterion`;
//! - `state`: the [`CameraState`] and `Front` types, built of those parts;
//! - `layout` (where the arrays lie in the words) and `lifecycle` (making and resetting a
//!   camera);
//! - the operations, each an `impl` of the state: `queries`, `fan`, `index_cache`, `ops`
//!   (split and collapse), `morph`, `refine`, `lag`, `emit`, `index_edits`, `compact`,
//!   `compact_step`.
//!
//! This file only declares them and re-exports what the crate shows.

mod certificate;
mod compact;
mod compact_progress;
mod compact_step;
mod config;
mod criterion;
mod device_space;
mod emit;
mod fan;
mod index_cache;
mod index_edits;
mod lag;
mod layout;
mod lifecycle;
mod morph;
mod morph_map;
mod morph_pool;
mod ops;
mod pair_map;
mod placement;
mod queries;
mod records;
mod refine;
mod state;
mod stats;

pub use compact_step::{CompactProgress, COMPACT_STEP};
pub use config::{CameraConfig, CameraError};
pub use emit::EmitError;
pub use index_edits::{IndexEdit, IndexEdits, SurfaceDraw};
pub use lag::FrontLag;
pub use ops::OpError;
pub use state::CameraState;
pub use stats::RefineStats;

#[cfg(feature = "alloc")]
pub(crate) use layout::{Layout, Scalars};

//! g-mesh level-of-detail control (Southern & Gain): one global parameter `T`, partitions of
//! its range into levels, the level and geomorph factor each instance draws, and the greedy
//! predictive controller that holds a scene's polygon budget by offsetting `T`.
//!
//! Everything here is `no_std` and allocation-free: partitions and per-level polygon counts
//! are borrowed (from a baked file's g-mesh sections or caller arrays), instance state is a
//! small caller-owned struct ([`LodInstance`]) separate from the shared model, and the
//! controller's working memory is a caller slice ([`ControlEntry`], one per instance).
//! The attribute interpolation itself is [`crate::gpu::morph_vertex`] on the CPU and the
//! geomorph shader stages on the GPU.

mod control;
mod model;
mod partition;

pub use control::{
    control, scene_polygons, ControlEntry, ControlOutcome, ControlParams, LodInstance, LodModel,
};
pub use model::{gmesh_tags, GMesh, GMeshFormatError, GMeshLevel, GMeshParts};
pub use partition::{
    even_boundaries, t_from_distance, volume_boundaries, GMeshError, LevelMorph, Partitions,
};

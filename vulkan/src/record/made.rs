//! What is made for a recorder: its material sets and camera morphs take its layouts.
//! Their constructors live here, above both, so that the material and morph modules do not
//! name the recorder.

use super::Recorder;
use crate::camera_morphs::{CameraMorphs, MorphStage};
use crate::device::Context;
use crate::error::Result;
use crate::material::{MaterialSet, SurfaceMaterial};
use crate::mesh::VertexBuffer;

impl MaterialSet {
    /// Writes one set per surface of `surfaces`, for `recorder`'s pipelines.
    pub fn new(
        ctx: &Context,
        recorder: &Recorder,
        surfaces: &[SurfaceMaterial<'_>],
    ) -> Result<Self> {
        Self::with_bindings(ctx, recorder.bindings(), surfaces)
    }
}

impl CameraMorphs {
    /// Buffers and descriptor sets for a camera with `max_morphs` morphs
    /// ([`CameraState::max_morphs`](caveclod_core::CameraState::max_morphs)) over
    /// `vertices`, for `frames_in_flight` frame slots, blended by `stage`, for `recorder`'s
    /// morphing pipelines (made with [`RecorderDesc::refine_morphs`](crate::RecorderDesc)).
    /// `vertices` must outlive it.
    pub fn new(
        ctx: &Context,
        recorder: &Recorder,
        name: &str,
        vertices: &VertexBuffer,
        stage: MorphStage,
        max_morphs: u32,
        frames_in_flight: usize,
    ) -> Result<Self> {
        let parts = recorder.morph_layout();
        Self::with_layout(
            ctx,
            parts,
            name,
            vertices,
            stage,
            max_morphs,
            frames_in_flight,
        )
    }
}

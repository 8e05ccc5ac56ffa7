//! The crate's one error type.
//!
//! Every Vulkan call's result goes through `VkResultExt::vk`, which names the call and
//! sorts the results a caller may want to handle apart: a lost device and running out of
//! memory are their own variants, everything else is [`Error::Vulkan`].

use ash::vk;

/// Everything that can go wrong in caveclod-vulkan.
///
/// A failing Vulkan call is named in its variant; a lost device and running out of memory
/// have variants of their own, every other result is [`Error::Vulkan`]. The core's errors
/// convert with `From`, so `?` works on `Hierarchy::from_bytes`, `CameraState::new`,
/// `refine`, index emission, octree cuts and g-mesh checks.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The Vulkan loader library could not be loaded (no Vulkan installed).
    #[error("cannot load the Vulkan loader: {0} (install a Vulkan driver, e.g. Mesa's lavapipe)")]
    Loading(#[from] ash::LoadingError),
    /// No physical device has what the renderer needs.
    #[error("no usable Vulkan device: {0}")]
    NoDevice(String),
    /// The device lacks what this crate needs (see the `requirements` table on
    /// [`DeviceFeatures`](crate::DeviceFeatures)), or a target format cannot be used.
    #[error("{device}: unsupported: {}", .missing.join(", "))]
    Unsupported {
        /// The device's name.
        device: String,
        /// Each missing version, feature or format capability.
        missing: Vec<String>,
    },
    /// The device was lost during `call`.
    #[error("{call}: device lost")]
    DeviceLost {
        /// The Vulkan call.
        call: &'static str,
    },
    /// Host or device memory ran out during `call`.
    #[error("{call}: out of {} memory", if *.device { "device" } else { "host" })]
    OutOfMemory {
        /// The Vulkan call (or allocation).
        call: &'static str,
        /// Device memory (else host memory).
        device: bool,
    },
    /// Any other failing Vulkan result.
    #[error("{call}: {result}")]
    Vulkan {
        /// The Vulkan call.
        call: &'static str,
        /// What it returned.
        result: vk::Result,
    },
    /// gpu-allocator refused an allocation.
    #[error("allocating {name}: {source}")]
    Allocation {
        /// The resource.
        name: String,
        /// Why.
        source: gpu_allocator::AllocationError,
    },
    /// The committed SPIR-V module cannot be read.
    #[error("shader module: {0}")]
    Shader(String),
    /// A hierarchy's bytes were refused ([`caveclod_core::Hierarchy::from_bytes`]).
    #[error("hierarchy: {0}")]
    Format(#[from] caveclod_core::FormatError),
    /// A camera could not be made over its memory ([`caveclod_core::CameraState::new`]).
    #[error("camera: {0}")]
    Camera(#[from] caveclod_core::CameraError),
    /// A camera operation (refine, split, collapse) was refused.
    #[error("camera operation: {0}")]
    CameraOp(#[from] caveclod_core::OpError),
    /// Index emission of a camera failed ([`CameraIndices::fill`](crate::CameraIndices::fill)).
    #[error("index emission: {0}")]
    Emit(#[from] caveclod_core::EmitError),
    /// An octree cut was refused ([`caveclod_core::OctreeCut`]).
    #[error("octree cut: {0}")]
    Cut(#[from] caveclod_core::CutError),
    /// An octree's bytes were refused ([`caveclod_core::Octree`]).
    #[error("octree: {0}")]
    OctreeFormat(#[from] caveclod_core::OctreeFormatError),
    /// G-mesh partitions or controller inputs were refused.
    #[error("g-mesh: {0}")]
    GMesh(#[from] caveclod_core::gmesh::GMeshError),
    /// A g-mesh's sections were refused.
    #[error("g-mesh format: {0}")]
    GMeshFormat(#[from] caveclod_core::gmesh::GMeshFormatError),
    /// An argument is out of range.
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
    /// Resources of this context were not destroyed before it.
    #[error("{} resource(s) leaked (not destroyed before the context): {}", .0.len(), .0.join(", "))]
    Leaked(Vec<String>),
}

/// Results of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Maps a Vulkan result to [`Error`], naming the call.
pub(crate) trait VkResultExt<T> {
    /// `Err` of a `vk::Result` becomes the matching [`Error`] variant for `call`.
    fn vk(self, call: &'static str) -> Result<T>;
}

impl<T> VkResultExt<T> for std::result::Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> Result<T> {
        self.map_err(|result| from_vk(call, result))
    }
}

/// The [`Error`] for a failing `result` of `call`.
pub(crate) fn from_vk(call: &'static str, result: vk::Result) -> Error {
    match result {
        vk::Result::ERROR_DEVICE_LOST => Error::DeviceLost { call },
        vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => Error::OutOfMemory { call, device: true },
        vk::Result::ERROR_OUT_OF_HOST_MEMORY => Error::OutOfMemory {
            call,
            device: false,
        },
        result => Error::Vulkan { call, result },
    }
}

/// The [`Error`] for a failed allocation of `name`.
pub(crate) fn from_allocation(name: &str, source: gpu_allocator::AllocationError) -> Error {
    match source {
        gpu_allocator::AllocationError::OutOfMemory => Error::OutOfMemory {
            call: "gpu_allocator::Allocator::allocate",
            device: true,
        },
        source => Error::Allocation {
            name: name.to_string(),
            source,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn device_lost_and_out_of_memory_have_their_own_variants() {
        let r: std::result::Result<(), vk::Result> = Err(vk::Result::ERROR_DEVICE_LOST);
        assert!(matches!(
            r.vk("vkQueueSubmit2"),
            Err(Error::DeviceLost {
                call: "vkQueueSubmit2"
            })
        ));
        let e = from_vk("vkAllocateMemory", vk::Result::ERROR_OUT_OF_DEVICE_MEMORY);
        assert!(matches!(e, Error::OutOfMemory { device: true, .. }));
        assert_eq!(e.to_string(), "vkAllocateMemory: out of device memory");
        let e = from_vk("vkCreateBuffer", vk::Result::ERROR_INITIALIZATION_FAILED);
        assert!(matches!(e, Error::Vulkan { .. }));
    }

    #[test]
    fn core_errors_convert_with_question_mark() {
        fn load(bytes: &[u8]) -> Result<usize> {
            Ok(caveclod_core::Hierarchy::from_bytes(bytes)?.surface_count())
        }
        let e = load(&[]).err();
        assert!(matches!(e, Some(Error::Format(_))), "{e:?}");
        assert!(e.is_some_and(|e| std::error::Error::source(&e).is_some()));

        let emit = caveclod_core::EmitError::WrongHierarchy;
        let e = Error::from(emit);
        assert!(matches!(e, Error::Emit(_)));
        assert_eq!(e.to_string(), format!("index emission: {emit}"));

        let e: Error = caveclod_core::CutError::WrongOctree.into();
        assert!(matches!(
            e,
            Error::Cut(caveclod_core::CutError::WrongOctree)
        ));
    }
}

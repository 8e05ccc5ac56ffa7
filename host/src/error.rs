//! The harness's one error type: every failing Vulkan call named, caveclod's own errors
//! passed through.

use caveclod_vulkan::ash::vk;
use caveclod_vulkan::gpu_allocator::AllocationError;

/// Everything that can go wrong in the host harness.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// caveclod-vulkan refused or failed (the Vulkan loader missing, a context refused).
    #[error(transparent)]
    Caveclod(#[from] caveclod_vulkan::Error),
    /// A Vulkan call of the host's failed.
    #[error("{call}: {result}")]
    Vulkan {
        /// The Vulkan call.
        call: &'static str,
        /// What it returned.
        result: vk::Result,
    },
    /// The host's gpu-allocator refused an allocation.
    #[error("allocating {name}: {source}")]
    Allocation {
        /// The resource.
        name: String,
        /// Why.
        #[source]
        source: AllocationError,
    },
    /// Validation was asked for, but the layer is not installed.
    #[error("validation asked for, but {0} is not installed (Debian: vulkan-validationlayers)")]
    NoValidationLayer(String),
    /// No physical device has what the host needs; each one is named with what it lacks.
    #[error("no usable Vulkan device: {0}")]
    NoDevice(String),
    /// The window system refused (a display or window handle, a surface format).
    #[error("the window: {0}")]
    Window(String),
    /// An argument is out of range (an empty target, a slot that does not exist).
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
    /// Teardown found what should have been destroyed first (allocations left, a context
    /// still holding the allocator).
    #[error("teardown: {0}")]
    Teardown(String),
}

/// Results of the harness.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Names the Vulkan call of a failing result.
pub(crate) trait VkExt<T> {
    /// `Err(Error::Vulkan { call, .. })` for a failing result.
    fn vk(self, call: &'static str) -> Result<T>;
}

impl<T> VkExt<T> for std::result::Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> Result<T> {
        self.map_err(|result| Error::Vulkan { call, result })
    }
}

/// An allocation error naming the resource.
pub(crate) fn allocation(name: &str) -> impl FnOnce(AllocationError) -> Error + '_ {
    move |source| Error::Allocation {
        name: name.to_string(),
        source,
    }
}

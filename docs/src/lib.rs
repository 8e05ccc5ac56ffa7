//! The README and the user guide, one module per page, so that `cargo test` compiles (and
//! runs) every Rust snippet in them: a snippet cannot drift from the API. The C snippets are
//! compiled against the header by `cargo xtask test`.
#![deny(missing_docs)]

/// `README.md`.
#[doc = include_str!("../../README.md")]
pub mod readme {}

/// `docs/baking.md`.
#[doc = include_str!("../baking.md")]
pub mod baking {}

/// `docs/out-of-core.md`.
#[doc = include_str!("../out-of-core.md")]
pub mod out_of_core {}

/// `docs/frame-loop.md`.
#[doc = include_str!("../frame-loop.md")]
pub mod frame_loop {}

/// `docs/vulkan.md`.
#[doc = include_str!("../vulkan.md")]
pub mod vulkan {}

/// `docs/gmesh-crowds.md`.
#[doc = include_str!("../gmesh-crowds.md")]
pub mod gmesh_crowds {}

/// `docs/c-and-cpp.md`.
#[doc = include_str!("../c-and-cpp.md")]
pub mod c_and_cpp {}

/// `docs/viewer.md`.
#[doc = include_str!("../viewer.md")]
pub mod viewer {}

/// `docs/measuring.md`.
#[doc = include_str!("../measuring.md")]
pub mod measuring {}

/// `docs/streaming.md`.
#[doc = include_str!("../streaming.md")]
pub mod streaming {}

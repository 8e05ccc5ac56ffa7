//! Typed indices into the hierarchy's arrays.
//!
//! Every id is a `#[repr(transparent)]` newtype over an unsigned integer and is `Pod`, so the
//! baked file's arrays of records are cast from bytes without copying. `NONE` (all bits set)
//! marks an absent reference: a root's parent, a leaf's children, the right polygon of a split
//! on a mesh border. Ids read from a file are validated once, at load; afterwards the runtime
//! indexes with them freely.

use bytemuck::{Pod, Zeroable};

macro_rules! id_type {
    ($(#[$doc:meta])* $name:ident, $int:ty) => {
        $(#[$doc])*
        #[repr(transparent)]
        #[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Pod, Zeroable)]
        pub struct $name(pub $int);

        impl $name {
            /// The absent id (all bits set).
            pub const NONE: Self = Self(<$int>::MAX);

            /// Builds an id from an array index.
            #[inline]
            pub const fn new(index: $int) -> Self {
                Self(index)
            }

            /// The id as an array index.
            #[inline]
            pub const fn index(self) -> usize {
                self.0 as usize
            }

            /// `true` unless this is [`Self::NONE`].
            #[inline]
            pub const fn is_some(self) -> bool {
                self.0 != <$int>::MAX
            }

            /// `true` if this is [`Self::NONE`].
            #[inline]
            pub const fn is_none(self) -> bool {
                self.0 == <$int>::MAX
            }

            /// `Some(self)` unless this is [`Self::NONE`].
            #[inline]
            pub const fn get(self) -> Option<Self> {
                if self.is_some() { Some(self) } else { None }
            }
        }

        impl core::fmt::Debug for $name {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                if self.is_none() {
                    write!(f, concat!(stringify!($name), "(NONE)"))
                } else {
                    write!(f, concat!(stringify!($name), "({})"), self.0)
                }
            }
        }

        impl core::fmt::Display for $name {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                core::fmt::Debug::fmt(self, f)
            }
        }
    };
}

id_type!(
    /// A node of the vertex hierarchy: a full-resolution vertex (leaf) or the result of a
    /// collapse (internal node, which owns a [`Split`](crate::Split) record).
    NodeId,
    u32
);
id_type!(
    /// A polygon (triangle) of the full-resolution mesh.
    PolyId,
    u32
);
id_type!(
    /// A node position: a unique point in space, shared by a node and its stationary
    /// descendants.
    PositionId,
    u32
);
id_type!(
    /// A surface: one material / texture, selecting the index list a polygon is emitted into.
    SurfaceId,
    u16
);
id_type!(
    /// A surface-group id: the row of the vertex table a polygon's corners are looked up in.
    /// Surface groups that share no position may share one id (graph colouring).
    SurfaceGroupId,
    u16
);

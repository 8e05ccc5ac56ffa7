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
    /// collapse (internal node, which owns a [`Split`](crate::format::Split) record).
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
id_type!(
    /// A polygon named by where it comes from rather than by its place in the polygon array:
    /// a base polygon's [`PolyId`], or `base_polygons + 2 · node + side` for a polygon that
    /// `node`'s split creates (side 1 for `f_r`), the slot the polygon would take in a camera
    /// whose pairs were numbered by node. [`Split::neighbours`](crate::format::Split) names polygons
    /// so: a camera finds a neighbour's slot from the key and its own map from split to pair,
    /// without reading the neighbour's polygon record (a dependent cache miss per neighbour
    /// in a split's or collapse's legality check).
    PolyKey,
    u32
);

impl PolyKey {
    /// The key of base polygon `poly`.
    #[inline]
    pub const fn base(poly: PolyId) -> Self {
        Self(poly.0)
    }

    /// The key of the polygon `node`'s split creates, `f_r` if `right`, in a hierarchy of
    /// `base_polygons` base polygons. (Wraps rather than panics on counts no valid file has;
    /// validation refuses such keys.)
    #[inline]
    pub const fn created(base_polygons: u32, node: NodeId, right: bool) -> Self {
        Self(
            base_polygons
                .wrapping_add(node.0.wrapping_mul(2))
                .wrapping_add(right as u32),
        )
    }

    /// The split that creates the polygon and whether it is that split's `f_r`; `None` for a
    /// base polygon (a key under `base_polygons`) and for [`Self::NONE`].
    #[inline]
    pub const fn creator(self, base_polygons: u32) -> Option<(NodeId, bool)> {
        if self.is_none() || self.0 < base_polygons {
            return None;
        }
        let rel = self.0 - base_polygons;
        Some((NodeId(rel >> 1), rel & 1 == 1))
    }
}

/// A page of one of a pool's files: the file's index (from
/// [`Residency::add_file`](crate::stream::Residency::add_file)) and the page's index in its table.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PageKey {
    /// The file.
    pub file: u32,
    /// The page.
    pub page: u32,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poly_keys_name_base_polygons_and_creators() {
        for nb in [1u32, 3, 1000] {
            for node in [0u32, 1, 77, 1 << 30] {
                for right in [false, true] {
                    let k = PolyKey::created(nb, NodeId(node), right);
                    assert!(k.0 >= nb);
                    assert_eq!(k.creator(nb), Some((NodeId(node), right)));
                }
            }
            for b in 0..nb.min(10) {
                assert_eq!(PolyKey::base(PolyId(b)), PolyKey(b));
                assert_eq!(PolyKey(b).creator(nb), None);
            }
            assert_eq!(PolyKey::NONE.creator(nb), None);
        }
    }
}

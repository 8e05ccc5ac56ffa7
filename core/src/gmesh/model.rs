//! The g-mesh levels stored beside a hierarchy: connectivity sets `c_i` and the geomorph
//! attribute pairs `(a_i, a'_i)` of every level, as indices into the hierarchy's persistent
//! vertex buffer.
//!
//! # Layout, against the paper's bound
//! Southern & Gain's practical layout (Fig. 14b) stores for every level its own attribute
//! arrays `a_i` and `a'_i` (the next level's attributes re-indexed like `a_i`), bounded by
//! `4κ|a_0| + 2ρ|c_0|` bytes (κ bytes per attribute entry, ρ per connectivity entry, levels
//! roughly halving). Our batches are half-edge collapses, so every attribute any level ever
//! needs — in `a_i` or in `a'_i` — is already a vertex of the hierarchy's vertex buffer: a level
//! stores, per vertex it uses, only the pair `(from, to)` of vertex-buffer indices (8 bytes,
//! against 2κ = 64 bytes for two 32-byte attribute entries) and its triangles as local indices
//! per surface. With halving levels that is about `κ|a_0| + 16|a_0| + 2ρ|c_0|` in all: the
//! attribute term shrinks from 4κ to 1.5κ. The two attribute streams a renderer binds
//! (`a_i`, `a'_i`) are gathered from these pairs at upload time.
//!
//! Sections (tags `GM..`, carried as extra sections of a `.clod` file, all little-endian):
//!
//! | tag    | record       | per                      | meaning                                |
//! |--------|--------------|--------------------------|----------------------------------------|
//! | `GMPC` | `u32`        | level                    | `|c_i|`, polygons of level `i`         |
//! | `GMBD` | `f32`        | level                    | partition boundary `R_i` (`R_n = 1`)   |
//! | `GMVL` | `f32`        | level                    | normalised volume `V_i` (`V_0 = 1`)    |
//! | `GMVO` | `u32`        | level + 1                | offsets into `GMVX`                    |
//! | `GMIO` | `u32`        | level × surface + 1      | offsets into `GMIX`, level-major       |
//! | `GMVX` | `[u32; 2]`   | vertex of a level        | `(from, to)` vertex-buffer indices     |
//! | `GMIX` | `u32`        | corner of a level        | index into the level's `GMVX` range    |
//!
//! At the coarsest level `from == to`. Everything is validated once in [`GMesh::new`].

use super::partition::{GMeshError, Partitions};
use super::LodModel;
use crate::format::Tag;
use crate::Hierarchy;

/// Section tags of the g-mesh levels.
pub mod gmesh_tags {
    use crate::format::Tag;
    /// Polygons per level.
    pub const POLYGONS: Tag = Tag(*b"GMPC");
    /// Partition boundaries per level.
    pub const BOUNDARIES: Tag = Tag(*b"GMBD");
    /// Normalised volumes per level.
    pub const VOLUMES: Tag = Tag(*b"GMVL");
    /// Vertex-pair offsets per level.
    pub const VERTEX_OFFSETS: Tag = Tag(*b"GMVO");
    /// Index offsets per level and surface.
    pub const INDEX_OFFSETS: Tag = Tag(*b"GMIO");
    /// `(from, to)` vertex pairs.
    pub const VERTICES: Tag = Tag(*b"GMVX");
    /// Local triangle indices.
    pub const INDICES: Tag = Tag(*b"GMIX");
    /// All of them, in file order.
    pub const ALL: [Tag; 7] = [
        POLYGONS,
        BOUNDARIES,
        VOLUMES,
        VERTEX_OFFSETS,
        INDEX_OFFSETS,
        VERTICES,
        INDICES,
    ];
}

/// The borrowed arrays of a g-mesh (see the module docs for their meaning).
#[derive(Clone, Copy, Debug)]
pub struct GMeshParts<'a> {
    /// `|c_i|` per level.
    pub level_polygons: &'a [u32],
    /// `R_i` per level.
    pub boundaries: &'a [f32],
    /// `V_i` per level.
    pub volumes: &'a [f32],
    /// Offsets into `vertices`, one per level plus one.
    pub vertex_offsets: &'a [u32],
    /// Offsets into `indices`, one per (level, surface) plus one.
    pub index_offsets: &'a [u32],
    /// `(from, to)` vertex-buffer indices.
    pub vertices: &'a [[u32; 2]],
    /// Local indices, three per triangle.
    pub indices: &'a [u32],
}

/// Why g-mesh sections were refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GMeshFormatError {
    /// Some but not all g-mesh sections are present.
    MissingSection(Tag),
    /// A section's size is not a whole number of records, or it is not 4-byte aligned.
    BadSection(Tag),
    /// The partitions or counts are inconsistent.
    Levels(GMeshError),
    /// An offset table does not start at 0, decreases, or does not end at its array's length.
    BadOffsets {
        /// The offset table.
        tag: Tag,
        /// Index of the first bad entry.
        index: usize,
    },
    /// A level's index count is not three times its polygon count.
    PolygonCount {
        /// The level.
        level: usize,
    },
    /// A vertex-buffer index is out of range.
    VertexOutOfRange {
        /// Index into `GMVX`.
        index: usize,
        /// The value.
        vertex: u32,
    },
    /// A local index points outside its level's vertex range.
    IndexOutOfRange {
        /// The level.
        level: usize,
        /// Index into `GMIX`.
        index: usize,
    },
    /// At the coarsest level a vertex morphs somewhere (`from != to`).
    CoarsestMorphs {
        /// Index into `GMVX`.
        index: usize,
    },
}

impl core::fmt::Display for GMeshFormatError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::MissingSection(t) => write!(f, "g-mesh section {t} is missing"),
            Self::BadSection(t) => {
                write!(
                    f,
                    "g-mesh section {t}: size or alignment does not fit its records"
                )
            }
            Self::Levels(e) => write!(f, "g-mesh levels: {e}"),
            Self::BadOffsets { tag, index } => write!(
                f,
                "g-mesh section {tag}, entry {index}: offsets must start at 0, never decrease \
                 and end at the array's length"
            ),
            Self::PolygonCount { level } => write!(
                f,
                "g-mesh level {level}: index count is not three times the polygon count"
            ),
            Self::VertexOutOfRange { index, vertex } => write!(
                f,
                "g-mesh section GMVX, record {index}: vertex {vertex} is outside the vertex buffer"
            ),
            Self::IndexOutOfRange { level, index } => write!(
                f,
                "g-mesh section GMIX, entry {index}: outside level {level}'s vertices"
            ),
            Self::CoarsestMorphs { index } => write!(
                f,
                "g-mesh section GMVX, record {index}: the coarsest level cannot morph"
            ),
        }
    }
}

impl core::error::Error for GMeshFormatError {}

/// Validated g-mesh levels over a vertex buffer of a known size.
#[derive(Clone, Copy, Debug)]
pub struct GMesh<'a> {
    parts: GMeshParts<'a>,
    partitions: Partitions<'a>,
    surfaces: usize,
}

/// One level's draw data.
#[derive(Clone, Copy, Debug)]
pub struct GMeshLevel<'a> {
    /// `(from, to)` vertex-buffer indices of the level's vertices.
    pub vertices: &'a [[u32; 2]],
    /// Local indices (into `vertices`), all surfaces, surface-major.
    pub indices: &'a [u32],
    /// Offsets of each surface's indices within `indices` (surfaces + 1 entries,
    /// relative to the level's first index).
    pub surface_offsets: &'a [u32],
    /// The first entry of `surface_offsets` in absolute terms (subtract it).
    pub index_base: u32,
}

impl<'a> GMeshLevel<'a> {
    /// The local indices of one surface.
    pub fn surface_indices(&self, surface: usize) -> &'a [u32] {
        let (Some(&s), Some(&e)) = (
            self.surface_offsets.get(surface),
            self.surface_offsets.get(surface + 1),
        ) else {
            return &[];
        };
        let (s, e) = (
            (s - self.index_base) as usize,
            (e - self.index_base) as usize,
        );
        self.indices.get(s..e).unwrap_or(&[])
    }
}

fn cast<T: bytemuck::Pod>(tag: Tag, bytes: &[u8]) -> Result<&[T], GMeshFormatError> {
    bytemuck::try_cast_slice(bytes).map_err(|_| GMeshFormatError::BadSection(tag))
}

fn check_offsets(tag: Tag, offsets: &[u32], len: usize) -> Result<(), GMeshFormatError> {
    if offsets.first() != Some(&0) {
        return Err(GMeshFormatError::BadOffsets { tag, index: 0 });
    }
    if let Some(i) = (1..offsets.len()).find(|&i| offsets[i] < offsets[i - 1]) {
        return Err(GMeshFormatError::BadOffsets { tag, index: i });
    }
    if offsets.last().map(|&l| l as usize) != Some(len) {
        return Err(GMeshFormatError::BadOffsets {
            tag,
            index: offsets.len().saturating_sub(1),
        });
    }
    Ok(())
}

impl<'a> GMesh<'a> {
    /// The g-mesh sections of a hierarchy loaded from bytes: `Ok(None)` when it has none.
    pub fn from_hierarchy(h: &Hierarchy<'a>) -> Result<Option<Self>, GMeshFormatError> {
        use gmesh_tags as t;
        let present = t::ALL
            .iter()
            .filter(|&&tag| h.section(tag).is_some())
            .count();
        if present == 0 {
            return Ok(None);
        }
        let get = |tag: Tag| h.section(tag).ok_or(GMeshFormatError::MissingSection(tag));
        let parts = GMeshParts {
            level_polygons: cast(t::POLYGONS, get(t::POLYGONS)?)?,
            boundaries: cast(t::BOUNDARIES, get(t::BOUNDARIES)?)?,
            volumes: cast(t::VOLUMES, get(t::VOLUMES)?)?,
            vertex_offsets: cast(t::VERTEX_OFFSETS, get(t::VERTEX_OFFSETS)?)?,
            index_offsets: cast(t::INDEX_OFFSETS, get(t::INDEX_OFFSETS)?)?,
            vertices: cast(t::VERTICES, get(t::VERTICES)?)?,
            indices: cast(t::INDICES, get(t::INDICES)?)?,
        };
        Self::new(parts, h.vertices().len(), h.surface_count()).map(Some)
    }

    /// Validates `parts` against a vertex buffer of `vertex_count` vertices and `surfaces`
    /// surfaces.
    pub fn new(
        parts: GMeshParts<'a>,
        vertex_count: usize,
        surfaces: usize,
    ) -> Result<Self, GMeshFormatError> {
        use gmesh_tags as t;
        let partitions = Partitions::new(parts.boundaries).map_err(GMeshFormatError::Levels)?;
        let levels = partitions.levels();
        let same = |what: &'static str, got: usize, expected: usize| {
            if got == expected {
                Ok(())
            } else {
                Err(GMeshFormatError::Levels(GMeshError::LengthMismatch {
                    what,
                    expected,
                    got,
                }))
            }
        };
        same("level_polygons", parts.level_polygons.len(), levels)?;
        same("volumes", parts.volumes.len(), levels)?;
        same("vertex_offsets", parts.vertex_offsets.len(), levels + 1)?;
        same(
            "index_offsets",
            parts.index_offsets.len(),
            levels * surfaces + 1,
        )?;
        if let Some(index) = parts.volumes.iter().position(|v| !v.is_finite()) {
            return Err(GMeshFormatError::Levels(GMeshError::NotFinite {
                what: "volumes",
                index,
            }));
        }
        check_offsets(
            t::VERTEX_OFFSETS,
            parts.vertex_offsets,
            parts.vertices.len(),
        )?;
        check_offsets(t::INDEX_OFFSETS, parts.index_offsets, parts.indices.len())?;
        for (index, pair) in parts.vertices.iter().enumerate() {
            if let Some(&vertex) = pair.iter().find(|&&v| v as usize >= vertex_count) {
                return Err(GMeshFormatError::VertexOutOfRange { index, vertex });
            }
        }
        for level in 0..levels {
            let (i0, i1) = (
                parts.index_offsets[level * surfaces] as usize,
                parts.index_offsets[(level + 1) * surfaces] as usize,
            );
            if i1 - i0 != 3 * parts.level_polygons[level] as usize {
                return Err(GMeshFormatError::PolygonCount { level });
            }
            let (v0, v1) = (
                parts.vertex_offsets[level] as usize,
                parts.vertex_offsets[level + 1] as usize,
            );
            let n = (v1 - v0) as u64;
            if let Some(k) = parts.indices[i0..i1]
                .iter()
                .position(|&i| u64::from(i) >= n)
            {
                return Err(GMeshFormatError::IndexOutOfRange {
                    level,
                    index: i0 + k,
                });
            }
            if level + 1 == levels {
                if let Some(k) = parts.vertices[v0..v1].iter().position(|p| p[0] != p[1]) {
                    return Err(GMeshFormatError::CoarsestMorphs { index: v0 + k });
                }
            }
        }
        Ok(Self {
            parts,
            partitions,
            surfaces,
        })
    }

    /// The arrays.
    pub fn parts(&self) -> &GMeshParts<'a> {
        &self.parts
    }

    /// Number of levels `n + 1`.
    pub fn levels(&self) -> usize {
        self.partitions.levels()
    }

    /// Number of surfaces.
    pub fn surfaces(&self) -> usize {
        self.surfaces
    }

    /// The partitions `R_i`.
    pub fn partitions(&self) -> Partitions<'a> {
        self.partitions
    }

    /// `|c_i|` per level, finest first.
    pub fn level_polygons(&self) -> &'a [u32] {
        self.parts.level_polygons
    }

    /// `V_i` per level.
    pub fn volumes(&self) -> &'a [f32] {
        self.parts.volumes
    }

    /// The controller's view of this g-mesh.
    pub fn lod_model(&self) -> LodModel<'a> {
        // Lengths were checked in `new`.
        LodModel {
            partitions: self.partitions,
            level_polygons: self.parts.level_polygons,
        }
    }

    /// One level's vertices and indices (`None` past the coarsest).
    pub fn level(&self, level: usize) -> Option<GMeshLevel<'a>> {
        if level >= self.levels() {
            return None;
        }
        let p = &self.parts;
        let (v0, v1) = (
            p.vertex_offsets[level] as usize,
            p.vertex_offsets[level + 1] as usize,
        );
        let s = self.surfaces;
        let offsets = &p.index_offsets[level * s..=(level + 1) * s];
        let (i0, i1) = (offsets[0] as usize, offsets[s] as usize);
        Some(GMeshLevel {
            vertices: &p.vertices[v0..v1],
            indices: &p.indices[i0..i1],
            surface_offsets: offsets,
            index_base: offsets[0],
        })
    }
}

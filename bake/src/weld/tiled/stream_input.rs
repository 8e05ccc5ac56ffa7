//! A PLY file streamed into tiles on disk, never held whole: the tiled weld's input for a
//! mesh larger than memory should hold.
//!
//! One pass over the file ([`crate::ooc::stream::read_indexed`]). The vertices come first:
//! each is welded on the way (a table of the distinct coordinates, numbered in input order as
//! step 1 of the in-core weld numbers them), its attributes, where the file has any, go to a
//! temporary file of fixed records at full precision (colours to linear, `v` flipped, as the
//! in-core importer reads them). The faces follow: each triangle of a face's fan gets its
//! corners' welded positions and attributes (looked up through a [`BlockCache`]: faces name
//! nearby vertices) and is appended to the file of the tile its centroid lies in. What stays
//! in memory is the welded positions and, per position, its tile (16 bytes a position), and
//! per input vertex its welded id while the faces are read (4 bytes a vertex).

use std::fs::File;
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};

use hashbrown::hash_table::{Entry, HashTable};

use super::mesh_input::TileGrid;
use super::tiles::{TileTriangle, TiledMesh, Tiles, SHARED};
use crate::base::colour::srgb_to_linear;
use crate::base::fxhash::hash_of;
use crate::base::temp::{SpillWriter, TempSpace};
use crate::mesh::{Surface, Texture};
use crate::ooc::soup::{HAS_COLOR, HAS_NORMAL, HAS_UV};
use crate::ooc::stream::{read_indexed, BlockCache, IndexedHeader, IndexedSink};
use crate::ooc::OocError;
use crate::weld::welded::{MAX_TRIANGLES, NONE};

/// A vertex's attributes: normal, texture coordinates, linear colour.
type VertexAttributes = [f32; 9];

/// Bytes of the vertex attributes' look-up cache.
const CACHE_BYTES: usize = 32 << 20;

/// Buffer of each tile's file.
const TILE_BUFFER: usize = 1 << 16;

/// The tiles of a PLY file, in temporary files.
pub struct StreamTiles {
    mesh: TiledMesh,
    /// Per tile, its file (`None` when empty).
    files: Vec<Option<PathBuf>>,
    /// What the file said besides its triangles.
    pub report: StreamedReport,
}

/// What a streamed file told besides its triangles.
#[derive(Clone, Debug, Default)]
pub struct StreamedReport {
    /// The surfaces (one, with the texture a `comment TextureFile` names).
    pub surfaces: Vec<Surface>,
    /// Triangles read.
    pub triangles: u64,
    /// Faces with fewer than three corners, skipped.
    pub skipped_faces: u64,
}

impl StreamTiles {
    /// Reads the PLY file at `path` (named `name` in errors) into tiles of about
    /// `tile_triangles` triangles each, in files of `temp`. A file with what only the
    /// in-core importer reads (triangle strips, per-corner texture coordinates) is
    /// [`OocError::Unsupported`].
    pub fn open(
        path: &Path,
        name: &str,
        temp: &TempSpace,
        tile_triangles: usize,
    ) -> Result<Self, OocError> {
        let file = File::open(path).map_err(|e| OocError::io(name, "cannot read", e))?;
        let mut state = Reading {
            name,
            temp,
            tile_triangles,
            header: None,
            positions: Vec::new(),
            by_bits: HashTable::new(),
            remap: Vec::new(),
            attributes: None,
            cache: None,
            flags: 0,
            grid: None,
            tiles: Vec::new(),
            owner: Vec::new(),
            next_index: 0,
        };
        let skipped = read_indexed(name, file, &mut state)?;
        let header = state.header.take();
        let (flags, texture) = header.map_or((0, None), |h| (h.flags, h.texture));
        let Reading {
            tiles,
            positions,
            owner,
            remap,
            next_index,
            ..
        } = state;
        let triangles = next_index;
        let files = tiles
            .into_iter()
            .map(|(w, n)| {
                if n == 0 {
                    Ok(None)
                } else {
                    w.finish().map(Some)
                }
            })
            .collect::<io::Result<Vec<_>>>()
            .map_err(|e| OocError::temp("writing the tiles' files", e))?;
        if triangles == 0 {
            return Err(OocError::Empty {
                file: name.to_string(),
            });
        }
        Ok(Self {
            mesh: TiledMesh {
                welded_positions: remap.len() as u64 - positions.len() as u64,
                positions,
                owner,
                surface_count: 1,
                has_colors: flags & HAS_COLOR != 0,
            },
            files,
            report: StreamedReport {
                surfaces: vec![Surface {
                    texture: texture.map(Texture::File),
                    ..Surface::plain("default")
                }],
                triangles,
                skipped_faces: skipped,
            },
        })
    }
}

impl Tiles for StreamTiles {
    fn mesh(&self) -> &TiledMesh {
        &self.mesh
    }

    fn tile_count(&self) -> usize {
        self.files.len()
    }

    fn read(&mut self, tile: usize, out: &mut Vec<TileTriangle>) -> io::Result<()> {
        out.clear();
        if let Some(path) = &self.files[tile] {
            let mut f = File::open(path)?;
            let len = f.metadata()?.len() as usize / std::mem::size_of::<TileTriangle>();
            out.resize(len, TileTriangle::default());
            f.read_exact(bytemuck::cast_slice_mut(out))?;
        }
        Ok(())
    }
}

fn too_large(name: &str, faces: u64, vertices: u64) -> OocError {
    OocError::Unsupported {
        file: name.to_string(),
        message: format!(
            "{faces} faces and {vertices} vertices: at most {MAX_TRIANGLES} triangles and {} points supported",
            NONE - 1
        ),
    }
}

/// The reading's state: the vertices welded, then the faces into tiles.
struct Reading<'a> {
    name: &'a str,
    temp: &'a TempSpace,
    tile_triangles: usize,
    header: Option<IndexedHeader>,
    /// The welded positions.
    positions: Vec<[f32; 3]>,
    /// Their ids, hashed by their coordinates' bits.
    by_bits: HashTable<u32>,
    /// The welded id of every input vertex.
    remap: Vec<u32>,
    /// The vertices' attributes while they are read.
    attributes: Option<SpillWriter>,
    /// ... and their look-up while the faces are read.
    cache: Option<BlockCache<VertexAttributes>>,
    /// What the vertices carry.
    flags: u16,
    grid: Option<TileGrid>,
    /// Per tile: its file and its triangles so far.
    tiles: Vec<(SpillWriter, u64)>,
    owner: Vec<u32>,
    next_index: u64,
}

impl IndexedSink for Reading<'_> {
    fn header(&mut self, h: &IndexedHeader) -> Result<(), OocError> {
        if let Some(what) = &h.unread {
            return Err(OocError::Unsupported {
                file: self.name.to_string(),
                message: format!("{what} is read by the in-core importer only"),
            });
        }
        if h.vertices >= u64::from(NONE) {
            return Err(too_large(self.name, h.faces, h.vertices));
        }
        self.remap.reserve(h.vertices as usize);
        if h.flags != 0 {
            self.attributes = Some(
                self.temp
                    .create("vertex-attributes", 1 << 16)
                    .map_err(|e| OocError::temp("creating the vertex attributes' file", e))?,
            );
        }
        self.header = Some(h.clone());
        Ok(())
    }

    fn vertex(&mut self, _: u64, v: &[f64; 12]) -> Result<(), OocError> {
        self.weld_vertex(v)
            .map_err(|e| OocError::temp("writing the vertex attributes", e))
    }

    fn face(&mut self, f: u64, corners: &[u64]) -> Result<(), OocError> {
        if self.tiles.is_empty() {
            self.start_faces()
                .map_err(|e| OocError::temp("creating the tiles' files", e))?;
        }
        self.fan(f, corners)
    }
}

impl Reading<'_> {
    fn weld_vertex(&mut self, v: &[f64; 12]) -> io::Result<()> {
        let p = [v[0] as f32, v[1] as f32, v[2] as f32];
        let bits = p.map(|x| (x + 0.0).to_bits());
        let positions = &mut self.positions;
        let entry = self.by_bits.entry(
            hash_of(&bits),
            |&id| positions[id as usize].map(|x| (x + 0.0).to_bits()) == bits,
            |&id| hash_of(&positions[id as usize].map(|x| (x + 0.0).to_bits())),
        );
        let id = match entry {
            Entry::Occupied(e) => *e.get(),
            Entry::Vacant(e) => {
                positions.push(p);
                let id = positions.len() as u32 - 1;
                e.insert(id);
                id
            }
        };
        self.remap.push(id);
        if let Some(w) = &mut self.attributes {
            let a: VertexAttributes = [
                v[3] as f32,
                v[4] as f32,
                v[5] as f32,
                v[6] as f32,
                1.0 - v[7] as f32,
                srgb_to_linear(v[8] as f32),
                srgb_to_linear(v[9] as f32),
                srgb_to_linear(v[10] as f32),
                v[11] as f32,
            ];
            w.write_all(bytemuck::cast_slice(&a))?;
        }
        Ok(())
    }

    /// After the vertices: the welding table goes, the attributes' file is read back through
    /// a cache, and the tiles' files open.
    fn start_faces(&mut self) -> io::Result<()> {
        let (faces, flags) = self.header.as_ref().map_or((0, 0), |h| (h.faces, h.flags));
        let (temp, tile_triangles) = (self.temp, self.tile_triangles);
        self.by_bits = HashTable::new();
        self.flags = flags;
        if let Some(w) = self.attributes.take() {
            let path = w.finish()?;
            let file = File::open(&path)?;
            let _ = std::fs::remove_file(&path);
            self.cache = Some(BlockCache::new(file, self.remap.len() as u64, CACHE_BYTES));
        }
        let mut side = 1u32;
        while faces.div_ceil(u64::from(side * side)) > tile_triangles.max(1) as u64 && side < 256 {
            side *= 2;
        }
        self.grid = Some(TileGrid::new(&self.positions, side));
        self.owner = vec![NONE; self.positions.len()];
        for t in 0..side * side {
            self.tiles
                .push((temp.create(&format!("tile-{t}"), TILE_BUFFER)?, 0));
        }
        Ok(())
    }

    /// A face: its fan's triangles into their tiles.
    fn fan(&mut self, f: u64, corners: &[u64]) -> Result<(), OocError> {
        let name = self.name;
        let terr = |e| OocError::temp("reading the vertex attributes", e);
        for k in 1..corners.len() - 1 {
            if self.next_index >= MAX_TRIANGLES as u64 {
                return Err(too_large(name, f, self.remap.len() as u64));
            }
            let v = [corners[0], corners[k], corners[k + 1]];
            let mut t = TileTriangle {
                index: self.next_index as u32,
                p: v.map(|i| self.remap[i as usize]),
                ..TileTriangle::default()
            };
            self.next_index += 1;
            if let Some(cache) = &mut self.cache {
                for (c, &i) in v.iter().enumerate() {
                    let a = cache.get(i).map_err(terr)?;
                    t.normal[c] = [a[0], a[1], a[2]];
                    t.uv[c] = [a[3], a[4]];
                    t.color[c] = [a[5], a[6], a[7], a[8]];
                }
            }
            for (bit, flag) in [(0, HAS_NORMAL), (3, HAS_UV), (6, HAS_COLOR)] {
                if self.flags & flag != 0 {
                    t.has |= 0b111 << bit;
                }
            }
            let tile = self
                .grid
                .as_ref()
                .map_or(0, |g| g.tile_of(&self.positions, t.p));
            for &x in &t.p {
                let o = &mut self.owner[x as usize];
                if *o == NONE {
                    *o = tile;
                } else if *o != tile {
                    *o = SHARED;
                }
            }
            let (w, n) = &mut self.tiles[tile as usize];
            w.write_all(bytemuck::bytes_of(&t))
                .map_err(|e| OocError::temp("writing the tiles' files", e))?;
            *n += 1;
        }
        Ok(())
    }
}

//! Vertices converted into the mesh's positions and attributes on all cores, a piece at a
//! time, the first vertex that is not finite reported as converting them in order would.

use rayon::prelude::*;

use super::corners::Corners;
use super::properties::{byte_colour, Vertex};
use crate::base::colour::srgb_to_linear;
use crate::base::ply::{A, NX, R, U, VERTEX_NAMES, X};
use crate::import::error::ImportError;
use crate::mesh::Mesh;

/// Vertices a piece of [`Corners::push_vertices`] converts on one thread.
const VERTEX_PIECE: usize = 1 << 13;

/// The attributes of a piece of vertices, as they are appended to the mesh.
#[derive(Default)]
struct VertexPiece {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    colors: Vec<[f32; 4]>,
}

impl Corners<'_> {
    /// Vertices `0..n` (`vertex(i)` is vertex `i` as read) converted on all cores, a piece
    /// at a time, and appended in order; on a vertex that is not finite, the error of the
    /// first such vertex, as converting them in order would give.
    pub(super) fn push_vertices(
        &self,
        mesh: &mut Mesh,
        n: usize,
        vertex: impl Fn(usize) -> Vertex + Sync,
    ) -> Result<(), ImportError> {
        let pieces: Vec<Result<VertexPiece, usize>> = (0..n.div_ceil(VERTEX_PIECE))
            .into_par_iter()
            .map(|p| self.vertex_piece(p * VERTEX_PIECE..n.min((p + 1) * VERTEX_PIECE), &vertex))
            .collect();
        let present = self.present;
        mesh.positions.reserve(n);
        mesh.normals.reserve(if present.normals { n } else { 0 });
        mesh.uvs.reserve(if present.uvs { n } else { 0 });
        mesh.colors.reserve(if present.colors { n } else { 0 });
        for piece in pieces {
            match piece {
                Ok(piece) => {
                    mesh.positions.extend(piece.positions);
                    mesh.normals.extend(piece.normals);
                    mesh.uvs.extend(piece.uvs);
                    mesh.colors.extend(piece.colors);
                }
                Err(i) => {
                    let names = &VERTEX_NAMES;
                    let at = || format!("vertex {i}");
                    return self.source.check_finite(&vertex(i).values, names, at);
                }
            }
        }
        Ok(())
    }

    /// The vertices `range` converted: position and the attributes present, UV `v`
    /// flipped, colours to linear; or the first that is not finite.
    fn vertex_piece(
        &self,
        range: std::ops::Range<usize>,
        vertex: &(impl Fn(usize) -> Vertex + Sync),
    ) -> Result<VertexPiece, usize> {
        let present = self.present;
        let mut piece = VertexPiece::default();
        piece.positions.reserve(range.len());
        for i in range {
            let v = vertex(i);
            let x = &v.values;
            if !x.iter().all(|c| c.is_finite()) {
                return Err(i);
            }
            piece.positions.push([x[X], x[X + 1], x[X + 2]]);
            if present.normals {
                piece.normals.push([x[NX], x[NX + 1], x[NX + 2]]);
            }
            if present.uvs {
                piece.uvs.push([x[U], 1.0 - x[U + 1]]);
            }
            if present.colors {
                let linear = |c: f32| self.linear(c);
                piece
                    .colors
                    .push([linear(x[R]), linear(x[R + 1]), linear(x[R + 2]), x[A]]);
            }
        }
        Ok(piece)
    }

    /// The sRGB colour channel `c` (in 0..=1) to linear: from the table when `c` is an
    /// 8-bit value as [`Vertex`] stores it (the same number the conversion gives).
    fn linear(&self, c: f32) -> f32 {
        let k = (c * 255.0).round();
        if (0.0..=255.0).contains(&k) && byte_colour(k as usize).to_bits() == c.to_bits() {
            self.byte_linear[k as usize]
        } else {
            srgb_to_linear(c)
        }
    }
}

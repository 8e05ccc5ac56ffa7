//! Hostile meshes straight into the bake, past every importer's checks: the bytes describe a
//! mesh of up to 64 positions (each coordinate a small grid value, so that duplicates,
//! degenerate and coplanar triangles are common, or any finite `f32`), optional normals, UVs
//! and colours per position, up to four surfaces, and triangles over them (repeated corners,
//! duplicates, flipped copies, non-manifold fans all reachable). Whatever validates is baked
//! (`pipeline::bake_mesh`: welder, surface groups, hierarchy builder), written and loaded
//! back: a refused bake must be a typed error, never `BakeError::Invalid`, and what it makes
//! must load.
#![no_main]

use caveclod_bake::mesh::{Mesh, Surface, Triangle, NO_ATTRIBUTE};
use caveclod_bake::pipeline::{bake_mesh, BakeError};
use caveclod_core::Hierarchy;
use libfuzzer_sys::fuzz_target;

/// Reads the bytes front to back, zeros once they run out.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn byte(&mut self) -> u8 {
        let Some((&b, rest)) = self.0.split_first() else {
            return 0;
        };
        self.0 = rest;
        b
    }

    /// A byte with the top bit clear gives a value on a 1/8 grid in -8..8; one with it set
    /// is followed by the four bytes of an `f32`, taken when finite.
    fn number(&mut self) -> f32 {
        let b = self.byte();
        if b & 0x80 == 0 {
            return (f32::from(b) - 64.0) / 8.0;
        }
        let v = f32::from_le_bytes([self.byte(), self.byte(), self.byte(), self.byte()]);
        if v.is_finite() {
            v
        } else {
            0.0
        }
    }
}

fn mesh_of(data: &[u8]) -> Mesh {
    let mut b = Bytes(data);
    let count = 3 + usize::from(b.byte()) % 62;
    let flags = b.byte();
    let surfaces = 1 + usize::from(flags >> 4) % 4;
    let mut mesh = Mesh {
        surfaces: (0..surfaces)
            .map(|s| Surface::plain(format!("s{s}")))
            .collect(),
        ..Mesh::default()
    };
    for _ in 0..count {
        mesh.positions.push([b.number(), b.number(), b.number()]);
        if flags & 1 != 0 {
            mesh.normals.push([b.number(), b.number(), b.number()]);
        }
        if flags & 2 != 0 {
            mesh.uvs.push([b.number(), b.number()]);
        }
        if flags & 4 != 0 {
            let c = (b.number().abs() / 8.0).min(1.0);
            mesh.colors.push([c, 1.0 - c, c, 1.0]);
        }
    }
    let attribute = |on: bool, i: u32| if on { i } else { NO_ATTRIBUTE };
    while !b.0.is_empty() {
        let position = [0; 3].map(|_| (usize::from(b.byte()) % count) as u32);
        let surface = u16::from(b.byte()) % surfaces as u16;
        mesh.triangles.push(Triangle {
            position,
            normal: position.map(|i| attribute(flags & 1 != 0, i)),
            uv: position.map(|i| attribute(flags & 2 != 0, i)),
            color: position.map(|i| attribute(flags & 4 != 0, i)),
            surface,
        });
    }
    mesh
}

fuzz_target!(|data: &[u8]| {
    let mesh = mesh_of(data);
    if mesh.validate().is_err() || mesh.triangles.is_empty() {
        return;
    }
    let baked = match bake_mesh(&mesh, "fuzz", &mut |_| {}) {
        Ok((baked, _)) => baked,
        Err(BakeError::Invalid(e)) => panic!("the baked hierarchy does not validate: {e}"),
        Err(_) => return,
    };
    let bytes = baked.to_bytes(&[]).expect("writing the baked hierarchy");
    let mut words = vec![0u64; bytes.len().div_ceil(8)];
    bytemuck::cast_slice_mut::<u64, u8>(&mut words)[..bytes.len()].copy_from_slice(&bytes);
    let aligned = &bytemuck::cast_slice::<u64, u8>(&words)[..bytes.len()];
    if let Err(e) = Hierarchy::from_bytes(aligned) {
        panic!("the baked file does not load: {e:?}");
    }
});

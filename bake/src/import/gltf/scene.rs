//! The scene's node hierarchy: which nodes are drawn, their world matrices, and how a matrix
//! maps positions and normals.

use super::importer::Importer;
use crate::import::error::{ImportError, Source};

/// Column-major 4 x 4 matrix, as glTF stores it.
pub(super) type Mat4 = [[f64; 4]; 4];

fn mul(a: &Mat4, b: &Mat4) -> Mat4 {
    let mut m = [[0.0; 4]; 4];
    for (c, col) in m.iter_mut().enumerate() {
        for (r, v) in col.iter_mut().enumerate() {
            *v = (0..4).map(|k| a[k][r] * b[c][k]).sum();
        }
    }
    m
}

const IDENTITY: Mat4 = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// The nodes to draw with their world matrices, depth first.
pub(super) fn scene_nodes(
    source: &Source,
    document: &::gltf::Document,
    nodes: &[::gltf::Node<'_>],
) -> Result<Vec<(usize, Mat4)>, ImportError> {
    let roots: Vec<usize> = match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => scene.nodes().map(|n| n.index()).collect(),
        None => {
            let mut is_child = vec![false; nodes.len()];
            for n in nodes {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            (0..nodes.len()).filter(|&i| !is_child[i]).collect()
        }
    };
    let mut visited = vec![false; nodes.len()];
    let mut out = Vec::new();
    let mut stack: Vec<(usize, Mat4)> = roots.into_iter().rev().map(|r| (r, IDENTITY)).collect();
    while let Some((i, parent)) = stack.pop() {
        let node = &nodes[i];
        let name = || match node.name() {
            Some(n) => format!("node {i} ('{n}')"),
            None => format!("node {i}"),
        };
        if std::mem::replace(&mut visited[i], true) {
            return Err(source.malformed(
                name(),
                "appears twice in the scene's node hierarchy (a cycle or a shared child)",
            ));
        }
        let local = node.transform().matrix().map(|c| c.map(f64::from));
        let world = mul(&parent, &local);
        if world.iter().flatten().any(|v| !v.is_finite()) {
            return Err(source.non_finite(name(), "world transform", f64::NAN));
        }
        out.push((i, world));
        let children: Vec<usize> = node.children().map(|c| c.index()).collect();
        for c in children.into_iter().rev() {
            stack.push((c, world));
        }
    }
    Ok(out)
}

impl Importer<'_> {
    /// Every mesh of the scene's nodes, in the world frame; skins counted.
    pub(super) fn add_scene(&mut self, document: &::gltf::Document) -> Result<(), ImportError> {
        let nodes: Vec<::gltf::Node<'_>> = document.nodes().collect();
        for (node, world) in scene_nodes(self.source, document, &nodes)? {
            let n = &nodes[node];
            if n.skin().is_some() {
                self.ignored_skins += 1;
            }
            if let Some(mesh) = n.mesh() {
                self.add_mesh(&mesh, &world)?;
            }
        }
        Ok(())
    }
}

/// A world matrix applied to vertices: positions by its upper 3 x 3 and translation, normals
/// by the cofactor matrix (det * inverse transpose) and renormalized, winding flipped when
/// the determinant is negative.
pub(super) struct Placement<'a> {
    world: &'a Mat4,
    cof: [[f64; 3]; 3],
    /// The determinant is negative: triangles are wound the other way.
    pub(super) flip: bool,
}

impl<'a> Placement<'a> {
    pub(super) fn new(world: &'a Mat4) -> Self {
        let a = |r: usize, c: usize| world[c][r];
        let cof = [
            [
                a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1),
                a(1, 2) * a(2, 0) - a(1, 0) * a(2, 2),
                a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0),
            ],
            [
                a(0, 2) * a(2, 1) - a(0, 1) * a(2, 2),
                a(0, 0) * a(2, 2) - a(0, 2) * a(2, 0),
                a(0, 1) * a(2, 0) - a(0, 0) * a(2, 1),
            ],
            [
                a(0, 1) * a(1, 2) - a(0, 2) * a(1, 1),
                a(0, 2) * a(1, 0) - a(0, 0) * a(1, 2),
                a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0),
            ],
        ];
        let det = a(0, 0) * cof[0][0] + a(0, 1) * cof[0][1] + a(0, 2) * cof[0][2];
        Placement {
            world,
            cof,
            flip: det < 0.0,
        }
    }

    /// Row `r`, column `c` of the world matrix.
    fn a(&self, r: usize, c: usize) -> f64 {
        self.world[c][r]
    }

    pub(super) fn position(&self, p: [f64; 3]) -> [f32; 3] {
        let out: [f64; 3] = std::array::from_fn(|r| {
            (0..3).map(|c| self.a(r, c) * p[c]).sum::<f64>() + self.a(r, 3)
        });
        out.map(|v| v as f32)
    }

    /// The transformed unit normal, or zero when it has no finite direction.
    pub(super) fn normal(&self, n: &[f64]) -> [f32; 3] {
        let sign = if self.flip { -1.0 } else { 1.0 };
        let t: [f64; 3] =
            std::array::from_fn(|r| sign * (0..3).map(|c| self.cof[r][c] * n[c]).sum::<f64>());
        let len = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
        if len > 0.0 && len.is_finite() {
            t.map(|v| (v / len) as f32)
        } else {
            [0.0; 3]
        }
    }
}

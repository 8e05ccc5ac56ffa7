//! A block's mesh as its collapses leave it after any number of them: a level keeps only the
//! first collapses of a block's build, and the stitch reads the triangles each kept collapse
//! found.

use crate::hierarchy::Hierarchy;

const NONE: u32 = u32::MAX;

/// The block's triangles (local ids) with their corners (local nodes) as the collapses
/// applied so far leave them.
pub(super) struct Replay {
    pub(super) corners: Vec<[u32; 3]>,
    pub(super) alive: Vec<bool>,
    /// Live triangles around each node that stands now.
    faces: Vec<Vec<u32>>,
    /// Live triangles.
    pub(super) live: usize,
}

impl Replay {
    /// The block's mesh before any collapse: `corners` of its triangles over its leaves
    /// `0..positions`, with room for the nodes of `collapses` collapses.
    pub(super) fn new(corners: Vec<[u32; 3]>, positions: usize, collapses: usize) -> Self {
        let mut faces = vec![Vec::new(); positions + collapses];
        for (f, c) in corners.iter().enumerate() {
            for &v in c {
                faces[v as usize].push(f as u32);
            }
        }
        Self {
            live: corners.len(),
            alive: vec![true; corners.len()],
            corners,
            faces,
        }
    }

    /// Applies collapse `i` of `local` (creating node `positions + i`).
    pub(super) fn apply(&mut self, local: &Hierarchy, positions: usize, i: usize) {
        let c = local.collapses[i];
        let n = (positions + i) as u32;
        for f in [c.fl, c.fr] {
            if f != NONE && self.alive[f as usize] {
                self.alive[f as usize] = false;
                self.live -= 1;
            }
        }
        let mut around = std::mem::take(&mut self.faces[c.t as usize]);
        around.append(&mut self.faces[c.u as usize]);
        around.retain(|&f| self.alive[f as usize]);
        for &f in &around {
            for v in &mut self.corners[f as usize] {
                if *v == c.t || *v == c.u {
                    *v = n;
                }
            }
        }
        self.faces[n as usize] = around;
    }
}

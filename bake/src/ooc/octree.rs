//! The octree over the sorted soup.
//!
//! Sorting by Morton key made every octree cell a contiguous range of the sorted order, so
//! the octree is a small table of nodes (depth, key prefix, range, children) over the sorted
//! key file ([`super::sort::SortedSoup::keys`]); the triangles stay on disk, in the sorted
//! runs. A node with more than `leaf_triangles` triangles is split into its non-empty
//! children (found by binary searches on the keys, a few reads each) until the maximum depth.
//! Leaves are the units the clustering threads share out and report progress by; a
//! clustering thread merges its leaves' triangles from the runs
//! ([`super::sort::SortedSoup::merge_from`]) and never holds a whole leaf.

use std::fs::File;
use std::os::unix::fs::FileExt;

use super::error::OocError;
use super::soup::{key_prefix, KEY_LEVELS};

/// "No child".
pub const NO_NODE: u32 = u32::MAX;

/// One octree node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Node {
    /// Depth (the root is 0).
    pub depth: u32,
    /// The cell: the key's top `3 * depth` bits.
    pub prefix: u64,
    /// First triangle in the sorted file.
    pub first: u64,
    /// Triangles in the cell.
    pub count: u64,
    /// Children by octant, [`NO_NODE`] where empty; all [`NO_NODE`] for a leaf.
    pub children: [u32; 8],
}

impl Node {
    /// Whether the node is a leaf.
    pub fn is_leaf(&self) -> bool {
        self.children.iter().all(|&c| c == NO_NODE)
    }
}

/// The octree: nodes in depth-first order (a leaf's triangles follow the previous leaf's).
#[derive(Clone, Debug, Default)]
pub struct Octree {
    /// Nodes; the root is node 0.
    pub nodes: Vec<Node>,
    /// Most triangles in one leaf.
    pub largest_leaf: u64,
}

impl Octree {
    /// Builds the octree over a sorted file of `triangles` keys (`u64` each).
    pub fn build(
        keys: &File,
        triangles: u64,
        leaf_triangles: u64,
        max_depth: u32,
    ) -> Result<Self, OocError> {
        let max_depth = max_depth.min(KEY_LEVELS);
        let key_at = |i: u64| -> Result<u64, OocError> {
            let mut b = [0u8; 8];
            keys.read_exact_at(&mut b, i * 8)
                .map_err(|e| OocError::temp("reading the sorted soup", e))?;
            Ok(u64::from_le_bytes(b))
        };
        let mut tree = Octree::default();
        tree.nodes.push(Node {
            depth: 0,
            prefix: 0,
            first: 0,
            count: triangles,
            children: [NO_NODE; 8],
        });
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            let node = tree.nodes[n as usize];
            if node.count <= leaf_triangles || node.depth >= max_depth {
                tree.largest_leaf = tree.largest_leaf.max(node.count);
                continue;
            }
            let d = node.depth + 1;
            let end = node.first + node.count;
            let mut lo = node.first;
            let mut kids = Vec::new();
            for octant in 0..8u64 {
                let prefix = node.prefix << 3 | octant;
                // First index in [lo, end) whose prefix exceeds `prefix`.
                let (mut a, mut b) = (lo, end);
                while a < b {
                    let mid = a + (b - a) / 2;
                    if key_prefix(key_at(mid)?, d) <= prefix {
                        a = mid + 1;
                    } else {
                        b = mid;
                    }
                }
                if a > lo {
                    let id = tree.nodes.len() as u32;
                    tree.nodes.push(Node {
                        depth: d,
                        prefix,
                        first: lo,
                        count: a - lo,
                        children: [NO_NODE; 8],
                    });
                    tree.nodes[n as usize].children[octant as usize] = id;
                    kids.push(id);
                }
                lo = a;
            }
            // Depth-first, octants in order.
            stack.extend(kids.into_iter().rev());
        }
        Ok(tree)
    }

    /// Leaves in file order.
    pub fn leaves(&self) -> Vec<Node> {
        let mut out = Vec::new();
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            let node = self.nodes[n as usize];
            if node.is_leaf() {
                out.push(node);
            } else {
                stack.extend(node.children.iter().rev().filter(|&&c| c != NO_NODE));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn leaves_partition_the_file_and_respect_the_limit() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s");
        let mut keys: Vec<u64> = (0..1000u64)
            .map(|i| (i * 2_654_435_761) % (1 << 63))
            .collect();
        keys.sort_unstable();
        std::fs::File::create(&path)
            .unwrap()
            .write_all(bytemuck::cast_slice(&keys))
            .unwrap();
        let f = File::open(&path).unwrap();
        let t = Octree::build(&f, 1000, 50, 21).unwrap();
        let leaves = t.leaves();
        let mut next = 0;
        for l in &leaves {
            assert_eq!(l.first, next);
            assert!(l.count <= 50);
            for i in l.first..l.first + l.count {
                assert_eq!(key_prefix(keys[i as usize], l.depth), l.prefix);
            }
            next += l.count;
        }
        assert_eq!(next, 1000);
        // Capped depth: leaves may exceed the limit.
        let t = Octree::build(&f, 1000, 50, 1).unwrap();
        assert_eq!(t.leaves().len(), t.nodes.len() - 1);
        assert!(t.largest_leaf > 50);
    }
}

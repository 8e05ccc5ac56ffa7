//! Which page each node's records go to: the top of the hierarchy to the root page, the rest
//! in pages of treelets: a subtree's top [`TREELET_LEVELS`] levels, and as many neighbouring
//! treelets as fit.
//!
//! A node's records are its node record, its split record and bounds, the polygons its split
//! creates, and the position (with its vertex-table entries and vertices) it brings when it
//! is a root or a floating child. A leaf goes to its parent's page.
//!
//! A camera's front cuts across the hierarchy at some depth, and it uses a page's nodes down
//! to the level it crosses there, not the ones below. So a page holds a region's nodes over a
//! narrow band of depths: the nodes below a treelet start treelets of their own, and a page
//! takes the next treelets of the same parent pages while it has room. Runs of the
//! depth-first order, tried first, put a path from a node to its leaves in each page, so a
//! front at a middle depth touched nearly every page; treelets as deep as a page holds left
//! most of each page below the front. A parent always lies in the same or an earlier page, and
//! a page has few parent pages.

use std::collections::VecDeque;

use caveclod_core::format::{Node, Split};
use caveclod_core::Hierarchy;

use super::error::PagedError;

const NONE: u32 = u32::MAX;
/// Bytes a page's nine arrays may lose to alignment.
const PADDING: u64 = 9 * 64;

/// The pages of a hierarchy's records.
pub(crate) struct Partition {
    /// Page of each node, by old id.
    pub home: Vec<u32>,
    /// Node bringing each position, by old position id.
    pub introducer: Vec<u32>,
    /// Pages in all; page 0 is the root page.
    pub pages: u32,
}

/// Bytes of the records that go with node `v` (leaf children not included).
fn own_bytes(h: &Hierarchy<'_>, v: usize, introduces: bool, colours: bool) -> u64 {
    let mut b = 8;
    if let Some(s) = h.splits().get(v) {
        b += 64 + 20 + if s.f_r.is_some() { 20 } else { 0 };
    }
    if introduces {
        let keys = h.vertex_keys(h.nodes()[v].position).len() as u64;
        b += 16 + 4 + keys * (8 + 32 + if colours { 4 } else { 0 });
    }
    b
}

/// The nodes that bring each position: roots, and each split's floating child.
fn introducers(h: &Hierarchy<'_>) -> Result<Vec<u32>, PagedError> {
    let nodes: &[Node] = h.nodes();
    let mut introducer = vec![NONE; h.positions().len()];
    let mut bring = |v: u32| -> Result<(), PagedError> {
        let p = nodes[v as usize].position.0 as usize;
        if introducer[p] != NONE {
            return Err(PagedError::Shape("a position is brought by two nodes"));
        }
        introducer[p] = v;
        Ok(())
    };
    for &r in h.roots() {
        bring(r.0)?;
    }
    for s in h.splits() {
        bring(s.floating.0)?;
    }
    if introducer.contains(&NONE) {
        return Err(PagedError::Shape("a position is brought by no node"));
    }
    Ok(introducer)
}

/// Cuts `h` into pages of at most `page_bytes` (the root page may be larger when the base
/// mesh alone is).
pub(crate) fn partition(h: &Hierarchy<'_>, page_bytes: u32) -> Result<Partition, PagedError> {
    let n = h.nodes().len();
    let splits: &[Split] = h.splits();
    let colours = h.vertex_colours().is_some();
    let introducer = introducers(h)?;
    let introduces = |v: usize| introducer[h.nodes()[v].position.0 as usize] == v as u32;
    // Each node's bytes with its leaf children's, and its depth.
    let mut with_leaves: Vec<u64> = (0..n)
        .map(|v| own_bytes(h, v, introduces(v), colours))
        .collect();
    let mut depth = vec![0u32; n];
    for v in 0..n {
        if let Some(p) = h.nodes()[v].parent.get() {
            depth[v] = depth[p.index()] + 1;
            if v >= splits.len() {
                with_leaves[p.index()] += with_leaves[v];
            }
        }
    }
    let budget = u64::from(page_bytes).saturating_sub(PADDING);
    let root_depth = root_depth(h, &with_leaves, &depth, budget);
    let mut home = vec![NONE; n];
    let mut frontier = VecDeque::new();
    for v in preorder(h) {
        let v = v as usize;
        if depth[v] <= root_depth {
            home[v] = 0;
        } else if h.nodes()[v]
            .parent
            .get()
            .is_none_or(|p| home[p.index()] == 0)
        {
            frontier.push_back(v as u32);
        }
    }
    let pages = Treelets {
        h,
        with_leaves: &with_leaves,
        depth: &depth,
        budget,
    }
    .fill(&mut home, frontier)?;
    if home[..splits.len()].contains(&NONE) {
        return Err(PagedError::Shape("a split is not reachable from the roots"));
    }
    for v in splits.len()..n {
        home[v] = h.nodes()[v].parent.get().map_or(0, |p| home[p.index()]);
    }
    Ok(Partition {
        home,
        introducer,
        pages,
    })
}

/// Levels of a treelet at most: a front uses the nodes of a treelet down to the level it
/// crosses, so short treelets, many to a page, keep more of each page in use.
const TREELET_LEVELS: u32 = 2;

/// Most parent pages a page takes treelets from.
const MAX_PARENT_PAGES: usize = 2;

/// The treelet pages below the root page.
struct Treelets<'a, 'h> {
    h: &'a Hierarchy<'h>,
    with_leaves: &'a [u64],
    depth: &'a [u32],
    budget: u64,
}

impl Treelets<'_, '_> {
    /// Assigns every node of the subtrees below `frontier` (treelet roots in order) a page
    /// after the root page; the number of pages.
    fn fill(&self, home: &mut [u32], mut frontier: VecDeque<u32>) -> Result<u32, PagedError> {
        let splits = self.h.splits();
        let mut page = 0u32;
        let mut filled = self.budget;
        let mut parents: Vec<u32> = Vec::new();
        let mut level = VecDeque::new();
        while let Some(r) = frontier.pop_front() {
            let parent = self.h.nodes()[r as usize]
                .parent
                .get()
                .map_or(0, |p| home[p.index()]);
            let room = filled + self.with_leaves[r as usize] <= self.budget;
            let related = parents.contains(&parent) || parents.len() < MAX_PARENT_PAGES;
            if !(room && related) {
                if self.with_leaves[r as usize] > self.budget {
                    return Err(PagedError::Shape("one node's records exceed a page"));
                }
                page += 1;
                filled = 0;
                parents.clear();
            }
            if !parents.contains(&parent) {
                parents.push(parent);
            }
            // The treelet: breadth first from `r` while the page has room; what does not fit
            // roots treelets of its own.
            level.push_back(r);
            let bottom = self.depth[r as usize] + TREELET_LEVELS;
            while let Some(v) = level.pop_front() {
                let bytes = self.with_leaves[v as usize];
                if self.depth[v as usize] >= bottom {
                    frontier.push_back(v);
                    continue;
                }
                if filled + bytes > self.budget {
                    frontier.push_back(v);
                    frontier.extend(level.drain(..));
                    break;
                }
                filled += bytes;
                home[v as usize] = page;
                let s = &splits[v as usize];
                for c in [s.stationary, s.floating] {
                    if c.index() < splits.len() {
                        level.push_back(c.0);
                    }
                }
            }
        }
        Ok(page + 1)
    }
}

/// The splittable nodes in depth-first preorder from the roots, stationary child first: the
/// first treelets' roots are taken in this order, so neighbouring treelets lie in
/// neighbouring pages whatever order the bake numbered the nodes in (the blocked bake
/// numbers block by block).
fn preorder(h: &Hierarchy<'_>) -> Vec<u32> {
    let splits = h.splits();
    let mut order = Vec::with_capacity(splits.len());
    let mut stack: Vec<u32> = h.roots().iter().rev().map(|r| r.0).collect();
    while let Some(v) = stack.pop() {
        let Some(s) = splits.get(v as usize) else {
            continue;
        };
        order.push(v);
        stack.push(s.floating.0);
        stack.push(s.stationary.0);
    }
    order
}

/// The deepest level whose nodes (with every level above) fit the root page beside the base
/// mesh; the roots are in it whatever their size.
fn root_depth(h: &Hierarchy<'_>, with_leaves: &[u64], depth: &[u32], budget: u64) -> u32 {
    let splits = h.splits().len();
    let mut per_level: Vec<u64> = Vec::new();
    for v in 0..splits {
        let d = depth[v] as usize;
        if per_level.len() <= d {
            per_level.resize(d + 1, 0);
        }
        per_level[d] += with_leaves[v];
    }
    let leaf_roots: u64 = h
        .roots()
        .iter()
        .filter(|r| r.index() >= splits)
        .map(|r| with_leaves[r.index()])
        .sum();
    let mut used =
        20 * h.base_polygon_count() as u64 + leaf_roots + per_level.first().copied().unwrap_or(0);
    let mut d = 0;
    while let Some(&next) = per_level.get(d as usize + 1) {
        if used + next > budget {
            break;
        }
        used += next;
        d += 1;
    }
    d
}

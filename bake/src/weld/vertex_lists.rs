//! Each position's vertices, `(surface group, attribute id)` sorted by group, in one array
//! with a start per position: 12 bytes a position with one vertex, where a vector per
//! position takes 24 for itself and a heap block besides.

use std::ops::Index;

/// Per position, the `(group, attribute id)` of each surface group with a vertex there, by
/// group: `lists[p]` is position `p`'s.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VertexLists {
    /// `start[p]..start[p + 1]` is position `p`'s range of `entries`.
    start: Vec<u32>,
    entries: Vec<(u32, u32)>,
}

impl Default for VertexLists {
    fn default() -> Self {
        Self {
            start: vec![0],
            entries: Vec::new(),
        }
    }
}

impl VertexLists {
    /// The lists of `positions` positions from `(group, position, attribute id)` triples in
    /// any order, each position's sorted by group.
    pub(super) fn from_entries(
        positions: usize,
        entries: impl Iterator<Item = (u32, u32, u32)> + Clone,
    ) -> Self {
        let mut start = vec![0u32; positions + 1];
        for (_, p, _) in entries.clone() {
            start[p as usize + 1] += 1;
        }
        for p in 0..positions {
            start[p + 1] += start[p];
        }
        let mut fill = start.clone();
        let mut out = vec![(0u32, 0u32); start[positions] as usize];
        for (g, p, a) in entries {
            let at = &mut fill[p as usize];
            out[*at as usize] = (g, a);
            *at += 1;
        }
        for p in 0..positions {
            out[start[p] as usize..start[p + 1] as usize].sort_unstable();
        }
        Self {
            start,
            entries: out,
        }
    }

    /// The lists of `start.len() - 1` positions: position `p`'s is
    /// `entries[start[p]..start[p + 1]]`, sorted by group.
    pub(super) fn from_parts(start: Vec<u32>, entries: Vec<(u32, u32)>) -> Self {
        debug_assert!(start.first() == Some(&0) && start.last() == Some(&(entries.len() as u32)));
        Self { start, entries }
    }

    /// Where each position's list starts in the lists of all positions, and the end:
    /// `starts()[p]..starts()[p + 1]` is position `p`'s range.
    pub fn starts(&self) -> &[u32] {
        &self.start
    }

    /// Every position's list, one after another in position order: position `p`'s is
    /// `entries()[starts()[p]..starts()[p + 1]]`.
    pub fn entries(&self) -> &[(u32, u32)] {
        &self.entries
    }

    /// Number of positions.
    pub fn len(&self) -> usize {
        self.start.len() - 1
    }

    /// Whether there is no position.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The attribute id of `group`'s vertex at position `p` (of the position's first vertex
    /// if the group has none there, which a triangle's corner never asks).
    #[inline]
    pub fn attributes_of(&self, p: usize, group: u32) -> u32 {
        let vs = &self[p];
        vs.iter()
            .find(|&&(g, _)| g == group)
            .or(vs.first())
            .map_or(0, |&(_, a)| a)
    }

    /// Each position's list, in position order.
    pub fn iter(&self) -> Lists<'_> {
        Lists {
            lists: self,
            next: 0,
        }
    }
}

/// The lists of a [`VertexLists`], in position order.
#[derive(Clone, Debug)]
pub struct Lists<'a> {
    lists: &'a VertexLists,
    next: usize,
}

impl<'a> Iterator for Lists<'a> {
    type Item = &'a [(u32, u32)];

    fn next(&mut self) -> Option<&'a [(u32, u32)]> {
        let p = self.next;
        (p < self.lists.len()).then(|| {
            self.next += 1;
            &self.lists[p]
        })
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = self.lists.len() - self.next;
        (left, Some(left))
    }
}

impl ExactSizeIterator for Lists<'_> {}

impl Index<usize> for VertexLists {
    type Output = [(u32, u32)];

    fn index(&self, p: usize) -> &[(u32, u32)] {
        &self.entries[self.start[p] as usize..self.start[p + 1] as usize]
    }
}

impl<'a> IntoIterator for &'a VertexLists {
    type Item = &'a [(u32, u32)];
    type IntoIter = Lists<'a>;

    fn into_iter(self) -> Lists<'a> {
        self.iter()
    }
}

/// Lists from each position's entries in turn (already sorted by group).
impl<L: IntoIterator<Item = (u32, u32)>> FromIterator<L> for VertexLists {
    fn from_iter<I: IntoIterator<Item = L>>(lists: I) -> Self {
        let mut v = Self::default();
        for list in lists {
            v.entries.extend(list);
            v.start.push(v.entries.len() as u32);
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::VertexLists;

    #[test]
    fn entries_in_any_order_give_each_position_its_list_by_group() {
        let entries = [(5, 2, 50), (1, 0, 10), (3, 2, 30), (4, 2, 40), (2, 0, 20)];
        let v = VertexLists::from_entries(4, entries.iter().copied());
        assert_eq!(v.len(), 4);
        assert_eq!(&v[0], &[(1, 10), (2, 20)]);
        assert!(v[1].is_empty());
        assert_eq!(&v[2], &[(3, 30), (4, 40), (5, 50)]);
        assert!(v[3].is_empty());
        let lists: Vec<Vec<(u32, u32)>> = v.iter().map(<[_]>::to_vec).collect();
        let again: VertexLists = lists.iter().map(|l| l.iter().copied()).collect();
        assert_eq!(again, v);
        assert!(VertexLists::default().is_empty());
    }
}

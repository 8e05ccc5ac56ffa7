//! Strongly connected sets of a directed graph (Tarjan's algorithm, iterative).

use std::collections::BTreeSet;

/// The strongly connected sets of two nodes or more of the graph over `0..n` with the given
/// adjacency, each sorted, in the order of their smallest node.
pub fn circles(n: usize, adjacency: &[BTreeSet<usize>]) -> Vec<Vec<usize>> {
    const UNSEEN: usize = usize::MAX;
    let mut index = vec![UNSEEN; n];
    let mut low = vec![0; n];
    let mut on_stack = vec![false; n];
    let mut stack = Vec::new();
    let mut next = 0;
    let mut out = Vec::new();
    for start in 0..n {
        if index[start] != UNSEEN {
            continue;
        }
        // (node, its successors not yet followed)
        let mut work: Vec<(usize, Vec<usize>)> = Vec::new();
        index[start] = next;
        low[start] = next;
        next += 1;
        stack.push(start);
        on_stack[start] = true;
        work.push((start, adjacency[start].iter().rev().copied().collect()));
        while let Some((v, pending)) = work.last_mut() {
            let v = *v;
            if let Some(w) = pending.pop() {
                if index[w] == UNSEEN {
                    index[w] = next;
                    low[w] = next;
                    next += 1;
                    stack.push(w);
                    on_stack[w] = true;
                    work.push((w, adjacency[w].iter().rev().copied().collect()));
                } else if on_stack[w] {
                    low[v] = low[v].min(index[w]);
                }
                continue;
            }
            work.pop();
            if let Some((parent, _)) = work.last() {
                low[*parent] = low[*parent].min(low[v]);
            }
            if low[v] == index[v] {
                let mut set = Vec::new();
                while let Some(w) = stack.pop() {
                    on_stack[w] = false;
                    set.push(w);
                    if w == v {
                        break;
                    }
                }
                if set.len() > 1 {
                    set.sort_unstable();
                    out.push(set);
                }
            }
        }
    }
    out.sort();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circles_are_found_and_chains_are_not() {
        let adj = |edges: &[(usize, usize)], n: usize| {
            let mut a = vec![BTreeSet::new(); n];
            for &(x, y) in edges {
                a[x].insert(y);
            }
            a
        };
        assert!(circles(3, &adj(&[(0, 1), (1, 2)], 3)).is_empty());
        assert_eq!(
            circles(
                5,
                &adj(&[(0, 1), (1, 2), (2, 0), (3, 4), (4, 3), (2, 3)], 5)
            ),
            vec![vec![0, 1, 2], vec![3, 4]]
        );
    }
}

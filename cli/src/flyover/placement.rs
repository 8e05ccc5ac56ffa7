//! Where the camera threads run: each pinned to a core, the cameras shared out so that the
//! cores carry equal work.
//!
//! More camera threads than cores, left to the operating system, go where it puts them (at
//! times several on one core), and any placement that puts the two busiest cameras on one
//! core makes every frame wait for that core. Cameras differ in cost (their routes see
//! fronts of different sizes), so threads are pinned, and the cameras are shared out by the
//! longest-processing-time rule: the busiest camera first, each to the core with the least
//! work so far, by each camera's cost in the sizing flight, or, in interleaved segments, over
//! the segment before (equal costs without either). Pinning by camera index alone would put
//! the two busiest cameras together as often as not; balancing by cost keeps the cores'
//! loads even, which is what a thread per camera gains from.

use core_affinity::CoreId;

/// The cores the process may run on, when there are at least two.
pub struct Cores(Vec<CoreId>);

impl Cores {
    /// The cores available to the process (`None` with fewer than two, or where the
    /// platform does not say: threads are then left to the system).
    pub fn available() -> Option<Self> {
        let ids = core_affinity::get_core_ids()?;
        (ids.len() >= 2).then_some(Self(ids))
    }

    /// How many.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Pins the calling thread to core `k` (of [`len`](Self::len)); `false` if the system
    /// refused, and the thread then runs where the system puts it.
    pub fn pin(&self, k: usize) -> bool {
        self.0
            .get(k % self.0.len().max(1))
            .is_some_and(|&id| core_affinity::set_for_current(id))
    }
}

/// The core of each camera: cameras in order of decreasing cost (ties by index), each to the
/// core with the least cost so far (ties to the lower core).
pub fn balance(costs: &[f64], cores: usize) -> Vec<usize> {
    let cores = cores.max(1);
    let mut order: Vec<usize> = (0..costs.len()).collect();
    order.sort_by(|&a, &b| costs[b].total_cmp(&costs[a]).then(a.cmp(&b)));
    let mut load = vec![0.0f64; cores];
    let mut core_of = vec![0; costs.len()];
    for c in order {
        let k = (0..cores)
            .min_by(|&x, &y| load[x].total_cmp(&load[y]).then(x.cmp(&y)))
            .unwrap_or(0);
        load[k] += costs[c].max(0.0);
        core_of[c] = k;
    }
    core_of
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_busiest_cameras_go_to_different_cores() {
        // The demo's four cameras (µs per frame): 117 + 165 and 125 + 155, not 117 + 125
        // and 165 + 155 as by index.
        assert_eq!(balance(&[117.0, 165.0, 125.0, 155.0], 2), vec![0, 0, 1, 1]);
        // Equal costs: round robin by index.
        assert_eq!(balance(&[1.0; 4], 2), vec![0, 1, 0, 1]);
        // One camera as costly as the others together gets a core of its own.
        assert_eq!(balance(&[1.0, 3.0, 1.0, 1.0], 2), vec![1, 0, 1, 1]);
        assert_eq!(balance(&[2.0, 1.0], 4), vec![0, 1]);
        assert!(balance(&[], 2).is_empty());
    }
}

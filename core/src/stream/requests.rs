//! A frame's requests: the absent parents they need, which of them can load now, and in
//! what order.

use super::residency::{Parents, Residency, ABSENT, LOADING, PLANNED, RESIDENT, STATE_MASK};

impl Residency<'_, '_> {
    /// Adds to this frame's requests the absent parents of every requested page, each at the
    /// largest priority of the pages below it, and marks resident parents as wanted (last
    /// on the eviction list). Pages are taken highest index first from a heap of the
    /// requests; parents are earlier pages, so a parent is raised before it is taken.
    pub(super) fn add_parents(&mut self) {
        let mut len = 0;
        for i in 0..self.requests {
            heap_push(self.w.requests.heap, self.w.requests.page, &mut len, i);
        }
        while let Some(i) = heap_pop(self.w.requests.heap, self.w.requests.page, &mut len) {
            let g = self.w.requests.page[i as usize] as usize;
            let priority = f32::from_bits(self.w.requests.priority[i as usize]);
            let key = self.key_of(g);
            let base = self.w.file_base[key.file as usize] as usize;
            let Some(table) = self.table(key.file) else {
                continue;
            };
            for &p in table.parents(key.page) {
                let q = base + p as usize;
                match self.w.pages.state[q] & STATE_MASK {
                    RESIDENT => self.touch(q),
                    ABSENT => {
                        let new = self.w.pages.wanted[q] != self.frame;
                        if let (Some(j), true) = (self.add_request(q, priority), new) {
                            let r = &mut self.w.requests;
                            heap_push(r.heap, r.page, &mut len, j as u32);
                        }
                    }
                    _ => {}
                }
            }
        }
    }

    /// Puts the requested pages that can load now at the start of the heap array; their
    /// number. A page can load when each parent is resident, loading, or itself loadable
    /// now: a chain of pages loads at once, and each installs after its parents (a
    /// parent's priority is at least its children's and ties go to the earlier page, so
    /// the loads' order puts parents first).
    pub(super) fn gather_loadable(&mut self) -> usize {
        let len = self.requests as usize;
        self.sort_requests_by_page(len);
        let mut n = 0;
        for k in 0..len {
            let i = self.w.requests.heap[k] as usize;
            let g = self.w.requests.page[i] as usize;
            if self.w.pages.state[g] == ABSENT && self.parents_ready(g) {
                self.w.pages.state[g] = PLANNED; // absent (0), and loadable now
                self.w.requests.heap[n] = g as u32;
                n += 1;
            }
        }
        n
    }

    /// Clears the marks [`gather_loadable`](Self::gather_loadable) left on the first
    /// `loadable` pages of the heap array that did not start loading.
    pub(super) fn clear_planned(&mut self, loadable: usize) {
        for k in 0..loadable {
            let g = self.w.requests.heap[k] as usize;
            self.w.pages.state[g] &= !PLANNED;
        }
    }

    /// Sorts the heap array's first `len` entries into the requests' indices in ascending
    /// page order (a heapsort in place).
    fn sort_requests_by_page(&mut self, len: usize) {
        let r = &mut self.w.requests;
        let mut heap_len = 0;
        for i in 0..len {
            heap_push(r.heap, r.page, &mut heap_len, i as u32);
        }
        while let Some(top) = heap_pop(r.heap, r.page, &mut heap_len) {
            r.heap[heap_len] = top;
        }
    }

    /// Orders the first `k` of the `loadable` pages at the start of the heap array by
    /// priority, highest first (ties by page); how many that is.
    pub(super) fn order_by_priority(&mut self, loadable: usize, k: usize) -> usize {
        let chosen = k.min(loadable);
        if chosen == 0 {
            return 0;
        }
        let request = &self.w.pages.request;
        let priority = &self.w.requests.priority;
        let rank = |&a: &u32, &b: &u32| {
            let pa = f32::from_bits(priority[request[a as usize] as usize]);
            let pb = f32::from_bits(priority[request[b as usize] as usize]);
            pb.total_cmp(&pa).then(a.cmp(&b))
        };
        let pages = &mut self.w.requests.heap[..loadable];
        if chosen < loadable {
            pages.select_nth_unstable_by(chosen - 1, rank);
        }
        pages[..chosen].sort_unstable_by(rank);
        chosen
    }

    /// Where the parents of page `g` are.
    pub(super) fn parents_state(&self, g: usize) -> Parents {
        let key = self.key_of(g);
        let base = self.w.file_base[key.file as usize] as usize;
        let Some(t) = self.table(key.file) else {
            return Parents::Gone;
        };
        let mut state = Parents::Resident;
        for &p in t.parents(key.page) {
            match self.w.pages.state[base + p as usize] & STATE_MASK {
                RESIDENT => {}
                LOADING => state = Parents::Loading,
                _ => return Parents::Gone,
            }
        }
        state
    }

    /// `true` if every parent of page `g` is resident, loading, or loadable now.
    fn parents_ready(&self, g: usize) -> bool {
        let key = self.key_of(g);
        let base = self.w.file_base[key.file as usize] as usize;
        self.table(key.file).is_some_and(|t| {
            t.parents(key.page).iter().all(|&p| {
                let q = base + p as usize;
                let state = self.w.pages.state[q];
                state == PLANNED || matches!(state & STATE_MASK, RESIDENT | LOADING)
            })
        })
    }
}

/// Pushes request `i` on the max-heap `heap[..len]`, ordered by `page[i]`.
fn heap_push(heap: &mut [u32], page: &[u32], len: &mut usize, i: u32) {
    let mut at = *len;
    heap[at] = i;
    *len += 1;
    while at > 0 {
        let up = (at - 1) / 2;
        if page[heap[up] as usize] >= page[heap[at] as usize] {
            break;
        }
        heap.swap(up, at);
        at = up;
    }
}

/// Pops the request of the highest page from the max-heap `heap[..len]`.
fn heap_pop(heap: &mut [u32], page: &[u32], len: &mut usize) -> Option<u32> {
    if *len == 0 {
        return None;
    }
    let top = heap[0];
    *len -= 1;
    heap[0] = heap[*len];
    let mut at = 0;
    loop {
        let (l, r) = (2 * at + 1, 2 * at + 2);
        let mut big = at;
        for c in [l, r] {
            if c < *len && page[heap[c] as usize] > page[heap[big] as usize] {
                big = c;
            }
        }
        if big == at {
            return Some(top);
        }
        heap.swap(at, big);
        at = big;
    }
}

//! The slot lists: free slots, and the eviction list of resident pages that nothing holds,
//! least recently wanted first. Both link slots through the slot words, so moving a page is
//! O(1) and nothing is scanned.

use super::config::SlotWords;

/// "No slot" and "no page".
pub(crate) const NONE: u32 = u32::MAX;

/// The two lists' ends.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lists {
    /// First free slot; the free list links through `next`.
    pub free: u32,
    /// The eviction list's first (least recently wanted) and last slots.
    pub head: u32,
    pub tail: u32,
    /// Slots on the free list, and on the eviction list.
    pub free_slots: u32,
    pub evictable: u32,
}

impl Lists {
    /// Every slot free, in order, and nothing to evict.
    pub(crate) fn all_free(slots: &mut SlotWords<'_>) -> Self {
        let n = slots.page.len();
        for s in 0..n {
            slots.page[s] = NONE;
            slots.prev[s] = NONE;
            slots.next[s] = if s + 1 < n { s as u32 + 1 } else { NONE };
        }
        Self {
            free: if n > 0 { 0 } else { NONE },
            head: NONE,
            tail: NONE,
            free_slots: n as u32,
            evictable: 0,
        }
    }

    /// A free slot, taken off the free list.
    pub(crate) fn take_free(&mut self, slots: &mut SlotWords<'_>) -> Option<u32> {
        let s = self.free;
        let next = *slots.next.get(s as usize)?;
        self.free = next;
        self.free_slots -= 1;
        slots.next[s as usize] = NONE;
        Some(s)
    }

    /// Gives slot `s` back to the free list.
    pub(crate) fn put_free(&mut self, slots: &mut SlotWords<'_>, s: u32) {
        slots.page[s as usize] = NONE;
        slots.prev[s as usize] = NONE;
        slots.next[s as usize] = self.free;
        self.free = s;
        self.free_slots += 1;
    }

    /// Appends slot `s` to the eviction list: evicted last.
    pub(crate) fn push_back(&mut self, slots: &mut SlotWords<'_>, s: u32) {
        slots.prev[s as usize] = self.tail;
        slots.next[s as usize] = NONE;
        match slots.next.get_mut(self.tail as usize) {
            Some(n) => *n = s,
            None => self.head = s,
        }
        self.tail = s;
        self.evictable += 1;
    }

    /// Takes slot `s` out of the eviction list.
    pub(crate) fn unlink(&mut self, slots: &mut SlotWords<'_>, s: u32) {
        let (prev, next) = (slots.prev[s as usize], slots.next[s as usize]);
        match slots.next.get_mut(prev as usize) {
            Some(n) => *n = next,
            None => self.head = next,
        }
        match slots.prev.get_mut(next as usize) {
            Some(p) => *p = prev,
            None => self.tail = prev,
        }
        slots.prev[s as usize] = NONE;
        slots.next[s as usize] = NONE;
        self.evictable -= 1;
    }

    /// The least recently wanted slot of the eviction list, taken off it.
    pub(crate) fn pop_front(&mut self, slots: &mut SlotWords<'_>) -> Option<u32> {
        let s = self.head;
        if s == NONE {
            return None;
        }
        self.unlink(slots, s);
        Some(s)
    }
}

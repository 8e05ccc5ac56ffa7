//! Where each active polygon lies in the camera's device index buffer, and which places
//! changed since the host last recorded them: the part of a camera that lets a host edit
//! its index buffers in place instead of rewriting them (see `index_edits`).
//!
//! The index buffer is one region per surface, each drawn by one call over its first `len`
//! places (three indices each). A polygon takes a place when a split (or a reset) creates it
//! and keeps it while it lives, however its slot moves (a collapse filling a hole, a
//! compaction): the camera's slot order and the device's place order are independent, so
//! compacting the camera writes nothing to the device. A collapse frees its pair's places;
//! a free place inside a region is a hole that the host draws as a degenerate triangle
//! until [`Placement::close_holes`] moves the region's last polygon into it, a bounded
//! number per frame. A new polygon takes the lowest hole, or the end of its region.
//!
//! A place is marked when what it must hold changes: a polygon placed or freed there, a
//! corner of its polygon moved, a morph starting or ending on one of its vertices (morphed
//! corners point at morph slots). Marks are a bit per place and a list the caller sized; a
//! list that fills marks the whole buffer, so the next edits rewrite every place and stay
//! exact.
//!
//! Each region holds as many places as the camera has polygon slots, so a surface never
//! runs out of room.

use bytemuck::{Pod, Zeroable};

use super::records::NONE;

/// One surface's places: region `r` is `r × slots .. (r + 1) × slots` of the buffer (every
/// region holds as many places as the camera has slots), drawn over its first `len`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub(crate) struct Region {
    /// Places in use or holes: the draw's count.
    pub len: u32,
    /// Free places below `len`.
    pub holes: u32,
    /// No hole lies below this place (relative to the region's first).
    pub low: u32,
}

pub(crate) const REGION_WORDS: usize = core::mem::size_of::<Region>() / 4;

/// The placement's state besides its arrays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct PlacementScalars {
    /// Entries of the list in use.
    pub listed: u32,
    /// The list overflowed, or the front was rebuilt: every place is to be written.
    pub everything: bool,
}

/// Words of each array: place per slot, slot per place, free and marked bits per place, the
/// list, the regions. All 0 when the camera keeps no placement.
pub(crate) fn words(slots: usize, surfaces: usize, list: usize) -> [usize; 6] {
    if list == 0 {
        return [0; 6];
    }
    let places = slots.saturating_mul(surfaces);
    [
        slots,
        places,
        places.div_ceil(32),
        places.div_ceil(32),
        list,
        surfaces.saturating_mul(REGION_WORDS),
    ]
}

/// The places of one camera's polygons (empty arrays when it keeps none).
#[derive(Debug)]
pub(crate) struct Placement<'m> {
    /// Per slot, its polygon's place, or `NONE`.
    pub place: &'m mut [u32],
    /// Per place, the slot whose polygon lies there, or `NONE` (free).
    pub slot_of: &'m mut [u32],
    /// A bit per place: a hole (free, below its region's `len`).
    pub free: &'m mut [u32],
    /// A bit per place: listed in `list`.
    pub marked: &'m mut [u32],
    /// Marked places, in the order they were marked.
    pub list: &'m mut [u32],
    pub regions: &'m mut [Region],
    pub scalars: PlacementScalars,
}

#[inline]
fn bit(words: &[u32], i: u32) -> bool {
    words
        .get(i as usize / 32)
        .is_some_and(|w| w & (1 << (i % 32)) != 0)
}

#[inline]
fn set_bit(words: &mut [u32], i: u32, on: bool) {
    if let Some(w) = words.get_mut(i as usize / 32) {
        if on {
            *w |= 1 << (i % 32);
        } else {
            *w &= !(1 << (i % 32));
        }
    }
}

impl Placement<'_> {
    /// Whether the camera keeps a placement.
    #[inline]
    pub fn is_on(&self) -> bool {
        !self.list.is_empty()
    }

    /// Places per region: the camera's slots.
    #[inline]
    fn capacity(&self) -> u32 {
        self.place.len() as u32
    }

    /// The first place of region `r`.
    #[inline]
    pub fn first(&self, r: usize) -> u32 {
        r as u32 * self.capacity()
    }

    /// Marks place `p` to be written.
    #[inline]
    pub fn mark(&mut self, p: u32) {
        if self.scalars.everything || bit(self.marked, p) {
            return;
        }
        match self.list.get_mut(self.scalars.listed as usize) {
            Some(e) => {
                *e = p;
                self.scalars.listed += 1;
                set_bit(self.marked, p, true);
            }
            None => self.scalars.everything = true,
        }
    }

    /// Marks every place (the next edits rewrite the whole buffer).
    pub fn mark_everything(&mut self) {
        if self.is_on() {
            self.scalars.everything = true;
        }
    }

    /// Marks the place of `slot`'s polygon, if it has one.
    #[inline]
    pub fn mark_slot(&mut self, slot: u32) {
        if let Some(&p) = self.place.get(slot as usize).filter(|&&p| p != NONE) {
            self.mark(p);
        }
    }

    /// The lowest hole of region `r`, if any.
    fn lowest_hole(&mut self, r: usize) -> Option<u32> {
        let g = *self.regions.get(r)?;
        if g.holes == 0 {
            return None;
        }
        let first = self.first(r);
        let (start, end) = (first + g.low, first + g.len);
        let mut w = start / 32;
        while w * 32 < end {
            let mut bits = *self.free.get(w as usize)?;
            if w == start / 32 {
                bits &= u32::MAX << (start % 32);
            }
            if bits != 0 {
                let p = w * 32 + bits.trailing_zeros();
                if p < end {
                    self.regions[r].low = p - first;
                    return Some(p);
                }
                return None;
            }
            w += 1;
        }
        None
    }

    /// Gives `slot`'s new polygon, of `surface`, a place: the lowest hole of its region, or
    /// the region's end.
    pub fn place_new(&mut self, slot: u32, surface: u16) {
        if !self.is_on() {
            return;
        }
        let r = usize::from(surface);
        let p = match self.lowest_hole(r) {
            Some(p) => {
                set_bit(self.free, p, false);
                self.regions[r].holes -= 1;
                p
            }
            None => match (self.first(r), self.capacity(), self.regions.get_mut(r)) {
                (first, capacity, Some(g)) if g.len < capacity => {
                    g.len += 1;
                    first + g.len - 1
                }
                // A region holds every slot, so this is a camera used on after an
                // inconsistency: the next reset places everything again.
                _ => {
                    self.scalars.everything = true;
                    return;
                }
            },
        };
        if let (Some(s), Some(q)) = (
            self.slot_of.get_mut(p as usize),
            self.place.get_mut(slot as usize),
        ) {
            *s = slot;
            *q = p;
        }
        self.mark(p);
    }

    /// Frees the place of `slot`'s polygon (it leaves the front): the region's end shrinks,
    /// or the place becomes a hole the host draws as nothing.
    pub fn unplace(&mut self, slot: u32) {
        let Some(q) = self.place.get_mut(slot as usize) else {
            return;
        };
        let p = core::mem::replace(q, NONE);
        if p == NONE {
            return;
        }
        if let Some(s) = self.slot_of.get_mut(p as usize) {
            *s = NONE;
        }
        let r = (p / self.capacity()) as usize;
        let first = self.first(r);
        if let Some(g) = self.regions.get_mut(r) {
            if p + 1 == first + g.len {
                g.len -= 1;
            } else {
                set_bit(self.free, p, true);
                g.holes += 1;
                g.low = g.low.min(p - first);
                self.mark(p);
            }
        }
    }

    /// `from`'s polygon now lies in slot `to` (a pair moved); `from` holds none.
    #[inline]
    pub fn move_slot(&mut self, from: u32, to: u32) {
        let p = self
            .place
            .get_mut(from as usize)
            .map_or(NONE, |q| core::mem::replace(q, NONE));
        if let Some(q) = self.place.get_mut(to as usize) {
            *q = p;
        }
        if let Some(s) = self.slot_of.get_mut(p as usize) {
            *s = to;
        }
    }

    /// Slot `slot`'s polygon lies at place `p` (or has none): a compaction moving pairs.
    #[inline]
    pub fn put(&mut self, slot: u32, p: u32) {
        if let Some(q) = self.place.get_mut(slot as usize) {
            *q = p;
            if let Some(s) = self.slot_of.get_mut(p as usize) {
                *s = slot;
            }
        }
    }

    /// Slots `a` and `b` swapped their polygons.
    #[inline]
    pub fn swap_slots(&mut self, a: u32, b: u32) {
        if !self.is_on() {
            return;
        }
        let (pa, pb) = (self.place[a as usize], self.place[b as usize]);
        self.place[a as usize] = pb;
        self.place[b as usize] = pa;
        for (p, s) in [(pa, b), (pb, a)] {
            if let Some(x) = self.slot_of.get_mut(p as usize) {
                *x = s;
            }
        }
    }

    /// Moves the last polygons of each region into its holes, at most `moves` in all, and
    /// trims holes off the regions' ends; the moves made.
    pub fn close_holes(&mut self, moves: u32) -> u32 {
        let mut made = 0;
        for r in 0..self.regions.len() {
            loop {
                self.trim(r);
                if made >= moves {
                    break;
                }
                let Some(hole) = self.lowest_hole(r) else {
                    break;
                };
                let last = self.first(r) + self.regions[r].len - 1;
                let slot = self.slot_of[last as usize];
                set_bit(self.free, hole, false);
                self.slot_of[hole as usize] = slot;
                if let Some(q) = self.place.get_mut(slot as usize) {
                    *q = hole;
                }
                self.slot_of[last as usize] = NONE;
                self.regions[r].holes -= 1;
                self.regions[r].len -= 1;
                self.mark(hole);
                made += 1;
            }
        }
        made
    }

    /// Drops the holes at region `r`'s end.
    fn trim(&mut self, r: usize) {
        let Some(&g) = self.regions.get(r) else {
            return;
        };
        let (mut g, first) = (g, self.first(r));
        while g.len > 0 && g.holes > 0 {
            let last = first + g.len - 1;
            if !bit(self.free, last) {
                break;
            }
            set_bit(self.free, last, false);
            g.len -= 1;
            g.holes -= 1;
        }
        if g.holes == 0 {
            g.low = g.len;
        }
        self.regions[r] = g;
    }

    /// Forgets every place and mark; the regions start empty and everything is to be written
    /// (a reset, which then places the base polygons).
    pub fn clear(&mut self) {
        if !self.is_on() {
            return;
        }
        self.place.fill(NONE);
        self.slot_of.fill(NONE);
        self.free.fill(0);
        self.marked.fill(0);
        self.regions.fill(Region::default());
        self.scalars = PlacementScalars {
            listed: 0,
            everything: true,
        };
    }

    /// Clears the marks once the edits they asked for were handed out.
    pub fn clear_marks(&mut self) {
        if self.scalars.everything {
            self.marked.fill(0);
        } else {
            for &p in &self.list[..self.scalars.listed as usize] {
                set_bit(self.marked, p, false);
            }
        }
        self.scalars = PlacementScalars::default();
    }

    /// Whether place `p` is to be drawn: below its region's `len`.
    #[inline]
    pub fn drawn(&self, p: u32) -> bool {
        let r = (p / self.capacity().max(1)) as usize;
        self.regions
            .get(r)
            .is_some_and(|g| p < self.first(r) + g.len)
    }

    /// The places region `r` draws.
    #[inline]
    pub fn drawn_range(&self, r: usize) -> core::ops::Range<u32> {
        let first = self.first(r);
        first..first + self.regions.get(r).map_or(0, |g| g.len)
    }
}

//! [`FrameLists`]: what a frame's refinement over streamed hierarchies leaves for the pool,
//! and [`Residency::apply`], which hands it over.
//!
//! While cameras refine, the pool is borrowed shared (by each [`StreamedHierarchy`]), so
//! what they change is written here, in the caller's memory: the pages their deferred splits
//! want, with the splits' error excess, and per pool slot how many more (or fewer) front
//! nodes stand on its page. [`Residency::apply`] then wants the pages and moves each page's
//! use count, before [`Residency::schedule`]: a page a front stands on is never evicted, and
//! one the fronts left becomes evictable.
//!
//! [`StreamedHierarchy`]: super::StreamedHierarchy

use super::config::{PoolConfig, PoolError};
use super::fault::StreamError;
use super::residency::Residency;
use crate::ids::PageKey;

/// A page wanted by a deferred split, and by how much (pixels) its error exceeds the
/// tolerance: the largest over the splits that wanted it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Want {
    /// The page.
    pub page: PageKey,
    /// The largest screen-space error excess of the splits waiting for it, in pixels.
    pub excess_px: f32,
}

/// What refinement over streamed hierarchies read and asked for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StreamedReads {
    /// Entries put in the wants list.
    pub wanted: u32,
    /// Wants that did not fit the list (asked again by a later frame).
    pub wants_dropped: u32,
    /// Reads of a record in a page that is not resident: refinement defers before it reads,
    /// so this stays 0 (it is counted to prove it).
    pub absent_reads: u64,
    /// Front nodes that joined or left in a page that is not resident: a camera's
    /// bookkeeping would contradict the pool's, so this stays 0 too.
    pub untracked_uses: u32,
}

/// Words per slot: the change of its page's uses, and whether the slot is listed.
const SLOT_WORDS: usize = 3;

/// A frame's wants and use changes, in caller memory (see the module docs).
pub struct FrameLists<'w> {
    pub(super) wants: &'w mut [Want],
    pub(super) want_len: u32,
    /// Per slot: the change of its page's front uses (`i32` bits).
    pub(super) deltas: &'w mut [u32],
    /// Per slot: 1 while it is in `touched`.
    pub(super) listed: &'w mut [u32],
    /// The slots whose uses changed, `touched_len` of them.
    pub(super) touched: &'w mut [u32],
    pub(super) touched_len: u32,
    pub(super) reads: StreamedReads,
}

impl<'w> FrameLists<'w> {
    /// Words the lists need for a pool of `config`.
    pub fn words_needed(config: &PoolConfig) -> usize {
        (config.slots as usize).saturating_mul(SLOT_WORDS)
    }

    /// Empty lists over `wants` (a few hundred entries hold a frame's) and `words`
    /// ([`words_needed`](Self::words_needed) of them).
    pub fn new(
        config: &PoolConfig,
        wants: &'w mut [Want],
        words: &'w mut [u32],
    ) -> Result<Self, PoolError> {
        let needed = Self::words_needed(config);
        if words.len() < needed {
            return Err(PoolError::TooSmall {
                what: "frame list words",
                needed,
                given: words.len(),
            });
        }
        let slots = config.slots as usize;
        let (deltas, rest) = words.split_at_mut(slots);
        let (listed, rest) = rest.split_at_mut(slots);
        let touched = &mut rest[..slots];
        deltas.fill(0);
        listed.fill(0);
        Ok(Self {
            wants,
            want_len: 0,
            deltas,
            listed,
            touched,
            touched_len: 0,
            reads: StreamedReads::default(),
        })
    }

    /// The pages wanted so far (a page may come more than once; [`Residency::want`] keeps
    /// the largest excess).
    pub fn wants(&self) -> &[Want] {
        &self.wants[..self.want_len as usize]
    }

    /// What was read and asked for since the lists were made.
    pub fn reads(&self) -> StreamedReads {
        self.reads
    }
}

impl Residency<'_, '_> {
    /// Hands a frame's `lists` to the pool (before [`schedule`](Self::schedule)): each
    /// wanted page is [`want`](Self::want)ed, and each slot's page's front uses move by
    /// what the cameras did, so a page a front stands on is kept and one the fronts left
    /// may be evicted. The lists are empty afterwards (their reads are kept).
    ///
    /// [`StreamError::NotInUse`] if the lists would take a page's uses below zero, which
    /// a camera's own bookkeeping never does.
    pub fn apply(&mut self, lists: &mut FrameLists<'_>) -> Result<(), StreamError> {
        let mut result = Ok(());
        for i in 0..lists.touched_len as usize {
            let slot = lists.touched[i] as usize;
            let delta = lists.deltas[slot] as i32;
            lists.deltas[slot] = 0;
            lists.listed[slot] = 0;
            if let Err(e) = self.move_uses(slot as u32, delta) {
                result = Err(e);
            }
        }
        lists.touched_len = 0;
        for i in 0..lists.want_len as usize {
            let w = lists.wants[i];
            self.want(w.page, w.excess_px)?;
        }
        lists.want_len = 0;
        result
    }
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;
    use crate::checksum::checksum64;
    use crate::format::paged::{PageEntry, PageLayout, PageTable};
    use crate::stream::{LoadRequest, PageState};

    const PAGES: usize = 4;
    const SIZE: usize = 128;

    fn entries() -> [PageEntry; PAGES] {
        let size = PageLayout::new([1, 0, 0, 0, 0, 0], false).map_or(0, |l| l.len);
        assert_eq!(size, SIZE);
        core::array::from_fn(|p| PageEntry {
            offset: (SIZE * (p + 1)) as u64,
            checksum: checksum64(&[0u8; SIZE]),
            size: SIZE as u32,
            parents_start: 0,
            parent_count: 0,
            max_error: 1.0,
            bounds_min: [0.0; 3],
            bounds_max: [1.0; 3],
            counts: [1, 0, 0, 0, 0, 0],
            flags: 0,
            reserved: [0; 3],
        })
    }

    /// A frame's lists move the uses of their slots' pages: a page a front stands on stays,
    /// one it left is evicted for a wanted page; a count below zero is refused.
    #[test]
    fn the_lists_keep_what_the_fronts_stand_on() {
        let entries = entries();
        let table = PageTable::new(&entries, &[], (SIZE * (PAGES + 1)) as u64).expect("table");
        let config = PoolConfig {
            max_requests: 4,
            ..PoolConfig::new(2 * SIZE as u64, SIZE as u32, 1, PAGES as u32)
        };
        let mut words = [0u32; 128];
        let mut bytes = [0u64; 2 * SIZE / 8 + 8];
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut bytes);
        let skip = bytes.as_ptr().align_offset(64);
        let mut tables = [None; 1];
        let mut pool = Residency::new(
            config,
            &mut words[..Residency::words_needed(&config)],
            &mut bytes[skip..skip + 2 * SIZE],
            &mut tables,
        )
        .expect("pool");
        pool.add_file(table, 0).expect("file");
        let key = |page| PageKey { file: 0, page };
        let mut loads = [LoadRequest::default(); 2];
        pool.begin_frame();
        pool.want(key(0), 1.0).expect("want");
        pool.want(key(1), 1.0).expect("want");
        assert_eq!(pool.schedule(&mut loads, &mut []).loads, 2);
        for l in loads {
            pool.complete(l.slot, |_, _, _| Ok(())).expect("install");
        }

        let mut wants = [Want::default(); 4];
        let mut list_words = [0u32; 6];
        let mut lists = FrameLists::new(&config, &mut wants, &mut list_words).expect("lists");
        // A front stands twice on page 0 and once on page 1, then leaves page 1; page 2 is
        // wanted.
        let slot = |page| pool.resident_slot(key(page)).expect("resident");
        let (s0, s1) = (slot(0), slot(1));
        for (s, d) in [(s0, 2i32), (s1, 1), (s1, -1)] {
            lists.deltas[s as usize] = (lists.deltas[s as usize] as i32 + d) as u32;
            if lists.listed[s as usize] == 0 {
                lists.listed[s as usize] = 1;
                lists.touched[lists.touched_len as usize] = s;
                lists.touched_len += 1;
            }
        }
        lists.wants[0] = Want {
            page: key(2),
            excess_px: 3.0,
        };
        lists.want_len = 1;
        pool.begin_frame();
        pool.apply(&mut lists).expect("apply");
        assert_eq!((pool.uses(key(0)), pool.uses(key(1))), (Some(2), Some(0)));
        assert!(lists.wants().is_empty());
        let mut evicted = [PageKey::default(); 2];
        let st = pool.schedule(&mut loads, &mut evicted);
        assert_eq!((st.loads, st.evictions, evicted[0]), (1, 1, key(1)));
        assert_eq!(pool.state(key(0)), Some(PageState::Resident));

        // Leaving a page more often than it was stood on is refused, and the count stays 0.
        lists.deltas[s0 as usize] = (-3i32) as u32;
        lists.listed[s0 as usize] = 1;
        lists.touched[0] = s0;
        lists.touched_len = 1;
        assert_eq!(pool.apply(&mut lists), Err(StreamError::NotInUse(key(0))));
        assert_eq!(pool.uses(key(0)), Some(0));
    }
}

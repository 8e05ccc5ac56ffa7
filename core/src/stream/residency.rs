//! [`Residency`]: which pages of which files are in the pool, which are wanted, and what
//! the host should load next.

use super::config::{FileTables, PoolConfig, PoolError, Words};
use super::fault::{FaultKind, InstallError, PageFault, StreamError};
use super::lists::{Lists, NONE};
use crate::checksum::checksum64;
use crate::format::paged::PageTable;
use crate::format::FormatError;
use crate::ids::PageKey;

/// Where a page is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PageState {
    /// Not in the pool.
    Absent,
    /// A slot is reserved and the host is loading it.
    Loading,
    /// In the pool.
    Resident,
    /// Its bytes failed their checks (or could not be read): it stays absent, and so do the
    /// pages below it.
    Failed,
}

pub(super) const ABSENT: u32 = 0;
pub(super) const LOADING: u32 = 1;
pub(super) const RESIDENT: u32 = 2;
const FAILED: u32 = 3;
/// Set in a page's state word while its slot is on the eviction list.
const EVICTABLE: u32 = 4;
pub(super) const STATE_MASK: u32 = 3;
/// Set in a pinned page's state word: resident outside the pool, never evicted.
pub(super) const PINNED: u32 = 8;
/// Set, during a [`Residency::schedule`], in an absent page's state word that can load now.
pub(super) const PLANNED: u32 = 16;

/// Where a page's parents are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Parents {
    /// All resident.
    Resident,
    /// All resident or loading, some loading.
    Loading,
    /// Some absent or failed.
    Gone,
}

/// What [`Residency::want`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wanted {
    /// The page is resident: use it.
    Resident,
    /// The page is loading or now requested: defer what needs it.
    Requested,
    /// The page failed: what needs it stays at the coarser level.
    Failed,
    /// This frame's requests are full ([`PoolConfig::max_requests`]); ask again next frame.
    Dropped,
}

/// "Load page `key` into slot `slot`": bytes `offset..offset + size` of its file go to
/// [`Residency::loading_slot_mut`]`(slot)`, then [`Residency::complete`] or
/// [`Residency::fail`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadRequest {
    /// The page.
    pub key: PageKey,
    /// The slot reserved for it.
    pub slot: u32,
    /// Where its bytes start in its file.
    pub offset: u64,
    /// How many bytes.
    pub size: u32,
}

/// What one [`Residency::schedule`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ScheduleStats {
    /// Pages requested this frame, with the absent parents they need.
    pub requested: u32,
    /// Loads issued.
    pub loads: u32,
    /// Pages evicted to make room.
    pub evictions: u32,
    /// Loadable pages left for a later frame (no room in `loads`, or no slot to take).
    pub waiting: u32,
    /// Requested pages waiting for a parent to arrive.
    pub blocked: u32,
    /// Requests past [`PoolConfig::max_requests`], dropped.
    pub dropped: u32,
}

/// Totals since the pool was made.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PoolStats {
    /// Pages resident now.
    pub resident: u32,
    /// Pages loading now.
    pub loading: u32,
    /// Pages that failed.
    pub failed: u32,
    /// Pages installed.
    pub installs: u64,
    /// Bytes installed.
    pub bytes_installed: u64,
    /// Pages evicted.
    pub evictions: u64,
    /// Slots free now.
    pub free_slots: u32,
    /// Resident pages nothing holds now (the eviction list): with the free slots, the room
    /// a frame's loads have without touching what the fronts stand on.
    pub evictable: u32,
}

/// The pages of a fixed pool: which are resident, which loading, which wanted this frame,
/// and which may be evicted. All of it in caller memory ([`Residency::words_needed`] words
/// and [`PoolConfig::pool_bytes`] bytes); nothing allocates.
///
/// Two rules make it safe to use: a page is resident only while its parents are (a page is
/// loaded only when its parents are resident, and a page with resident or loading children
/// is never evicted), and a page in use ([`use_page`](Self::use_page)) is never evicted.
pub struct Residency<'a, 'm> {
    pub(super) config: PoolConfig,
    pub(super) tables: FileTables<'a, 'm>,
    pub(super) pool: &'m mut [u8],
    pub(super) w: Words<'m>,
    pub(super) files: u32,
    pub(super) pages: u32,
    pub(super) frame: u32,
    pub(super) requests: u32,
    pub(super) dropped: u32,
    pub(super) lists: Lists,
    pub(super) totals: PoolStats,
    /// The device vertex pool's root region taken by the files added so far.
    pub(super) root_vertices_used: u32,
}

impl<'a, 'm> Residency<'a, 'm> {
    /// Words of bookkeeping a pool of `config` needs.
    pub fn words_needed(config: &PoolConfig) -> usize {
        config.words()
    }

    /// A pool over the caller's `words`, `pool` bytes (64-byte aligned,
    /// [`PoolConfig::pool_bytes`] of them) and one table place per file; every slot free.
    pub fn new(
        config: PoolConfig,
        words: &'m mut [u32],
        pool: &'m mut [u8],
        tables: FileTables<'a, 'm>,
    ) -> Result<Self, PoolError> {
        config.validate()?;
        check_len("pool bytes", config.pool_bytes(), pool.len())?;
        check_len("file tables", config.files as usize, tables.len())?;
        if pool.as_ptr() as usize % 64 != 0 {
            return Err(PoolError::Misaligned);
        }
        let mut w = Words::cut(&config, words)?;
        let lists = Lists::all_free(&mut w.slots);
        w.pages.slot.fill(NONE);
        w.pages.state.fill(ABSENT);
        w.pages.resident.fill(NONE);
        w.pages.uses.fill(0);
        w.pages.children.fill(0);
        w.pages.wanted.fill(0);
        tables.fill(None);
        Ok(Self {
            config,
            tables,
            pool,
            w,
            files: 0,
            pages: 0,
            frame: 1,
            requests: 0,
            dropped: 0,
            lists,
            totals: PoolStats::default(),
            root_vertices_used: 0,
        })
    }

    /// Adds a file's pages to the pool; its index names its pages in [`PageKey::file`]. Its
    /// first `pinned` pages (a paged file's root pages) are resident from now on, outside the
    /// pool: their bytes are the caller's, and they are never evicted.
    pub fn add_file(&mut self, table: PageTable<'a>, pinned: u32) -> Result<u32, PoolError> {
        if self.files >= self.config.files {
            return Err(PoolError::TooManyFiles {
                files: self.config.files,
            });
        }
        let needed = u64::from(self.pages) + table.len() as u64;
        if needed > u64::from(self.config.pages) {
            return Err(PoolError::TooManyPages {
                needed,
                pages: self.config.pages,
            });
        }
        if pinned as usize > table.len() {
            return Err(PoolError::BadConfig {
                what: "more pinned pages than the file has",
            });
        }
        let largest = table.largest_page_from(pinned);
        if largest > self.config.slot_bytes {
            return Err(PoolError::PageTooLarge {
                page_bytes: largest,
                slot_bytes: self.config.slot_bytes,
            });
        }
        let file = self.files;
        self.reserve_vertices(file, &table, pinned)?;
        self.w.file_base[file as usize] = self.pages;
        let base = self.pages as usize;
        self.w.pages.state[base..base + pinned as usize].fill(RESIDENT | PINNED);
        self.tables[file as usize] = Some(table);
        self.files += 1;
        self.pages = needed as u32;
        Ok(file)
    }

    /// The configuration.
    pub fn config(&self) -> &PoolConfig {
        &self.config
    }

    /// Totals since the pool was made.
    pub fn stats(&self) -> PoolStats {
        PoolStats {
            free_slots: self.lists.free_slots,
            evictable: self.lists.evictable,
            ..self.totals
        }
    }

    /// Where page `key` is; `None` for a key the pool does not serve.
    pub fn state(&self, key: PageKey) -> Option<PageState> {
        let g = self.global(key)?;
        Some(match self.w.pages.state[g] & STATE_MASK {
            ABSENT => PageState::Absent,
            LOADING => PageState::Loading,
            RESIDENT => PageState::Resident,
            _ => PageState::Failed,
        })
    }

    /// The bytes of resident page `key` (`None` for a pinned page: those bytes are the
    /// caller's).
    pub fn page_bytes(&self, key: PageKey) -> Option<&[u8]> {
        let g = self.global(key)?;
        if self.w.pages.state[g] & STATE_MASK != RESIDENT {
            return None;
        }
        let size = self.entry_size(key)?;
        self.slot_range(self.w.pages.slot[g], size)
            .and_then(|r| self.pool.get(r))
    }

    /// Starts a frame: the previous frame's requests are forgotten (loads in flight go on).
    pub fn begin_frame(&mut self) {
        self.frame = self.frame.wrapping_add(1);
        if self.frame == 0 {
            // Once in 2³² frames: no page may keep a stamp equal to the new frame's.
            self.w.pages.wanted.fill(0);
            self.frame = 1;
        }
        self.requests = 0;
        self.dropped = 0;
    }

    /// A camera wants page `key`, for a split whose screen-space error exceeds the tolerance
    /// by `excess` (pixels; the largest over the cameras orders the loads).
    pub fn want(&mut self, key: PageKey, excess: f32) -> Result<Wanted, StreamError> {
        let g = self.global(key).ok_or(StreamError::UnknownPage(key))?;
        Ok(match self.w.pages.state[g] & STATE_MASK {
            RESIDENT => {
                self.touch(g);
                Wanted::Resident
            }
            LOADING => Wanted::Requested,
            FAILED => Wanted::Failed,
            _ => match self.add_request(g, excess) {
                Some(_) => Wanted::Requested,
                None => Wanted::Dropped,
            },
        })
    }

    /// A camera's front starts using resident page `key`: it is not evicted until as many
    /// [`release_page`](Self::release_page) calls.
    pub fn use_page(&mut self, key: PageKey) -> Result<(), StreamError> {
        let g = self.global(key).ok_or(StreamError::UnknownPage(key))?;
        if self.w.pages.state[g] & STATE_MASK != RESIDENT {
            return Err(StreamError::NotResident(key));
        }
        self.w.pages.uses[g] = self.w.pages.uses[g].saturating_add(1);
        self.refresh(g);
        Ok(())
    }

    /// Ends one [`use_page`](Self::use_page) of `key`.
    pub fn release_page(&mut self, key: PageKey) -> Result<(), StreamError> {
        let g = self.global(key).ok_or(StreamError::UnknownPage(key))?;
        if self.w.pages.uses[g] == 0 {
            return Err(StreamError::NotInUse(key));
        }
        self.w.pages.uses[g] -= 1;
        self.refresh(g);
        Ok(())
    }

    /// The slot of resident, streamed page `key` (`None` for a page not in the pool, or
    /// pinned: those are never evicted).
    #[inline]
    pub(crate) fn resident_slot(&self, key: PageKey) -> Option<u32> {
        let g = self.global(key)?;
        let slot = self.w.pages.resident[g];
        (slot != NONE).then_some(slot)
    }

    /// The first global index of file `file`'s pages, and how many it has.
    pub(crate) fn file_pages(&self, file: u32) -> Option<(usize, usize)> {
        let table = self.table(file)?;
        Some((self.w.file_base[file as usize] as usize, table.len()))
    }

    /// The slot of global page `g` while it is streamed and resident.
    #[inline]
    pub(crate) fn resident_slot_at(&self, g: usize) -> Option<u32> {
        let slot = *self.w.pages.resident.get(g)?;
        (slot != NONE).then_some(slot)
    }

    /// Moves the uses of the page in `slot` by `delta` (see [`apply`](Self::apply)).
    pub(super) fn move_uses(&mut self, slot: u32, delta: i32) -> Result<(), StreamError> {
        let g = *self
            .w
            .slots
            .page
            .get(slot as usize)
            .ok_or(StreamError::NoSuchSlot { slot })?;
        if g == NONE || delta == 0 {
            return Ok(());
        }
        let g = g as usize;
        let uses = i64::from(self.w.pages.uses[g]) + i64::from(delta);
        self.w.pages.uses[g] = uses.clamp(0, i64::from(u32::MAX)) as u32;
        self.refresh(g);
        if uses < 0 {
            return Err(StreamError::NotInUse(self.key_of(g)));
        }
        Ok(())
    }

    /// Uses of page `key` ([`use_page`](Self::use_page) less releases).
    pub fn uses(&self, key: PageKey) -> Option<u32> {
        self.global(key).map(|g| self.w.pages.uses[g])
    }

    /// Chooses this frame's loads: this frame's requests with the absent parents they need,
    /// the loadable ones (every parent resident) in order of priority, each given a free slot
    /// or the slot of the least recently wanted page that nothing holds. Fills `loads` (as
    /// many as fit) and names each evicted page in `evicted` (no eviction past its room).
    pub fn schedule(
        &mut self,
        loads: &mut [LoadRequest],
        evicted: &mut [PageKey],
    ) -> ScheduleStats {
        self.add_parents();
        let loadable = self.gather_loadable();
        let mut stats = ScheduleStats {
            requested: self.requests,
            blocked: self.requests - loadable as u32,
            dropped: self.dropped,
            ..ScheduleStats::default()
        };
        let chosen = self.order_by_priority(loadable, loads.len());
        for i in 0..chosen {
            let g = self.w.requests.heap[i] as usize;
            let Some(slot) = self.find_slot(evicted, &mut stats) else {
                break;
            };
            if self.parents_state(g) == Parents::Gone {
                // Making room evicted one of its parents (or a parent found no slot): it
                // waits for a later frame.
                self.lists.put_free(&mut self.w.slots, slot);
                continue;
            }
            loads[stats.loads as usize] = self.start_load(g, slot);
            stats.loads += 1;
        }
        self.clear_planned(loadable);
        stats.waiting = loadable as u32 - stats.loads;
        stats
    }

    /// The bytes of slot `slot`, reserved by a [`LoadRequest`], for the host to fill with the
    /// page's `size` bytes.
    pub fn loading_slot_mut(&mut self, slot: u32) -> Result<&mut [u8], StreamError> {
        let (g, key) = self.loading(slot)?;
        let size = self
            .entry_size(key)
            .ok_or(StreamError::NotLoading { slot })?;
        let range = self
            .slot_range(self.w.pages.slot[g], size)
            .ok_or(StreamError::NotLoading { slot })?;
        self.pool
            .get_mut(range)
            .ok_or(StreamError::NotLoading { slot })
    }

    /// The host filled slot `slot`: the page's checksum is checked, then its contents by
    /// `validate` (given the page, its bytes, and this pool to look at its resident parents);
    /// it becomes resident, or fails (reported here, once) and stays absent.
    /// [`install`](Self::install) validates a paged file's page by its root.
    pub fn complete(
        &mut self,
        slot: u32,
        validate: impl FnOnce(PageKey, &[u8], &Self) -> Result<(), FormatError>,
    ) -> Result<PageKey, InstallError> {
        let (g, key) = self.loading(slot).map_err(InstallError::Misuse)?;
        match self.parents_state(g) {
            Parents::Resident => {}
            Parents::Loading => return Err(InstallError::Wait),
            Parents::Gone => {
                self.abandon(g, slot);
                return Err(InstallError::Abandoned(key));
            }
        }
        if let Err(kind) = self.check(key, slot, validate) {
            self.give_up(g, slot);
            return Err(InstallError::Fault(PageFault { key, kind }));
        }
        self.w.pages.state[g] = RESIDENT;
        self.w.pages.resident[g] = slot;
        self.note_arrays(key, slot);
        self.totals.loading -= 1;
        self.totals.resident += 1;
        self.totals.installs += 1;
        self.totals.bytes_installed += u64::from(self.entry_size(key).unwrap_or(0));
        self.refresh(g);
        Ok(key)
    }

    /// The host could not read the page of slot `slot`: it fails, stays absent, and its slot
    /// is free again. The fault to report is returned.
    pub fn fail(&mut self, slot: u32) -> Result<PageFault, StreamError> {
        let (g, key) = self.loading(slot)?;
        self.give_up(g, slot);
        Ok(PageFault {
            key,
            kind: FaultKind::Io,
        })
    }

    fn check(
        &self,
        key: PageKey,
        slot: u32,
        validate: impl FnOnce(PageKey, &[u8], &Self) -> Result<(), FormatError>,
    ) -> Result<(), FaultKind> {
        let entry = self.table(key.file).and_then(|t| t.entry(key.page));
        let Some(entry) = entry else {
            return Err(FaultKind::Io);
        };
        let bytes = self
            .slot_range(slot, entry.size)
            .and_then(|r| self.pool.get(r))
            .ok_or(FaultKind::Io)?;
        let computed = checksum64(bytes);
        if computed != entry.checksum {
            return Err(FaultKind::Checksum {
                stored: entry.checksum,
                computed,
            });
        }
        validate(key, bytes, self).map_err(FaultKind::Content)
    }

    /// A loading page whose parent failed: its slot is freed, its parents lose a child, and
    /// it is absent again.
    fn abandon(&mut self, g: usize, slot: u32) {
        self.give_up(g, slot);
        self.w.pages.state[g] = ABSENT;
        self.totals.failed -= 1;
    }

    /// A loading page failed: its slot is freed, its parents lose a child, it stays failed.
    fn give_up(&mut self, g: usize, slot: u32) {
        self.w.pages.state[g] = FAILED;
        self.w.pages.slot[g] = NONE;
        self.lists.put_free(&mut self.w.slots, slot);
        self.totals.loading -= 1;
        self.totals.failed += 1;
        self.for_parents(g, |r, parent| {
            r.w.pages.children[parent] -= 1;
            r.refresh(parent);
        });
    }

    /// The page loading into `slot`.
    fn loading(&self, slot: u32) -> Result<(usize, PageKey), StreamError> {
        let g = *self
            .w
            .slots
            .page
            .get(slot as usize)
            .ok_or(StreamError::NotLoading { slot })?;
        let loading = self.w.pages.state.get(g as usize) == Some(&LOADING);
        if g == NONE || !loading {
            return Err(StreamError::NotLoading { slot });
        }
        Ok((g as usize, self.key_of(g as usize)))
    }

    /// Reserves `slot` for page `g`: it is loading, and holds its parents.
    fn start_load(&mut self, g: usize, slot: u32) -> LoadRequest {
        self.w.pages.state[g] = LOADING;
        self.w.pages.slot[g] = slot;
        self.w.slots.page[slot as usize] = g as u32;
        self.totals.loading += 1;
        self.for_parents(g, |r, parent| {
            r.w.pages.children[parent] += 1;
            r.refresh(parent);
        });
        let key = self.key_of(g);
        let (offset, size) = self
            .table(key.file)
            .and_then(|t| t.entry(key.page))
            .map_or((0, 0), |e| (e.offset, e.size));
        LoadRequest {
            key,
            slot,
            offset,
            size,
        }
    }

    /// A free slot, or the slot of the least recently wanted evictable page, evicted and
    /// named in `evicted` (`None` when neither exists or `evicted` is full).
    fn find_slot(&mut self, evicted: &mut [PageKey], stats: &mut ScheduleStats) -> Option<u32> {
        if let Some(s) = self.lists.take_free(&mut self.w.slots) {
            return Some(s);
        }
        let out = evicted.get_mut(stats.evictions as usize)?;
        let s = self.lists.pop_front(&mut self.w.slots)?;
        let g = self.w.slots.page[s as usize] as usize;
        *out = self.key_of(g);
        self.w.pages.state[g] = ABSENT;
        self.w.pages.slot[g] = NONE;
        self.w.pages.resident[g] = NONE;
        self.w.slots.page[s as usize] = NONE;
        self.totals.resident -= 1;
        self.totals.evictions += 1;
        stats.evictions += 1;
        self.for_parents(g, |r, parent| {
            r.w.pages.children[parent] -= 1;
            r.refresh(parent);
        });
        Some(s)
    }

    /// Puts page `g` on the eviction list or takes it off, as its state now says.
    pub(super) fn refresh(&mut self, g: usize) {
        let state = self.w.pages.state[g];
        let listed = state & EVICTABLE != 0;
        let evictable = state & (STATE_MASK | PINNED) == RESIDENT
            && self.w.pages.uses[g] == 0
            && self.w.pages.children[g] == 0;
        let slot = self.w.pages.slot[g];
        if evictable && !listed {
            self.lists.push_back(&mut self.w.slots, slot);
            self.w.pages.state[g] = state | EVICTABLE;
        } else if !evictable && listed {
            self.lists.unlink(&mut self.w.slots, slot);
            self.w.pages.state[g] = state & !EVICTABLE;
        }
    }

    /// Page `g` was wanted: on the eviction list, it goes to the end (evicted last).
    pub(super) fn touch(&mut self, g: usize) {
        if self.w.pages.state[g] & EVICTABLE != 0 {
            let slot = self.w.pages.slot[g];
            self.lists.unlink(&mut self.w.slots, slot);
            self.lists.push_back(&mut self.w.slots, slot);
        }
    }

    /// Calls `f` with each parent of page `g`, by global index.
    pub(super) fn for_parents(&mut self, g: usize, mut f: impl FnMut(&mut Self, usize)) {
        let key = self.key_of(g);
        let base = self.w.file_base[key.file as usize] as usize;
        if let Some(table) = self.table(key.file) {
            for &p in table.parents(key.page) {
                f(self, base + p as usize);
            }
        }
    }

    pub(super) fn table(&self, file: u32) -> Option<PageTable<'a>> {
        self.tables.get(file as usize).copied().flatten()
    }

    fn entry_size(&self, key: PageKey) -> Option<u32> {
        self.table(key.file)?.entry(key.page).map(|e| e.size)
    }

    fn slot_range(&self, slot: u32, size: u32) -> Option<core::ops::Range<usize>> {
        if slot >= self.config.slots || size > self.config.slot_bytes {
            return None;
        }
        let start = slot as usize * self.config.slot_bytes as usize;
        Some(start..start + size as usize)
    }

    /// The global index of `key`.
    pub(super) fn global(&self, key: PageKey) -> Option<usize> {
        let table = self.table(key.file)?;
        if key.page as usize >= table.len() {
            return None;
        }
        Some(self.w.file_base[key.file as usize] as usize + key.page as usize)
    }

    /// The key of global page `g`: the last file starting at or before it.
    pub(super) fn key_of(&self, g: usize) -> PageKey {
        let bases = &self.w.file_base[..self.files as usize];
        let file = bases
            .partition_point(|&b| b as usize <= g)
            .saturating_sub(1);
        PageKey {
            file: file as u32,
            page: (g - bases.get(file).copied().unwrap_or(0) as usize) as u32,
        }
    }

    /// Requests page `g` this frame at `priority` (raising an earlier request's); its index
    /// in the requests, `None` if they are full.
    pub(super) fn add_request(&mut self, g: usize, priority: f32) -> Option<usize> {
        let r = &mut self.w.requests;
        if self.w.pages.wanted[g] == self.frame {
            let i = self.w.pages.request[g] as usize;
            let old = f32::from_bits(r.priority[i]);
            r.priority[i] = old.max(priority).to_bits();
            return Some(i);
        }
        let i = self.requests as usize;
        if i >= r.page.len() {
            self.dropped += 1;
            return None;
        }
        r.page[i] = g as u32;
        r.priority[i] = priority.to_bits();
        self.w.pages.wanted[g] = self.frame;
        self.w.pages.request[g] = i as u32;
        self.requests += 1;
        Some(i)
    }
}

fn check_len(what: &'static str, needed: usize, given: usize) -> Result<(), PoolError> {
    if given < needed {
        return Err(PoolError::TooSmall {
            what,
            needed,
            given,
        });
    }
    Ok(())
}

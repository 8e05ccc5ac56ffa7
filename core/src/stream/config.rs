//! What a pool is sized by, where its bookkeeping lies in the caller's words, and why a
//! configuration or its memory was refused.

use crate::format::paged::{PageArray, PageTable};

/// The sizes of a [`Residency`](super::Residency): fixed when it is made, so its memory is
/// the caller's and never grows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PoolConfig {
    /// Bytes a slot holds: a multiple of 64, at least every page's size
    /// ([`PageTable::largest_page`]).
    pub slot_bytes: u32,
    /// Slots in the pool: the pool's bytes are `slots × slot_bytes`.
    pub slots: u32,
    /// Files the pool may serve at once.
    pub files: u32,
    /// Pages over all those files.
    pub pages: u32,
    /// Pages that may be wanted in one frame (requests past it are counted and dropped).
    pub max_requests: u32,
    /// The renderer's device vertex pool, slot for slot beside this pool's bytes; `None`
    /// for a pool that feeds no device pool (index lists then name vertices by their ids).
    pub vertex_pool: Option<VertexPoolLayout>,
}

impl PoolConfig {
    /// A pool of `pool_bytes` in slots of `slot_bytes` for `files` files of `pages` pages
    /// in all, with room for 4,096 requests a frame.
    pub fn new(pool_bytes: u64, slot_bytes: u32, files: u32, pages: u32) -> Self {
        let slots = pool_bytes
            .checked_div(u64::from(slot_bytes))
            .unwrap_or(0)
            .min(u64::from(u32::MAX - 1)) as u32;
        Self {
            slot_bytes,
            slots,
            files,
            pages,
            max_requests: 4096,
            vertex_pool: None,
        }
    }

    /// This pool with a device vertex pool of `layout` beside it (see
    /// [`VertexPoolLayout`]).
    pub fn with_vertex_pool(self, layout: VertexPoolLayout) -> Self {
        Self {
            vertex_pool: Some(layout),
            ..self
        }
    }

    /// The device vertex pool's slots: the first `slots × slot_vertices` vertices (0 without
    /// one).
    pub(crate) fn slot_vertices_total(&self) -> u64 {
        self.vertex_pool
            .map_or(0, |l| u64::from(self.slots) * u64::from(l.slot_vertices))
    }

    /// Words of bookkeeping the pool keeps in the caller's memory
    /// ([`Residency::words_needed`](super::Residency::words_needed)).
    pub(crate) fn words(&self) -> usize {
        let [pages, slots, requests, files] = self.array_words();
        pages
            .saturating_add(slots)
            .saturating_add(requests)
            .saturating_add(files)
    }

    /// Words of the per-page, per-slot, per-request and per-file arrays.
    fn array_words(&self) -> [usize; 4] {
        [
            (self.pages as usize).saturating_mul(PAGE_WORDS),
            (self.slots as usize).saturating_mul(SLOT_WORDS),
            (self.max_requests as usize).saturating_mul(REQUEST_WORDS),
            (self.files as usize).saturating_mul(FILE_WORDS),
        ]
    }

    /// The pool's bytes.
    pub fn pool_bytes(&self) -> usize {
        (self.slots as usize).saturating_mul(self.slot_bytes as usize)
    }

    /// Checks the sizes themselves.
    pub(crate) fn validate(&self) -> Result<(), PoolError> {
        let aligned = self.slot_bytes > 0 && self.slot_bytes % 64 == 0;
        if !aligned || self.slots == 0 || self.slots == u32::MAX {
            return Err(PoolError::BadConfig {
                what: "slot_bytes must be a non-zero multiple of 64 and slots non-zero",
            });
        }
        if self.pages == u32::MAX || self.max_requests == 0 {
            return Err(PoolError::BadConfig {
                what: "pages must be below u32::MAX and max_requests non-zero",
            });
        }
        if let Some(l) = self.vertex_pool {
            let fits = l.slot_vertices > 0
                && self.slot_vertices_total() <= u64::from(l.vertices)
                && l.vertices < u32::MAX / 2;
            if !fits {
                return Err(PoolError::BadConfig {
                    what: "a vertex pool needs slot_vertices > 0 and room for every slot's \
                           vertices within vertices, below 2^31",
                });
            }
        }
        Ok(())
    }
}

/// Bytes of one vertex in the device pool.
const VERTEX_BYTES: u64 = core::mem::size_of::<crate::format::Vertex>() as u64;

/// The shape of a device vertex pool: the page in slot `s` has its vertices at
/// `s × slot_vertices`, and the files' root pages follow the slots (see
/// [`Residency::page_vertices`](super::Residency::page_vertices)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VertexPoolLayout {
    /// Vertices per slot: at least the most any streamed page holds
    /// ([`PageTable::most_vertices_from`](crate::stream::PageTable::most_vertices_from)).
    pub slot_vertices: u32,
    /// Vertices in all: the slots', then room for every file's root vertices
    /// ([`PageTable::vertices_before`](crate::stream::PageTable::vertices_before)). Morph
    /// slots are numbered past them.
    pub vertices: u32,
}

impl VertexPoolLayout {
    /// The layout of a device pool of `bytes` with slots of `slot_vertices` and room for
    /// `root_vertices`, and how many slots it has (the page pool's
    /// [`PoolConfig::slots`](super::PoolConfig::slots)); `None` if not even one slot fits.
    pub fn for_bytes(bytes: u64, slot_vertices: u32, root_vertices: u64) -> Option<(Self, u32)> {
        let vertices = (bytes / VERTEX_BYTES).min(u64::from(u32::MAX / 2 - 1));
        let slots = vertices
            .checked_sub(root_vertices)?
            .checked_div(u64::from(slot_vertices))?;
        let slots = u32::try_from(slots).ok().filter(|&s| s > 0)?;
        let layout = Self {
            slot_vertices,
            vertices: vertices as u32,
        };
        Some((layout, slots))
    }

    /// [`for_bytes`](Self::for_bytes) for a file of `table`, its first `pinned` pages its
    /// roots: slots of its largest streamed page's vertices, room for its roots' vertices.
    pub fn for_file(bytes: u64, table: &PageTable<'_>, pinned: u32) -> Option<(Self, u32)> {
        let roots = table.vertices_before(pinned);
        Self::for_bytes(bytes, table.most_vertices_from(pinned), roots)
    }

    /// The device pool index of vertex `index` of the page in slot `slot`; `None` past the
    /// slot's vertices.
    #[inline]
    pub fn slot_place(&self, slot: u32, index: u32) -> Option<u32> {
        if index >= self.slot_vertices {
            return None;
        }
        slot.checked_mul(self.slot_vertices)?.checked_add(index)
    }

    /// The device pool's bytes.
    pub fn bytes(&self) -> u64 {
        u64::from(self.vertices) * VERTEX_BYTES
    }
}

/// Words per page: its slot, state, front uses, resident or loading children, the frame it
/// was last wanted in, its place in that frame's requests, and its slot again while it is
/// streamed and resident (the one word a record read looks at).
pub(crate) const PAGE_WORDS: usize = 7;
/// Words per slot: its page, the links of the eviction or free list, and where its page's
/// arrays lie (a start and a length in bytes per [`PageArray`]).
pub(crate) const SLOT_WORDS: usize = 3 + ARRAY_WORDS;
/// Words per slot of where its page's arrays lie.
pub(crate) const ARRAY_WORDS: usize = 2 * PageArray::COUNT;
/// Words per request: the page, its priority, and a place in the heap.
pub(crate) const REQUEST_WORDS: usize = 3;
/// Words per file: its first page's global index, and where its root pages' vertices start
/// in the device vertex pool's root region.
pub(crate) const FILE_WORDS: usize = 2;

/// The per-page arrays, by global page index (a file's pages follow its first one's).
pub(crate) struct PageWords<'m> {
    pub slot: &'m mut [u32],
    pub state: &'m mut [u32],
    pub uses: &'m mut [u32],
    pub children: &'m mut [u32],
    pub wanted: &'m mut [u32],
    pub request: &'m mut [u32],
    /// The slot of a streamed, resident page; `NONE` otherwise.
    pub resident: &'m mut [u32],
}

/// The per-slot arrays.
pub(crate) struct SlotWords<'m> {
    pub page: &'m mut [u32],
    pub prev: &'m mut [u32],
    pub next: &'m mut [u32],
    /// [`ARRAY_WORDS`] per slot: each array's start and length in bytes within the slot.
    pub arrays: &'m mut [u32],
}

/// This frame's requests: page, priority (`f32` bits), and the heap of their indices.
pub(crate) struct RequestWords<'m> {
    pub page: &'m mut [u32],
    pub priority: &'m mut [u32],
    pub heap: &'m mut [u32],
}

/// The caller's words cut into the pool's arrays.
pub(crate) struct Words<'m> {
    pub pages: PageWords<'m>,
    pub slots: SlotWords<'m>,
    pub requests: RequestWords<'m>,
    pub file_base: &'m mut [u32],
    /// Per file: its root vertices' start past the device vertex pool's slots.
    pub file_root_vertices: &'m mut [u32],
}

impl<'m> Words<'m> {
    /// Cuts `words` (at least [`PoolConfig::words`] of them) into the arrays.
    pub(crate) fn cut(config: &PoolConfig, words: &'m mut [u32]) -> Result<Self, PoolError> {
        let needed = config.words();
        if words.len() < needed {
            return Err(PoolError::TooSmall {
                what: "words",
                needed,
                given: words.len(),
            });
        }
        let (p, s, r) = (
            config.pages as usize,
            config.slots as usize,
            config.max_requests as usize,
        );
        let mut rest = words;
        let mut take = |n: usize| {
            let (head, tail) = core::mem::take(&mut rest).split_at_mut(n);
            rest = tail;
            head
        };
        Ok(Self {
            pages: PageWords {
                slot: take(p),
                state: take(p),
                uses: take(p),
                children: take(p),
                wanted: take(p),
                request: take(p),
                resident: take(p),
            },
            slots: SlotWords {
                page: take(s),
                prev: take(s),
                next: take(s),
                arrays: take(s * ARRAY_WORDS),
            },
            requests: RequestWords {
                page: take(r),
                priority: take(r),
                heap: take(r),
            },
            file_base: take(config.files as usize),
            file_root_vertices: take(config.files as usize),
        })
    }
}

/// Why a pool could not be made, or a file not added to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PoolError {
    /// The configuration's sizes are unusable.
    BadConfig {
        /// Which rule they break.
        what: &'static str,
    },
    /// Too little memory was given.
    TooSmall {
        /// `"words"`, `"pool bytes"` or `"file tables"`.
        what: &'static str,
        /// How much is needed.
        needed: usize,
        /// How much was given.
        given: usize,
    },
    /// The pool's bytes do not start on a 64-byte boundary, so a page's records could not be
    /// cast in place from its slot.
    Misaligned,
    /// The pool already serves [`PoolConfig::files`] files.
    TooManyFiles {
        /// The configured number.
        files: u32,
    },
    /// Adding the file would pass [`PoolConfig::pages`].
    TooManyPages {
        /// Pages the pool would serve with it.
        needed: u64,
        /// The configured number.
        pages: u32,
    },
    /// The device vertex pool has no room for a file's vertices: a page holds more than a
    /// slot's vertices, or its root pages' vertices pass the room left after the slots.
    VertexPoolTooSmall {
        /// `"a page's vertices"` or `"root vertices"`.
        what: &'static str,
        /// Vertices needed.
        needed: u64,
        /// Room for them.
        room: u64,
    },
    /// A page is larger than a slot.
    PageTooLarge {
        /// The file's largest page, in bytes.
        page_bytes: u32,
        /// [`PoolConfig::slot_bytes`].
        slot_bytes: u32,
    },
}

impl core::fmt::Display for PoolError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BadConfig { what } => write!(f, "page pool: {what}"),
            Self::TooSmall {
                what,
                needed,
                given,
            } => write!(f, "page pool: {given} {what} given, {needed} needed"),
            Self::Misaligned => write!(f, "page pool: its bytes must start on 64 bytes"),
            Self::TooManyFiles { files } => {
                write!(f, "page pool: already serves its {files} files")
            }
            Self::TooManyPages { needed, pages } => {
                write!(
                    f,
                    "page pool: {needed} pages needed, configured for {pages}"
                )
            }
            Self::VertexPoolTooSmall { what, needed, room } => write!(
                f,
                "vertex pool: {what} need {needed} vertices, it has room for {room}"
            ),
            Self::PageTooLarge {
                page_bytes,
                slot_bytes,
            } => write!(
                f,
                "page pool: a page of {page_bytes} bytes does not fit a slot of {slot_bytes}"
            ),
        }
    }
}

impl core::error::Error for PoolError {}

/// The file tables a pool borrows: one per file it may serve.
pub type FileTables<'a, 'm> = &'m mut [Option<PageTable<'a>>];

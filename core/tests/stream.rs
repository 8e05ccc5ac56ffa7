//! The page pool: page tables refused field by field, a chain of pages loaded at once and
//! installed parents first, loads in the order of the priorities, eviction least recently wanted first and never of a page in use or with
//! resident children, bad pages reported once, many files in one pool, and a random soak
//! that checks closure after every step without allocating.

mod counting;

use caveclod_core::format::checksum64;
use caveclod_core::format::paged::PageLayout;
use caveclod_core::stream::{
    FaultKind, InstallError, LoadRequest, PageEntry, PageField, PageKey, PageState, PageTable,
    PoolConfig, PoolError, Residency, StreamError, VertexPoolLayout, Wanted,
};
use caveclod_core::FormatError;
use counting::{allocations, assert_counting};

/// A file of random pages, each with up to three earlier pages as parents.
struct World {
    bytes: Vec<u8>,
    entries: Vec<PageEntry>,
    parents: Vec<u32>,
}

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }
}

fn world(pages: u32, seed: u64) -> World {
    world_of(pages, seed, |_, rng| {
        [1 + rng.below(200) as u32, 0, 0, 0, 0, 0]
    })
}

/// [`world`] with page `p`'s record counts `counts(p, rng)`.
fn world_of(pages: u32, seed: u64, counts: impl Fn(u32, &mut Rng) -> [u32; 6]) -> World {
    let mut rng = Rng(seed | 1);
    let (mut bytes, mut entries, mut parents) = (vec![0u8; 64], Vec::new(), Vec::new());
    for page in 0..pages {
        let counts = counts(page, &mut rng);
        let size = PageLayout::new(counts, false).expect("layout").len as u32;
        let offset = bytes.len() as u64;
        let data: Vec<u8> = (0..size).map(|_| rng.next() as u8).collect();
        bytes.extend_from_slice(&data);
        bytes.resize(bytes.len().next_multiple_of(64), 0);
        let start = parents.len() as u32;
        if page > 0 {
            let mut mine: Vec<u32> = (0..rng.below(4))
                .map(|_| rng.below(u64::from(page)) as u32)
                .collect();
            mine.sort_unstable();
            mine.dedup();
            parents.extend(mine);
        }
        let lo = [rng.below(100) as f32, 0.0, 0.0];
        entries.push(PageEntry {
            offset,
            checksum: checksum64(&data),
            size,
            parents_start: start,
            parent_count: parents.len() as u32 - start,
            max_error: rng.below(10) as f32,
            bounds_min: lo,
            bounds_max: [lo[0] + 1.0, 1.0, 1.0],
            counts,
            flags: 0,
            reserved: [0; 3],
        });
    }
    World {
        bytes,
        entries,
        parents,
    }
}

impl World {
    fn table(&self) -> PageTable<'_> {
        PageTable::new(&self.entries, &self.parents, self.bytes.len() as u64).expect("table")
    }
}

/// Memory for a pool of `slots` slots of 2 KiB over `pages` pages in `files` files.
struct Memory {
    config: PoolConfig,
    words: Vec<u32>,
    pool: Vec<u64>,
}

fn memory(slots: u32, files: u32, pages: u32) -> Memory {
    let config = PoolConfig::new(u64::from(slots) * 2048, 2048, files, pages);
    // Eight-byte words, and a start rounded to 64 by over-allocating and slicing.
    Memory {
        config,
        words: vec![0; Residency::words_needed(&config)],
        pool: vec![0; config.pool_bytes() / 8 + 8],
    }
}

fn pool<'a, 'm>(m: &'m mut Memory, tables: &'m mut [Option<PageTable<'a>>]) -> Residency<'a, 'm> {
    let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut m.pool);
    let skip = bytes.as_ptr().align_offset(64);
    let bytes = &mut bytes[skip..skip + m.config.pool_bytes()];
    Residency::new(m.config, &mut m.words, bytes, tables).expect("pool")
}

/// A pool serving `w` alone.
fn one_file<'a, 'm>(
    m: &'m mut Memory,
    tables: &'m mut [Option<PageTable<'a>>],
    w: &'a World,
) -> Residency<'a, 'm> {
    let mut r = pool(m, tables);
    r.add_file(w.table(), 0).expect("file");
    r
}

/// Serves `loads` from the files, flipping a byte of the pages in `bad`.
fn serve(
    r: &mut Residency<'_, '_>,
    worlds: &[&World],
    loads: &[LoadRequest],
    bad: &[PageKey],
) -> Vec<Result<PageKey, InstallError>> {
    loads
        .iter()
        .map(|l| {
            let w = worlds[l.key.file as usize];
            let slot = r.loading_slot_mut(l.slot).expect("loading slot");
            let src = &w.bytes[l.offset as usize..][..l.size as usize];
            slot.copy_from_slice(src);
            if bad.contains(&l.key) {
                slot[0] ^= 0x40;
            }
            r.complete(l.slot, |_, _, _| Ok(()))
        })
        .collect()
}

/// Every resident or loading page has its parents resident, and the counts agree.
fn check_closure(r: &Residency<'_, '_>, worlds: &[&World], pinned: &[u32]) {
    let (mut resident, mut held) = (0, 0);
    for (file, w) in worlds.iter().enumerate() {
        let t = w.table();
        for page in 0..t.len() as u32 {
            let key = PageKey {
                file: file as u32,
                page,
            };
            let state = r.state(key).expect("known page");
            if matches!(state, PageState::Resident | PageState::Loading) {
                held += u32::from(page >= pinned[file]);
                for &p in t.parents(page) {
                    let parent = PageKey {
                        file: key.file,
                        page: p,
                    };
                    // A resident page's parents are resident; a loading page's may be
                    // loading too (a chain loads at once, and installs parents first).
                    let ok = match r.state(parent) {
                        Some(PageState::Resident) => true,
                        Some(PageState::Loading) => state == PageState::Loading,
                        _ => false,
                    };
                    assert!(ok, "{key:?} is {state:?}, its parent {:?}", r.state(parent));
                }
            }
            let in_pool = page >= pinned[file];
            resident += u32::from(state == PageState::Resident && in_pool);
            if !in_pool {
                assert_eq!(state, PageState::Resident, "{key:?} is pinned");
                continue;
            }
            if r.uses(key).expect("uses") > 0 {
                assert_eq!(state, PageState::Resident, "{key:?} is used");
            }
        }
    }
    assert_eq!(r.stats().resident, resident);
    assert!(held <= r.config().slots);
}

fn key(page: u32) -> PageKey {
    PageKey { file: 0, page }
}

#[test]
fn page_tables_are_refused_field_by_field() {
    let w = world(6, 7);
    let len = w.bytes.len() as u64;
    let refuse = |f: &dyn Fn(&mut Vec<PageEntry>, &mut Vec<u32>), field: PageField| {
        let (mut e, mut p) = (w.entries.clone(), w.parents.clone());
        f(&mut e, &mut p);
        let err = PageTable::new(&e, &p, len).expect_err("refused");
        assert_eq!(err.field, field, "{err}");
        assert!(err.to_string().contains("page 3"), "{err}");
    };
    refuse(&|e, _| e[3].offset += 8, PageField::Offset);
    refuse(&|e, _| e[3].size = 0, PageField::Size);
    refuse(
        &|e, _| e[3].counts[1] = e[3].counts[0] + 1,
        PageField::Counts,
    );
    refuse(&|e, _| e[3].counts[0] += 100, PageField::Counts);
    refuse(&|e, _| e[3].flags = 2, PageField::Counts);
    refuse(&|e, _| e[3].offset = len - 64, PageField::Size);
    refuse(&|e, _| e[3].parents_start = 1000, PageField::Parents);
    refuse(
        &|e, p| {
            e[3].parents_start = p.len() as u32;
            e[3].parent_count = 1;
            p.push(3);
        },
        PageField::Parents,
    );
    refuse(
        &|e, p| {
            e[3].parents_start = p.len() as u32;
            e[3].parent_count = 2;
            p.extend([1, 0]);
        },
        PageField::Parents,
    );
    refuse(&|e, _| e[3].max_error = f32::NAN, PageField::MaxError);
    refuse(&|e, _| e[3].bounds_min[1] = 5.0, PageField::Bounds);
    assert!(PageTable::new(&w.entries, &w.parents, len).is_ok());
}

/// A chain 0 <- 1 <- 2: wanting page 2 loads 0, then 1, then 2, one frame each.
#[test]
fn a_chain_loads_at_once_and_installs_parents_first() {
    let mut w = world(3, 1);
    for (i, e) in w.entries.iter_mut().enumerate() {
        e.parents_start = 0;
        e.parent_count = 0;
        if i > 0 {
            e.parents_start = (i - 1) as u32;
            e.parent_count = 1;
        }
    }
    w.parents = vec![0, 1];
    let mut m = memory(4, 1, 3);
    let mut tables = vec![None; 1];
    let mut r = one_file(&mut m, &mut tables, &w);
    let mut loads = [LoadRequest::default(); 4];
    // The chain loads at once, parents first.
    r.begin_frame();
    assert_eq!(r.want(key(2), 1.0), Ok(Wanted::Requested));
    let stats = r.schedule(&mut loads, &mut []);
    assert_eq!((stats.loads, stats.requested), (3, 3));
    assert_eq!(
        loads[..3].iter().map(|l| l.key).collect::<Vec<_>>(),
        [key(0), key(1), key(2)]
    );
    // A page that arrives before its parent waits, its bytes kept.
    let fill = |r: &mut Residency<'_, '_>, l: &LoadRequest| {
        let src = &w.bytes[l.offset as usize..][..l.size as usize];
        r.loading_slot_mut(l.slot)
            .expect("slot")
            .copy_from_slice(src);
    };
    for l in &loads[..3] {
        fill(&mut r, l);
    }
    let install = |r: &mut Residency<'_, '_>, l: &LoadRequest| r.complete(l.slot, |_, _, _| Ok(()));
    assert_eq!(install(&mut r, &loads[2]), Err(InstallError::Wait));
    assert_eq!(install(&mut r, &loads[0]), Ok(key(0)));
    assert_eq!(install(&mut r, &loads[2]), Err(InstallError::Wait));
    assert_eq!(install(&mut r, &loads[1]), Ok(key(1)));
    assert_eq!(install(&mut r, &loads[2]), Ok(key(2)));
    r.begin_frame();
    assert_eq!(r.want(key(2), 1.0), Ok(Wanted::Resident));
    assert_eq!(
        r.page_bytes(key(2)),
        Some(&w.bytes[w.entries[2].offset as usize..][..w.entries[2].size as usize])
    );
}

#[test]
fn a_page_whose_parent_fails_while_it_loads_is_abandoned() {
    let mut w = world(2, 3);
    w.entries[0].parent_count = 0;
    w.entries[1].parents_start = 0;
    w.entries[1].parent_count = 1;
    w.parents = vec![0];
    let mut m = memory(4, 1, 2);
    let mut tables = vec![None; 1];
    let mut r = one_file(&mut m, &mut tables, &w);
    let mut loads = [LoadRequest::default(); 4];
    r.begin_frame();
    r.want(key(1), 1.0).expect("want");
    assert_eq!(r.schedule(&mut loads, &mut []).loads, 2);
    let fault = r.fail(loads[0].slot).expect("fail");
    assert_eq!((fault.key, fault.kind), (key(0), FaultKind::Io));
    assert_eq!(
        r.complete(loads[1].slot, |_, _, _| Ok(())),
        Err(InstallError::Abandoned(key(1)))
    );
    // Absent, not failed: only the parent was bad; it stays absent with its parent.
    assert_eq!(r.state(key(1)), Some(PageState::Absent));
    assert_eq!((r.stats().failed, r.stats().loading), (1, 0));
    r.begin_frame();
    r.want(key(1), 1.0).expect("want");
    assert_eq!(r.schedule(&mut loads, &mut []).loads, 0);
}

fn flat_world(pages: u32) -> World {
    let mut w = world(pages, 3);
    for e in &mut w.entries {
        e.parent_count = 0;
    }
    w
}

#[test]
fn the_largest_excess_loads_first() {
    let w = flat_world(8);
    let mut m = memory(8, 1, 8);
    let mut tables = vec![None; 1];
    let mut r = one_file(&mut m, &mut tables, &w);
    r.begin_frame();
    for (page, excess) in [(1, 0.5), (5, 3.0), (2, 1.0), (5, 0.1), (7, 2.0)] {
        r.want(key(page), excess).expect("want");
    }
    let mut loads = [LoadRequest::default(); 2];
    let stats = r.schedule(&mut loads, &mut []);
    assert_eq!((stats.loads, stats.waiting, stats.requested), (2, 2, 4));
    assert_eq!([loads[0].key, loads[1].key], [key(5), key(7)]);
}

#[test]
fn eviction_takes_the_least_recently_wanted_page_nothing_holds() {
    let w = flat_world(6);
    let mut m = memory(3, 1, 6);
    let mut tables = vec![None; 1];
    let mut r = one_file(&mut m, &mut tables, &w);
    let mut loads = [LoadRequest::default(); 3];
    r.begin_frame();
    for page in 0..3 {
        r.want(key(page), 1.0).expect("want");
    }
    let n = r.schedule(&mut loads, &mut []).loads as usize;
    serve(&mut r, &[&w], &loads[..n], &[]);
    r.use_page(key(0)).expect("use");
    r.begin_frame();
    assert_eq!(r.want(key(1), 1.0), Ok(Wanted::Resident));
    assert_eq!(r.want(key(3), 1.0), Ok(Wanted::Requested));
    assert_eq!(r.want(key(4), 1.0), Ok(Wanted::Requested));
    let mut evicted = [PageKey::default(); 4];
    let stats = r.schedule(&mut loads, &mut evicted);
    // Page 0 is used; page 2 was wanted longest ago, then page 1.
    assert_eq!(stats.evictions, 2);
    assert_eq!(&evicted[..2], &[key(2), key(1)]);
    serve(&mut r, &[&w], &loads[..2], &[]);
    // Now every slot is held: page 0 is used, 3 and 4 too.
    r.use_page(key(3)).expect("use");
    r.use_page(key(4)).expect("use");
    r.begin_frame();
    r.want(key(5), 9.0).expect("want");
    let stats = r.schedule(&mut loads, &mut evicted);
    assert_eq!((stats.loads, stats.waiting, stats.evictions), (0, 1, 0));
    r.release_page(key(4)).expect("release");
    assert_eq!(r.release_page(key(4)), Err(StreamError::NotInUse(key(4))));
    let stats = r.schedule(&mut loads, &mut evicted);
    assert_eq!((stats.loads, stats.evictions), (1, 1));
    assert_eq!(evicted[0], key(4));
}

#[test]
fn bad_pages_are_reported_once_and_stay_absent() {
    let w = flat_world(4);
    let mut m = memory(4, 1, 4);
    let mut tables = vec![None; 1];
    let mut r = one_file(&mut m, &mut tables, &w);
    let mut loads = [LoadRequest::default(); 4];
    r.begin_frame();
    for page in 0..4 {
        r.want(key(page), 1.0).expect("want");
    }
    let n = r.schedule(&mut loads, &mut []).loads as usize;
    assert_eq!(n, 4);
    // Page 1's bytes are flipped; page 2's contents are refused; page 3 cannot be read.
    let l = loads;
    let slot = r.loading_slot_mut(l[1].slot).expect("slot");
    slot.copy_from_slice(&w.bytes[l[1].offset as usize..][..l[1].size as usize]);
    slot[7] ^= 1;
    let fault = r.complete(l[1].slot, |_, _, _| Ok(()));
    assert!(
        matches!(fault, Err(InstallError::Fault(f)) if matches!(f.kind, FaultKind::Checksum { .. }))
    );
    let slot = r.loading_slot_mut(l[2].slot).expect("slot");
    slot.copy_from_slice(&w.bytes[l[2].offset as usize..][..l[2].size as usize]);
    let refused = FormatError::MissingSection {
        tag: caveclod_core::format::tags::NODES,
    };
    let fault = r.complete(l[2].slot, |_, _, _| Err(refused));
    let Err(InstallError::Fault(f)) = fault else {
        panic!("refused")
    };
    assert_eq!(f.kind, FaultKind::Content(refused));
    assert!(f.to_string().starts_with("file 0: page 2: "), "{f}");
    assert_eq!(r.fail(l[3].slot).map(|f| f.kind), Ok(FaultKind::Io));
    assert_eq!(
        r.complete(l[3].slot, |_, _, _| Ok(())),
        Err(InstallError::Misuse(StreamError::NotLoading {
            slot: l[3].slot
        }))
    );
    serve(&mut r, &[&w], &l[..1], &[]);
    r.begin_frame();
    for page in 1..4 {
        assert_eq!(r.want(key(page), 5.0), Ok(Wanted::Failed));
    }
    let stats = r.schedule(&mut loads, &mut []);
    assert_eq!((stats.loads, stats.requested), (0, 0));
    assert_eq!((r.stats().failed, r.stats().resident), (3, 1));
}

/// A file of pages without parents holding `vertices[p]` vertices each.
fn world_with_vertices(vertices: &[u32]) -> World {
    let mut w = world_of(vertices.len() as u32, 5, |p, _| {
        [1, 0, 0, 0, 0, vertices[p as usize]]
    });
    for e in &mut w.entries {
        e.parent_count = 0;
    }
    w
}

#[test]
fn a_vertex_pool_is_checked_when_made_and_as_files_are_added() {
    let bad = |layout| {
        let config = PoolConfig::new(4 * 2048, 2048, 2, 16).with_vertex_pool(layout);
        let mut m = Memory {
            config,
            words: vec![0; Residency::words_needed(&config)],
            pool: vec![0; config.pool_bytes() / 8 + 8],
        };
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut m.pool);
        let skip = bytes.as_ptr().align_offset(64);
        let bytes = &mut bytes[skip..skip + config.pool_bytes()];
        let mut tables = [None, None];
        Residency::new(config, &mut m.words, bytes, &mut tables).err()
    };
    for layout in [(0, 100), (40, 159)] {
        let (slot_vertices, vertices) = layout;
        assert!(matches!(
            bad(VertexPoolLayout {
                slot_vertices,
                vertices
            }),
            Some(PoolError::BadConfig { .. })
        ));
    }
    // Two root pages of 10 and 20 vertices, streamed pages of at most 40.
    let w = world_with_vertices(&[10, 20, 40, 7, 33]);
    let add = |slot_vertices, vertices| {
        let layout = VertexPoolLayout {
            slot_vertices,
            vertices,
        };
        let mut m = memory(4, 2, 16);
        m.config = m.config.with_vertex_pool(layout);
        m.words.resize(Residency::words_needed(&m.config), 0);
        let mut tables = [None, None];
        let mut r = pool(&mut m, &mut tables);
        [r.add_file(w.table(), 2), r.add_file(w.table(), 2)]
    };
    let too_small = |what, needed, room| Err(PoolError::VertexPoolTooSmall { what, needed, room });
    assert_eq!(
        add(39, 4 * 39 + 60)[0],
        too_small("a page's vertices", 40, 39)
    );
    assert_eq!(add(40, 4 * 40 + 29)[0], too_small("root vertices", 30, 29));
    assert_eq!(
        add(40, 4 * 40 + 30),
        [Ok(0), too_small("root vertices", 30, 0)]
    );
    assert_eq!(add(40, 4 * 40 + 60), [Ok(0), Ok(1)]);
}

#[test]
fn many_files_share_one_pool() {
    let (a, b) = (world(20, 11), world(30, 12));
    let mut m = memory(10, 2, 50);
    let mut tables = vec![None; 2];
    let mut r = pool(&mut m, &mut tables);
    assert_eq!(r.add_file(a.table(), 0), Ok(0));
    assert_eq!(r.add_file(b.table(), 2), Ok(1));
    let mut loads = [LoadRequest::default(); 10];
    let mut evicted = [key(0); 10];
    for frame in 0..40u32 {
        r.begin_frame();
        let file = frame % 2;
        let page = (frame * 7) % if file == 0 { 20 } else { 30 };
        r.want(PageKey { file, page }, 1.0).expect("want");
        let n = r.schedule(&mut loads, &mut evicted).loads as usize;
        for (l, done) in loads[..n]
            .iter()
            .zip(serve(&mut r, &[&a, &b], &loads[..n], &[]))
        {
            assert_eq!(done, Ok(l.key));
            let w = if l.key.file == 0 { &a } else { &b };
            let bytes = r.page_bytes(l.key).expect("resident");
            assert_eq!(checksum64(bytes), w.entries[l.key.page as usize].checksum);
        }
        check_closure(&r, &[&a, &b], &[0, 2]);
    }
    assert!(r.stats().evictions > 0);
}

/// Random wants, uses, releases, bad pages and failed reads over a pool a fifth of the
/// file: closure and the counts hold after every frame, no page in use is evicted, and the
/// frames allocate nothing.
#[test]
fn a_random_soak_keeps_closure_without_allocating() {
    let w = world(300, 5);
    let mut m = memory(60, 1, 300);
    let mut tables = vec![None; 1];
    let mut r = one_file(&mut m, &mut tables, &w);
    let mut loads = [LoadRequest::default(); 16];
    let mut evicted = [key(0); 16];
    let mut used = vec![0u32; 300];
    let mut rng = Rng(99);
    let frames = if cfg!(miri) { 30 } else { 600 };
    assert_counting();
    let before = allocations();
    let mut faults = 0;
    for _ in 0..frames {
        r.begin_frame();
        for _ in 0..20 {
            let page = rng.below(300) as u32;
            let _ = r
                .want(key(page), rng.below(100) as f32 / 10.0)
                .expect("want");
            if r.state(key(page)) == Some(PageState::Resident) && rng.below(3) == 0 {
                r.use_page(key(page)).expect("use");
                used[page as usize] += 1;
            }
        }
        for page in 0..300 {
            if used[page] > 0 && rng.below(4) == 0 {
                r.release_page(key(page as u32)).expect("release");
                used[page] -= 1;
            }
        }
        let stats = r.schedule(&mut loads, &mut evicted);
        for k in &evicted[..stats.evictions as usize] {
            assert_eq!(used[k.page as usize], 0, "{k:?} evicted while used");
        }
        for l in &loads[..stats.loads as usize] {
            let roll = rng.below(50);
            if roll == 0 {
                r.fail(l.slot).expect("fail");
                faults += 1;
                continue;
            }
            let slot = r.loading_slot_mut(l.slot).expect("slot");
            slot.copy_from_slice(&w.bytes[l.offset as usize..][..l.size as usize]);
            if roll == 1 {
                slot[0] ^= 1;
            }
            match r.complete(l.slot, |_, _, _| Ok(())) {
                Ok(k) => assert_eq!(k, l.key),
                Err(InstallError::Fault(f)) => {
                    assert!(matches!(f.kind, FaultKind::Checksum { .. }));
                    faults += 1;
                }
                // A parent loading in the same frame failed just before.
                Err(InstallError::Abandoned(k)) => assert_eq!(k, l.key),
                Err(e) => panic!("{e}"),
            }
        }
        check_closure(&r, &[&w], &[0]);
    }
    assert_eq!(allocations(), before, "the frames allocated");
    assert_eq!(r.stats().failed, faults);
    assert!(r.stats().installs > 60, "{:?}", r.stats());
    assert!(r.stats().evictions > 0, "{:?}", r.stats());
}

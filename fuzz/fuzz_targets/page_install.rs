//! A paged file's root and pages from arbitrary bytes: `PagedRoot::from_bytes` on the root
//! (retried with the header's length and checksum rewritten to match, so mutations reach the
//! checks), then every page streamed through a small pool from the same bytes, each
//! installed with its checks or failed; every installed page's records are then read through
//! its view with the references the checks promise. Any panic is a bug.
#![no_main]

use caveclod_core::format::paged::PagedRoot;
use caveclod_core::format::{checksum64, FileHeader};
use caveclod_core::stream::{LoadRequest, PageKey, PageState, PoolConfig, Residency};
use libfuzzer_sys::fuzz_target;

const HEADER_LEN: usize = size_of::<FileHeader>();

/// Streams every page of `root` from `file` through an eight-slot pool.
fn stream(root: &PagedRoot<'_>, file: &[u8]) {
    let table = root.table();
    let slot_bytes = table.largest_page().next_multiple_of(64).max(64);
    let config = PoolConfig::new(8 * u64::from(slot_bytes), slot_bytes, 1, table.len() as u32);
    let mut words = vec![0u32; Residency::words_needed(&config)];
    let mut pool = vec![0u64; config.pool_bytes() / 8 + 8];
    let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut pool);
    let skip = bytes.as_ptr().align_offset(64);
    let bytes = &mut bytes[skip..skip + config.pool_bytes()];
    let mut tables = vec![None; 1];
    let Ok(mut r) = Residency::new(config, &mut words, bytes, &mut tables) else {
        return;
    };
    if r.add_file(table, root.paged().root_pages).is_err() {
        return;
    }
    let mut loads = [LoadRequest::default(); 8];
    let mut evicted = [PageKey::default(); 8];
    for frame in 0..table.len().min(64) as u32 * 2 {
        r.begin_frame();
        let page = root.paged().root_pages + frame / 2;
        if page < table.len() as u32 {
            let _ = r.want(PageKey { file: 0, page }, 1.0);
        }
        let stats = r.schedule(&mut loads, &mut evicted);
        for l in &loads[..stats.loads as usize] {
            let start = l.offset as usize;
            let src = file.get(start..start.saturating_add(l.size as usize));
            match (src, r.loading_slot_mut(l.slot)) {
                (Some(src), Ok(dst)) if dst.len() == src.len() => {
                    dst.copy_from_slice(src);
                    if r.install(l.slot, root).is_ok() {
                        read_page(&r, root, l.key);
                    }
                }
                _ => {
                    let _ = r.fail(l.slot);
                }
            }
        }
    }
}

/// Reads an installed page's records: their parents' pages are resident, as promised.
fn read_page(r: &Residency<'_, '_>, root: &PagedRoot<'_>, key: PageKey) {
    let Some(view) = r.page_view(key, root) else {
        panic!("an installed page has no view");
    };
    let ids = root.ids();
    for n in view.nodes {
        if let Some(p) = n.parent.get() {
            let parent = PageKey { file: 0, page: ids.page(p.0) };
            assert_eq!(r.state(parent), Some(PageState::Resident));
        }
    }
}

fuzz_target!(|data: &[u8]| {
    if data.len() < HEADER_LEN {
        return;
    }
    let mut words = vec![0u64; data.len().div_ceil(8)];
    let bytes = &mut bytemuck::cast_slice_mut::<u64, u8>(&mut words)[..data.len()];
    bytes.copy_from_slice(data);
    let header: FileHeader = bytemuck::pod_read_unaligned(&bytes[..HEADER_LEN]);
    let root_len = (header.file_len as usize).clamp(HEADER_LEN, bytes.len());
    if PagedRoot::from_bytes(&bytes[..root_len]).is_err() {
        let mut fixed = header;
        fixed.checksum = checksum64(&bytes[HEADER_LEN..root_len]);
        fixed.file_len = root_len as u64;
        bytes[..HEADER_LEN].copy_from_slice(bytemuck::bytes_of(&fixed));
    }
    let bytes = &bytemuck::cast_slice::<u64, u8>(&words)[..data.len()];
    if let Ok(root) = PagedRoot::from_bytes(&bytes[..root_len]) {
        stream(&root, bytes);
    }
});

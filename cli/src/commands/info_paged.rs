//! `caveclod info` of a paged file: what its root says, read without a page; with
//! `--validate-all`, every page read and checked as the pool would check it.

use std::io::Read;
use std::path::Path;
use std::time::Instant;

use caveclod_core::format::{FileHeader, FLAG_PAGED};
use caveclod_io::PagedFile;
use serde_json::{json, Map, Value};

use crate::args::InfoArgs;

/// `true` if `path`'s header says the file is paged (a file that cannot be read is left to
/// the whole-file path, which reports it).
pub fn is_paged(path: &Path) -> bool {
    let mut head = [0u8; core::mem::size_of::<FileHeader>()];
    let read = std::fs::File::open(path).and_then(|mut f| f.read_exact(&mut head));
    read.is_ok() && bytemuck::pod_read_unaligned::<FileHeader>(&head).flags == FLAG_PAGED
}

/// Prints the root's report (and checks every page with `--validate-all`).
pub fn info(a: &InfoArgs) -> Result<(), String> {
    let start = Instant::now();
    let result = report(a, start);
    match (&result, a.json) {
        (Ok(r), true) => println!("{}", Value::Object(r.clone())),
        (Ok(r), false) => {
            println!("{}: valid (paged)", a.file.display());
            for (k, v) in r {
                println!("  {k}: {v}");
            }
        }
        (Err(e), true) => println!("{}", json!({ "valid": false, "error": e })),
        (Err(_), false) => {}
    }
    result.map(|_| ())
}

fn report(a: &InfoArgs, start: Instant) -> Result<Map<String, Value>, String> {
    let file = PagedFile::open(&a.file).map_err(|e| e.to_string())?;
    let root = file.root().map_err(|e| e.to_string())?;
    let opened = start.elapsed().as_secs_f64();
    let (meta, paged, table) = (root.meta(), root.paged(), root.table());
    let mut r = Map::new();
    r.insert("valid".into(), json!(true));
    r.insert("paged".into(), json!(true));
    r.insert("file_bytes".into(), json!(paged.file_len));
    r.insert("root_bytes".into(), json!(file.root_bytes().len()));
    r.insert("pages".into(), json!(table.len()));
    r.insert("root_pages".into(), json!(paged.root_pages));
    r.insert("largest_page_bytes".into(), json!(paged.largest_page));
    r.insert("page_bits".into(), json!(paged.page_bits));
    r.insert("nodes".into(), json!(meta.node_count));
    r.insert("splits".into(), json!(meta.split_count));
    r.insert("polygons".into(), json!(meta.polygon_count));
    r.insert("base_polygons".into(), json!(meta.base_polygon_count));
    r.insert("vertices".into(), json!(meta.vertex_count));
    r.insert("surfaces".into(), json!(meta.surface_count));
    r.insert("bounds_min".into(), json!(meta.bounds_min));
    r.insert("bounds_max".into(), json!(meta.bounds_max));
    r.insert("open_seconds".into(), json!(opened));
    if a.validate_all {
        let checked = file.validate_all().map_err(|e| e.to_string())?;
        r.insert("pages_checked".into(), json!(checked));
        r.insert(
            "validate_seconds".into(),
            json!(start.elapsed().as_secs_f64() - opened),
        );
    }
    Ok(r)
}

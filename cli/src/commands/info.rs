//! `caveclod info`: counts, sizes and validation status of a .clod file.

use caveclod_bake::report::BakeInfo;
use caveclod_core::Hierarchy;
use serde_json::{Map, Value};

use super::load::with_hierarchy;
use crate::args::InfoArgs;
use crate::info as report;

/// Validates the file and prints its report; with `--json`, a file that does not load prints
/// `{"valid": false, "error": …}` (and the command still fails).
pub fn info(a: &InfoArgs) -> Result<(), String> {
    if super::info_paged::is_paged(&a.file) {
        return super::info_paged::info(a);
    }
    let result = with_hierarchy(&a.file, |h| {
        let r = valid_report(h);
        if a.json {
            println!("{}", serde_json::Value::Object(r));
        } else {
            println!("{}: valid\n{}", a.file.display(), report::human(&r));
        }
        Ok(())
    });
    if let (Err(e), true) = (&result, a.json) {
        println!("{}", serde_json::json!({ "valid": false, "error": e }));
    }
    result
}

/// The report of a valid file: [`report::report`] with its bake information, `valid`, and the
/// bake's duration where the file records it.
fn valid_report(h: &Hierarchy<'_>) -> Map<String, Value> {
    let info = BakeInfo::read(h);
    let mut r = report::report(h, info.as_ref());
    r.insert("valid".into(), serde_json::json!(true));
    if let Some(i) = &info {
        r.insert("bake_seconds".into(), serde_json::json!(i.bake_seconds));
    }
    r
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use caveclod_io::{AlignedBytes, ClodFile};

    use super::*;

    /// A file read through a memory map (as `caveclod info` reads it) reports what the same
    /// file read into the heap reports, and the command's report holds the library's.
    #[test]
    fn a_mapped_file_reports_as_a_read_one() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../core/tests/data/terrain6.clod");
        let mapped = ClodFile::open(&path).expect("map");
        assert!(mapped.bytes().is_mapped());
        let read = AlignedBytes::read(&path).expect("read");
        let (hm, hr) = (
            mapped.hierarchy().expect("valid"),
            read.hierarchy().expect("valid"),
        );
        assert_eq!(report::report(&hm, None), report::report(&hr, None));
        let printed = valid_report(&hm);
        for (key, value) in report::report(&hr, None) {
            assert_eq!(printed[&key], value, "{key}");
        }
        assert_eq!(printed["valid"], true);
    }
}

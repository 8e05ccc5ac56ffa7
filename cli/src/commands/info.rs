//! `caveclod info`: counts, sizes and validation status of a .clod file.

use caveclod_bake::report::BakeInfo;
use caveclod_cli::info as report;

use super::with_hierarchy;
use crate::args::InfoArgs;

/// Validates the file and prints its report; with `--json`, a file that does not load prints
/// `{"valid": false, "error": …}` (and the command still fails).
pub fn info(a: &InfoArgs) -> Result<(), String> {
    let result = with_hierarchy(&a.file, |h| {
        let info = BakeInfo::read(h);
        let mut r = report::report(h, info.as_ref());
        r.insert("valid".into(), serde_json::json!(true));
        if let Some(i) = &info {
            r.insert("bake_seconds".into(), serde_json::json!(i.bake_seconds));
        }
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

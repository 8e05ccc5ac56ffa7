//! `caveclod page`: the paged form of a baked file, and what it holds.

use std::path::Path;

use caveclod_io::ClodFile;

use crate::args::PageArgs;
use crate::outputs;

/// Writes the paged form of `a.input` to `a.output`.
pub fn page(a: &PageArgs) -> Result<(), String> {
    outputs::check_file_output(&a.output, &["clod"], "a paged .clod", &[&a.input])?;
    write(&a.input, &a.output, a.page_size, a.json)
}

/// Reads the whole file `input`, writes its paged form with pages of at most `page_size`
/// bytes to `output`, and prints what it holds.
pub fn write(input: &Path, output: &Path, page_size: u64, json: bool) -> Result<(), String> {
    let page_bytes = u32::try_from(page_size)
        .ok()
        .filter(|&b| b >= 4096)
        .ok_or_else(|| format!("--page-size {page_size}: expected 4K to 4G"))?;
    let file = ClodFile::open(input).map_err(|e| e.to_string())?;
    let h = file.hierarchy().map_err(|e| e.to_string())?;
    let options = caveclod_bake::paged::PageOptions { page_bytes };
    let s = caveclod_bake::paged::write_paged(&h, output, &options).map_err(|e| e.to_string())?;
    if json {
        let paged = serde_json::json!({
            "pages": s.pages,
            "largest_page_bytes": s.largest_page,
            "root_bytes": s.root_bytes,
            "file_bytes": s.file_bytes,
            "page_bits": s.page_bits,
        });
        println!("{}", serde_json::json!({ "paged": paged }));
    } else {
        println!(
            "paged {}: {} pages of at most {} bytes, root {} bytes, file {} bytes",
            output.display(),
            s.pages,
            s.largest_page,
            s.root_bytes,
            s.file_bytes
        );
    }
    Ok(())
}

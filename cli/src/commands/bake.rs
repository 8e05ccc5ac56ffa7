//! `caveclod bake`: import, bake (in core or streamed out of core), optionally add g-mesh
//! levels, write the .clod file and print its report.

use caveclod_bake::baked::{BakeWriteError, Baked};
use caveclod_bake::blocked::{BlockedOptions, LevelStats};
use caveclod_bake::clod_file::Inspect;
use caveclod_bake::gmesh::{GMeshData, GMeshOptions};
use caveclod_bake::import::ImportOptions;
use caveclod_bake::ooc::{MultiresOctree, OocOptions, OocStage, OocStats};
use caveclod_bake::pipeline::{
    build_file, build_file_spilled, build_out_of_core, Built, SpilledBuild, Stage,
};
use caveclod_bake::report::BakeInfo;
use caveclod_core::format::ExtraSection;
use caveclod_core::Hierarchy;
use caveclod_io::{ClodBytes, ClodFile};
use serde_json::{json, Map, Value};
use std::path::Path;

use super::progress::Progress;
use crate::args::BakeArgs;
use crate::info as report;
use crate::outputs;

/// What a bake made, in core or out of core, up to the arrays.
struct Made {
    built: Build,
    /// What the report adds.
    extras: Extras,
}

/// A bake up to the arrays: its hierarchy in memory, or a blocked build's with the
/// collapses on disk.
enum Build {
    InMemory(Built),
    Spilled(SpilledBuild),
}

impl Build {
    fn info(&self) -> &BakeInfo {
        match self {
            Build::InMemory(b) => &b.info,
            Build::Spilled(b) => &b.info,
        }
    }

    fn seconds(&self) -> f64 {
        match self {
            Build::InMemory(b) => b.seconds(),
            Build::Spilled(b) => b.seconds(),
        }
    }

    /// Writes the file one array at a time, from the collapses in memory or on disk, and
    /// hands the written file's validated hierarchy to `inspect` before the rename.
    fn write(
        self,
        path: &std::path::Path,
        extra: &[ExtraSection<'_>],
        inspect: Inspect<'_>,
    ) -> Result<u64, BakeWriteError> {
        match self {
            Build::InMemory(b) => b.write_inspected(path, extra, inspect),
            Build::Spilled(b) => b.write_inspected(path, extra, inspect),
        }
    }

    /// The hierarchy in memory (a spilled one read back).
    fn into_built(self, name: &str) -> Result<Built, String> {
        match self {
            Build::InMemory(b) => Ok(b),
            Build::Spilled(b) => b.into_built(name).map_err(|e| e.to_string()),
        }
    }
}

/// What a bake's report adds to the file's, and the extra sections besides the hierarchy.
struct Extras {
    /// The out-of-core simplification's figures (out of core only).
    ooc_stats: Option<OocStats>,
    /// The multiresolution octree (out of core only, when the options ask for it).
    octree: Option<MultiresOctree>,
    /// The levels of a blocked build (blocked only).
    levels: Option<(BlockedOptions, Vec<LevelStats>)>,
}

/// Bakes the input, writes the .clod file, reads it back and prints its report. The output
/// is checked before any work (a `.clod` name, not the input, in a writable directory).
/// Progress goes to stderr: a bar on a terminal, otherwise (or with `--json`) a line every
/// few seconds.
pub fn bake(a: &BakeArgs) -> Result<(), String> {
    check_paths(a)?;
    if let Some(page_size) = a.page_size {
        return bake_paged(a, page_size);
    }
    let bar = Progress::new(
        "{spinner} {msg} [{bar:30}] {pos}/{len} collapses ({elapsed})",
        "collapses",
        a.json,
    )?;
    let mut on_stage = |s: Stage| show_stage(&bar, s);
    let made = if a.out_of_core {
        bake_streamed(a, &mut on_stage)
    } else if a.blocked {
        bake_blocked(a, &mut on_stage)
    } else {
        build_file(
            &a.input,
            &ImportOptions { spacing: a.spacing },
            &mut on_stage,
        )
        .map(|built| Made {
            built: Build::InMemory(built),
            extras: Extras {
                ooc_stats: None,
                octree: None,
                levels: None,
            },
        })
        .map_err(|e| e.to_string())
    };
    bar.finish();
    let Made { built, extras } = made?;
    let r = if a.gmesh {
        let info = write_with_gmesh(a, built, &extras, &bar)?;
        report_released(&a.output, |h| {
            Ok(bake_report(h, &info, &extras, a.memory_budget))
        })?
    } else {
        // The arrays are assembled as they are written.
        show_stage(&bar, Stage::Assemble);
        write_streamed(a, built, &extras)?
    };
    if a.json {
        println!("{}", Value::Object(r));
    } else {
        println!(
            "baked {} -> {}\n{}",
            a.input.display(),
            a.output.display(),
            report::human(&r)
        );
    }
    Ok(())
}

/// [`super::load::with_hierarchy`] for the report on a file that `--gmesh` wrote from arrays
/// validated in memory (the streamed writes report from their own read-back instead), as
/// large as the bake made it: a mapped file's pages are handed back as the validation and the report read them
/// ([`caveclod_bake::clod_file::with_pages_released`]), so the report does not hold the
/// whole file resident.
fn report_released<R>(
    path: &Path,
    f: impl FnOnce(&Hierarchy<'_>) -> Result<R, String>,
) -> Result<R, String> {
    let file = ClodFile::open(path).map_err(|e| e.to_string())?;
    let report = || {
        let h = file.hierarchy().map_err(|e| e.to_string())?;
        f(&h)
    };
    match file.bytes() {
        ClodBytes::Mapped(map) => caveclod_bake::clod_file::with_pages_released(map, report),
        ClodBytes::Owned(_) => report(),
    }
}

/// Bakes the whole-file form beside the output, writes the paged form over the output from
/// it, and removes it.
fn bake_paged(a: &BakeArgs, page_size: u64) -> Result<(), String> {
    let name = a
        .output
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let whole = a
        .output
        .with_file_name(format!(".{name}.{}.whole.clod", std::process::id()));
    let inner = BakeArgs {
        output: whole.clone(),
        page_size: None,
        ..a.clone()
    };
    let result =
        bake(&inner).and_then(|()| super::page::write(&whole, &a.output, page_size, a.json));
    let _ = std::fs::remove_file(&whole);
    result
}

/// The output and the out-of-core temporary directory checked before the bake starts.
fn check_paths(a: &BakeArgs) -> Result<(), String> {
    outputs::check_file_output(&a.output, &["clod"], "a .clod hierarchy", &[&a.input])?;
    if let Some(dir) = &a.temp_dir {
        if !dir.is_dir() {
            return Err(format!(
                "{}: --temp-dir: does not exist or is not a directory; expected an existing \
                 directory",
                dir.display()
            ));
        }
    }
    Ok(())
}

/// Shows the in-core bake's stage (and the collapses done).
fn show_stage(bar: &Progress, s: Stage) {
    match s {
        Stage::Import => bar.show("importing", None),
        Stage::Weld => bar.show("welding", None),
        Stage::Collapse(done, most) => bar.show("hierarchy", Some((done, most))),
        Stage::Assemble => bar.show("assembling", None),
    }
}

/// Simplifies the input out of core, streaming it from disk with a bar of its own, then bakes
/// the simplified mesh in core.
fn bake_streamed(a: &BakeArgs, on_stage: &mut dyn FnMut(Stage)) -> Result<Made, String> {
    fixed_mmap_threshold();
    let options = OocOptions {
        temp_dir: a.temp_dir.clone(),
        target_triangles: a.target_triangles,
        leaf_triangles: a.leaf_triangles,
        ..OocOptions::with_budget(a.memory_budget)
    };
    let ooc_bar = Progress::new(
        "{spinner} {msg} [{bar:30}] {pos}/{len} triangles ({elapsed})",
        "triangles",
        a.json,
    )?;
    let mut on_ooc = |s: OocStage| {
        let (msg, done, total) = match s {
            OocStage::Read(d, t) => ("reading and sorting".to_string(), d, t),
            OocStage::Merge(d, t) => ("merging sorted runs".to_string(), d, t),
            OocStage::Cluster(r, d, t) => (format!("clustering on a {r}^3 grid"), d, t),
        };
        ooc_bar.show(&msg, Some((done, total)));
    };
    let r = build_out_of_core(&a.input, &options, &mut on_ooc, &mut |s| {
        ooc_bar.finish();
        on_stage(s)
    });
    ooc_bar.finish();
    let o = r.map_err(|e| e.to_string())?;
    Ok(Made {
        built: Build::InMemory(o.built),
        extras: Extras {
            ooc_stats: Some(o.stats),
            octree: o.octree,
            levels: None,
        },
    })
}

/// Bytes per input triangle a block's build peaks at (the in-core build's, measured), which
/// sizes the blocks from the memory budget.
const BLOCK_BYTES_PER_TRIANGLE: u64 = 1024;

/// Bakes the input in blocks ([`caveclod_bake::blocked`]), the blocks sized so that as
/// many builds as run at once fit the memory budget.
fn bake_blocked(a: &BakeArgs, on_stage: &mut dyn FnMut(Stage)) -> Result<Made, String> {
    fixed_mmap_threshold();
    let options =
        BlockedOptions::for_budget(a.memory_budget, rayon_threads(), BLOCK_BYTES_PER_TRIANGLE);
    let (built, levels) = build_file_spilled(
        &a.input,
        &ImportOptions { spacing: a.spacing },
        &options,
        on_stage,
    )
    .map_err(|e| e.to_string())?;
    Ok(Made {
        built: Build::Spilled(built),
        extras: Extras {
            ooc_stats: None,
            octree: None,
            levels: Some((options, levels)),
        },
    })
}

/// Threads the blocks of a level are built on.
fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, usize::from)
}

/// Buffers of a megabyte or more straight from the system and back to it when freed. An
/// out-of-core bake allocates and frees buffers of many megabytes (sort chunks, clusters
/// growing on several threads); glibc raises its threshold for that to the largest buffer
/// freed so far, after which freed buffers stay resident in its arenas and count in the
/// peak as if still in use, outside the memory budget. A blocked bake frees its
/// blocks' builds level after level and the welded mesh before the written file is mapped
/// for validation, which then finds them still resident.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn fixed_mmap_threshold() {
    // SAFETY: `mallopt` sets a parameter of glibc's allocator, which takes its own lock; it
    // changes where later allocations come from, not any memory in use.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 1 << 20);
    }
}

/// Other allocators are left as they are.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn fixed_mmap_threshold() {}

/// The g-mesh levels over the baked hierarchy, down to `min_polygons` (the default if `None`).
fn gmesh_levels(baked: &Baked, min_polygons: Option<u32>) -> Result<GMeshData, String> {
    let h = baked.hierarchy().map_err(|e| e.to_string())?;
    let options = GMeshOptions {
        min_polygons: min_polygons.unwrap_or(0),
        ..GMeshOptions::default()
    };
    caveclod_bake::gmesh::build(&h, &options).map_err(|e| e.to_string())
}

/// Writes the file from the welded mesh and the collapses one array at a time
/// ([`Built::write_inspected`], [`SpilledBuild::write_inspected`]), with the bake's report and
/// the multiresolution octree (if any) as extra sections; the mesh and the collapses are
/// dropped once written. Returns the file's report, made from the hierarchy the writer's
/// read-back validated, so the file is validated once and the report describes those bytes.
fn write_streamed(
    a: &BakeArgs,
    built: Build,
    extras: &Extras,
) -> Result<Map<String, Value>, String> {
    let mut info = built.info().clone();
    info.bake_seconds = built.seconds();
    let mut report = None;
    write_with(extras, &info, None, |sections| {
        built.write(&a.output, sections, &mut |h| {
            report = Some(bake_report(h, &info, extras, a.memory_budget));
        })
    })?;
    report.ok_or_else(|| format!("{}: written but not inspected", a.output.display()))
}

/// Assembles the arrays, builds the g-mesh levels over them and writes the file with the
/// levels, the bake's report and the multiresolution octree (if any). Returns the report.
fn write_with_gmesh(
    a: &BakeArgs,
    built: Build,
    extras: &Extras,
    bar: &Progress,
) -> Result<BakeInfo, String> {
    let (baked, info) = built
        .into_built(&a.input.display().to_string())?
        .assemble(&mut |s| show_stage(bar, s))
        .map_err(|e| e.to_string())?;
    bar.show("building g-mesh levels", None);
    let levels = gmesh_levels(&baked, a.gmesh_min_polygons)?;
    write_with(extras, &info, Some(&levels), |sections| {
        baked.write(&a.output, sections)
    })?;
    Ok(info)
}

/// Gathers the extra sections (the bake's report, the g-mesh levels and the multiresolution
/// octree, each when there is one) and writes the file through `write`.
fn write_with(
    extras: &Extras,
    info: &BakeInfo,
    levels: Option<&GMeshData>,
    write: impl FnOnce(&[ExtraSection<'_>]) -> Result<u64, BakeWriteError>,
) -> Result<(), String> {
    let json_info = info.to_json();
    let mut sections = vec![BakeInfo::section(&json_info)];
    if let Some(g) = levels {
        sections.extend(g.sections());
    }
    let octree_parts = extras.octree.as_ref().map(|o| o.parts());
    if let Some(p) = &octree_parts {
        sections.extend(p.sections());
    }
    write(&sections).map_err(|e| e.to_string())?;
    Ok(())
}

/// The written file's report with the bake's time, the out-of-core figures and peak memory.
fn bake_report(
    h: &Hierarchy<'_>,
    info: &BakeInfo,
    extras: &Extras,
    memory_budget: u64,
) -> Map<String, Value> {
    let mut r = report::report(h, Some(info));
    r.insert("bake_seconds".into(), json!(info.bake_seconds));
    if let Some(st) = &extras.ooc_stats {
        r.insert(
            "input_triangles_per_second".into(),
            json!(st.input_triangles as f64 / info.bake_seconds),
        );
        r.insert("out_of_core".into(), ooc_report(st, memory_budget));
    }
    if let Some((options, levels)) = &extras.levels {
        r.insert(
            "blocked".into(),
            json!({
                "memory_budget": memory_budget,
                "block_triangles": options.block_triangles,
                "levels": levels.iter().map(|l| json!({
                    "blocks": l.blocks,
                    "largest_block": l.largest_block,
                    "triangles": l.triangles,
                    "collapses": l.collapses,
                })).collect::<Vec<_>>(),
            }),
        );
    }
    r.insert(
        "peak_rss_bytes".into(),
        json!(caveclod_bake::ooc::peak_rss_bytes()),
    );
    r
}

/// The out-of-core simplification's figures as one JSON object.
fn ooc_report(st: &OocStats, memory_budget: u64) -> Value {
    json!({
        "memory_budget": memory_budget,
        "input_vertices": st.input_vertices,
        "clustered_triangles": st.output_triangles,
        "clusters": st.clusters,
        "resolution": st.resolution,
        "target_triangles": st.target_triangles,
        "sort_octree_nodes": st.octree_nodes,
        "sort_octree_leaves": st.octree_leaves,
        "lod_levels": st.lod_levels,
        "lod_nodes": st.lod_nodes,
        "lod_seconds": st.lod_seconds,
        "sorted_runs": st.runs,
        "temp_bytes": st.temp_bytes,
        "read_seconds": st.seconds[0],
        "merge_seconds": st.seconds[1],
        "cluster_seconds": st.seconds[2],
        "triangles_per_second": st.input_triangles as f64
            / (st.seconds[0] + st.seconds[1] + st.seconds[2]),
    })
}

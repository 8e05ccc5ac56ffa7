//! CAD-style part soups bake to the end: many separate parts touching without sharing
//! vertices, many materials, meshes instanced by several nodes. An assembly with these traits
//! once spun forever in the hierarchy build (a full pass that cut its queued other
//! directions applied nothing and was repeated); the generated one here hung the same way.

use caveclod_bake::import::ImportOptions;
use caveclod_bake::pipeline::{bake_file, bake_mesh, Stage};
use caveclod_bake::report::BakeInfo;
use caveclod_tests::parts::{PartSoup, SoupShape};
use caveclod_tests::AlignedBytes;
use proptest::prelude::*;

/// The collapse progress reports of a bake: `(done, most)` after every pass.
type Reports = Vec<(u64, u64)>;

fn collapse_reports(reports: &mut Reports) -> impl FnMut(Stage) + '_ {
    move |s| {
        if let Stage::Collapse(done, most) = s {
            reports.push((done, most));
        }
    }
}

/// One report per pass, the collapses never fewer, the bound fixed, and no more passes than
/// the collapses allow: each pass applies a collapse, or stopped at its share and hands over
/// to a full pass, which applies one or is the last.
fn check_reports(reports: &Reports, info: &BakeInfo) {
    assert_eq!(reports.len(), info.passes as usize);
    let &(done, most) = reports.last().expect("a pass");
    assert!(reports
        .windows(2)
        .all(|w| w[0].0 <= w[1].0 && w[0].1 == w[1].1));
    assert!(done <= most, "{done} > {most}");
    assert!(
        u64::from(info.passes) <= 2 * done + 2,
        "{} passes",
        info.passes
    );
}

#[test]
fn a_cad_assembly_written_as_gltf_bakes_to_the_end() {
    let soup = PartSoup::generate(&SoupShape::CAD_ASSEMBLY, 1);
    assert_eq!((soup.meshes.len(), soup.instances.len()), (29, 82));
    let dir = tempfile::tempdir().unwrap();
    let path = soup.write_gltf(dir.path(), "assembly").unwrap();
    let mut reports = Reports::new();
    let (baked, info) = bake_file(
        &path,
        &ImportOptions::default(),
        &mut collapse_reports(&mut reports),
    )
    .expect("bake");
    assert_eq!(info.input_triangles, soup.triangle_count() as u64);
    // The parts touch: welding merged coincident positions and cut or dropped what the
    // touching faces share.
    let r = info.repairs;
    assert!(r.welded_positions > 0, "{r:?}");
    assert!(r.non_manifold_edges + r.duplicate_triangles > 0, "{r:?}");
    check_reports(&reports, &info);
    let &(done, most) = reports.last().unwrap();
    assert!(done > most / 2, "{done} of {most} collapses");
    // The written file loads.
    let bytes = baked.to_bytes(&[]).expect("bytes");
    let file = AlignedBytes::from_slice(&bytes);
    let h = file.hierarchy().expect("the loader accepts the bake");
    assert!(
        (2..=34).contains(&h.surface_count()),
        "{}",
        h.surface_count()
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Random small soups: the bake ends, with a hierarchy the loader accepts.
    #[test]
    fn random_part_soups_bake_to_a_valid_hierarchy(
        seed in any::<u64>(),
        meshes in 1usize..4,
        parts in 1usize..8,
        instances in 1usize..10,
        materials in 1u16..6,
        cells in 1u32..4,
    ) {
        let shape = SoupShape { meshes, parts, instances, materials, cells };
        let soup = PartSoup::generate(&shape, seed);
        let mut reports = Reports::new();
        let (baked, info) = bake_mesh(&soup.to_mesh(), "soup", &mut collapse_reports(&mut reports))
            .map_err(|e| TestCaseError::fail(e.to_string()))?;
        check_reports(&reports, &info);
        let bytes = baked.to_bytes(&[]).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let file = AlignedBytes::from_slice(&bytes);
        prop_assert!(file.hierarchy().is_ok());
    }
}

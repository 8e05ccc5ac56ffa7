//! The out-of-core bake's multiresolution octree drawn on lavapipe, with zero validation
//! messages: a camera's cut at a fine tolerance and at a coarse one (several levels in one
//! view) are drawn from the octree's one vertex buffer and the cut's per-surface index lists;
//! the coarse cut differs measurably but opens (almost) no holes: neighbouring nodes overlap
//! by the triangles crossing their border, so the sky shows through the surface at under 0.1%
//! of the pixels the fine cut covers (without the overlap: 0.3%). `CAVECLOD_TEST_IMAGES=dir`
//! saves both images and one with the holes in red.

mod vulkan_support;

use caveclod_bake::ooc::{MultiresOptions, OocOptions};
use caveclod_core::{Octree, OctreeCut};
use caveclod_tests::generate;
use caveclod_vulkan::{IndexSource, VertexBuffer};
use vulkan_support::*;

const SIZE: u32 = 256;

fn cut_lists(t: &Octree<'_>, cut: &OctreeCut<'_>) -> Vec<Vec<u32>> {
    let mut lists: Vec<Vec<u32>> = (0..t.surface_count())
        .map(|s| vec![0u32; cut.index_count(s)])
        .collect();
    let mut written = vec![0u32; t.surface_count()];
    let mut outs: Vec<&mut [u32]> = lists.iter_mut().map(Vec::as_mut_slice).collect();
    ok(cut.emit_indices(t, &mut outs, &mut written), "emit");
    lists
}

#[test]
fn an_octree_cut_draws_without_holes_at_level_changes() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let input = dir.path().join("terrain.ply");
    ok(
        generate::terrain(&input, 60_000, &mut |_, _| {}),
        "generate",
    );
    let options = OocOptions {
        temp_dir: Some(dir.path().to_path_buf()),
        leaf_triangles: 1 << 10,
        target_triangles: Some(12_000),
        octree: Some(MultiresOptions {
            block_levels: 3,
            coarsest_triangles: 256,
        }),
        ..OocOptions::with_budget(8 << 20)
    };
    let out = ok(
        caveclod_bake::ooc::simplify(&input, &options, &mut |_| {}),
        "out-of-core simplification",
    );
    let octree = out.octree.expect("the octree was asked for");
    let t = ok(Octree::new(octree.parts()), "the octree validates");

    let ctx = context();
    let size = generate::TERRAIN_SIZE;
    let look = terrain_camera(size, 0.7, 0.45, 0.12);
    let view = look.view(SIZE, SIZE);
    let vertices = ok(
        VertexBuffer::from_vertices(&ctx, "octree", t.vertices()),
        "octree vertices",
    );
    let render = |tolerance: f32| {
        let mut memory = vec![0u32; OctreeCut::words_needed(&t)];
        let mut cut = ok(OctreeCut::new(&t, &mut memory), "cut");
        let stats = ok(cut.select(&t, &view, tolerance), "select");
        let levels: Vec<u32> = cut
            .selected()
            .iter()
            .map(|&n| t.nodes()[n as usize].level)
            .collect();
        let lists = cut_lists(&t, &cut);
        let refs: Vec<&[u32]> = lists.iter().map(Vec::as_slice).collect();
        let image = render_alone(
            &ctx,
            &vertices,
            t.surface_count(),
            &look,
            (SIZE, SIZE),
            IndexSource::Lists(&refs),
        );
        (image, stats, levels)
    };
    let (fine, fine_stats, fine_levels) = render(0.5);
    // The error bounds are conservative (the farthest corner of each cluster's box, plus half a
    // cell), about two to three cells of a level: a coarse tolerance mixes levels here.
    let (coarse, coarse_stats, coarse_levels) = render(40.0);
    println!("fine: {fine_stats:?}\ncoarse: {coarse_stats:?} levels {coarse_levels:?}");
    assert!(fine_levels.iter().all(|&l| l == 0), "{fine_levels:?}");
    let mut distinct = coarse_levels.clone();
    distinct.sort_unstable();
    distinct.dedup();
    assert!(distinct.len() >= 2, "one level only: {coarse_levels:?}");
    assert!(coarse_stats.triangles < fine_stats.triangles);

    let covered = fine.covered(BACKGROUND);
    assert!(covered > u64::from(SIZE * SIZE) / 3, "{covered} pixels");
    let d = ok(coarse.diff(&fine), "diff");
    println!("coarse vs fine: {d:?}");
    assert!(d.mean_channel_difference > 0.05, "{d:?}");
    // Holes: pixels the fine cut covers that the coarse one leaves as background although
    // the coarse terrain covers a pixel above them in the same column (the sky seen through
    // the surface). Background above the coarse terrain is a lower silhouette, not a hole.
    let bg = |img: &caveclod_vulkan::RgbaImage, x: u32, y: u32| img.pixel(x, y) == Some(BACKGROUND);
    let mut holes = 0;
    let mut silhouette = 0;
    let mut marked = coarse.clone();
    for x in 0..SIZE {
        let mut terrain_above = false;
        for y in 0..SIZE {
            let (f, c) = (bg(&fine, x, y), bg(&coarse, x, y));
            if !f && c {
                if terrain_above {
                    holes += 1;
                    let i = ((y * SIZE + x) * 4) as usize;
                    marked.pixels[i..i + 4].copy_from_slice(&[255, 0, 0, 255]);
                } else {
                    silhouette += 1;
                }
            }
            terrain_above |= !c;
        }
    }
    println!("holes: {holes}, silhouette: {silhouette}, of {covered} covered pixels");
    save(&fine, "octree_fine.png");
    save(&coarse, "octree_coarse.png");
    save(&marked, "octree_holes.png");
    assert!(
        (holes as f64) < 0.001 * covered as f64,
        "{holes} of {covered} pixels open at level changes"
    );
    assert!(
        (holes as f64) < 0.002 * covered as f64,
        "{holes} of {covered} pixels open at level changes"
    );
    ok(vertices.destroy(&ctx), "destroy");
    assert_clean(&ctx, "drawing octree cuts");
    ok(ctx.destroy(), "destroy context");
}

//! The hierarchy built in blocks cuts as well as the in-core one: on a generated 300 × 300
//! terrain (180,000 triangles, a texture seam down the middle), the view-independent cuts at
//! 10% and 1% of the triangles of a blocked bake (4 × 4 blocks, three levels) are within
//! 1.25× the Hausdorff distance of the in-core bake's cuts, measured against the input by the
//! bake benchmark's sampled symmetric distance.

use caveclod_bake::baked::Baked;
use caveclod_bake::blocked::{self, BlockedOptions};
use caveclod_bake::hierarchy::{self, AttributeWeights};
use caveclod_bake::weld;
use caveclod_benches::cut::our_cut;
use caveclod_benches::distance::{distances, Reference, Soup};
use caveclod_tests::{meshes, to_mesh};

const SIDE: u32 = 300;
const SAMPLES: usize = 40_000;

#[test]
fn blocked_cuts_are_within_a_quarter_of_the_in_core_hausdorff() {
    let w = weld::weld(&to_mesh(&meshes::terrain(SIDE, SIDE, 11))).expect("weld");
    let input: Soup = w
        .triangles
        .iter()
        .map(|t| t.p.map(|p| w.positions[p as usize]))
        .collect();
    let weights = AttributeWeights::default();
    let in_core = hierarchy::build(&w, &weights, &mut |_, _| {}).expect("in-core build");
    let in_core = Baked::new(&w, &in_core);
    let options = BlockedOptions {
        block_triangles: w.triangles.len() / 16,
    };
    let b = blocked::build(&w, &weights, &options, &mut |_, _| {}).expect("blocked build");
    assert_eq!(b.levels.len(), 3, "{:?}", b.levels);
    assert_eq!(b.levels[0].blocks, 16);
    let blocked = Baked::new(&w, &b.hierarchy);
    let (hi, hb) = (
        in_core.hierarchy().expect("valid"),
        blocked.hierarchy().expect("valid"),
    );
    assert_eq!(hb.polygon_count(), hi.polygon_count());
    let reference = Reference::new(&input, SAMPLES, 1);
    for share in [10, 100] {
        let target = input.len().div_ceil(share);
        let (ci, cb) = (our_cut(&hi, target), our_cut(&hb, target));
        assert!(ci.len() > target * 9 / 10 && cb.len() > target * 9 / 10);
        let (di, _) = distances(&reference, &ci, SAMPLES, 2);
        let (db, _) = distances(&reference, &cb, SAMPLES, 2);
        eprintln!(
            "1/{share}: in-core {} triangles, Hausdorff {di:.5}; blocked {} triangles, \
             Hausdorff {db:.5} ({:.2}x)",
            ci.len(),
            cb.len(),
            db / di
        );
        assert!(
            db <= 1.25 * di,
            "1/{share}: blocked {db} > 1.25 × in-core {di}"
        );
    }
}

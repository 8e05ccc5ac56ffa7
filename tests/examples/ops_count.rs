//! Instruction counts of split and collapse (run under callgrind with
//! `--toggle-collect=ops_count::run`): full split of a 128² terrain, then full collapse.
use caveclod_core::{CameraState, NodeId};

#[inline(never)]
fn run(h: &caveclod_core::Hierarchy<'_>, cam: &mut CameraState<'_>, order: &[NodeId]) -> usize {
    let mut n = 0;
    for &v in order {
        if cam.split(h, v).is_ok() {
            n += 1;
        }
    }
    let splits = n;
    for &v in order.iter().rev() {
        match cam.collapse(h, v) {
            Ok(()) => n += 1,
            Err(e) => {
                eprintln!("collapse {v} failed after {} collapses: {e}", n - splits);
                break;
            }
        }
    }
    n
}

fn main() {
    let baked = caveclod_tests::bake(&caveclod_tests::meshes::terrain(128, 128, 1));
    let h = baked.hierarchy();
    let mut mem = vec![0u32; CameraState::words_needed(&h)];
    let mut cam = CameraState::new(&h, &mut mem).expect("sized");
    // A legal order: the order a full forced split applies them in.
    caveclod_tests::check::split_all(&h, &mut cam);
    let mut order: Vec<NodeId> = (0..h.splits().len() as u32).map(NodeId).collect();
    // Parents before children is legal for splits only if neighbours are active: replay
    // by repeatedly trying until all are split.
    cam.reset(&h);
    let mut seq = Vec::new();
    while !order.is_empty() {
        order.retain(|&v| {
            if cam.split(&h, v).is_ok() {
                seq.push(v);
                false
            } else {
                true
            }
        });
    }
    cam.reset(&h);
    let t = std::time::Instant::now();
    let n = run(&h, &mut cam, &seq);
    println!(
        "{n} operations in {:.2} ms: {:.2} M ops/s",
        t.elapsed().as_secs_f64() * 1e3,
        n as f64 / t.elapsed().as_secs_f64() / 1e6
    );
}

//! The demo's pictures on a small generated terrain: the sampled frames of the four
//! cameras' flight are drawn with geomorphs blended by the compute stage and written.

use caveclod_tests::{bake, meshes};

use crate::demo::render::{render_flight, SIZE};

#[test]
fn the_sampled_frames_are_drawn_and_written() {
    let baked = bake(&meshes::terrain(32, 32, 5));
    let h = baked.hierarchy();
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
    let (files, device) =
        render_flight(&h, 4, &[1, 3], dir.path()).unwrap_or_else(|e| panic!("{e}"));
    assert!(!device.is_empty());
    let names: Vec<String> = files
        .iter()
        .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    assert_eq!(names, ["frame-001.png", "frame-003.png"]);
    for f in &files {
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(f).unwrap_or_else(|e| panic!("{e}")),
        ));
        let mut reader = decoder.read_info().unwrap_or_else(|e| panic!("{e}"));
        let mut pixels = vec![0; reader.output_buffer_size().unwrap_or(0)];
        let frame = reader
            .next_frame(&mut pixels)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((frame.width, frame.height), SIZE);
        // The sky is one colour; the terrain in front of it is lit and shaded.
        let sky = &pixels[..4];
        let ground = pixels.chunks_exact(4).filter(|p| *p != sky).count();
        assert!(
            ground > pixels.len() / 4 / 10,
            "{}: little terrain",
            f.display()
        );
    }
}

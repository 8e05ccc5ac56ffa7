//! Edited index buffers on lavapipe: four geomorphing cameras fly for 300 frames, drawn from
//! device index buffers patched with only the places that changed (`CameraIndices::edited`),
//! for one, two and three frames in flight, with the validation layer and its
//! synchronization validation silent. Twins of the cameras, flown alike, apply the same edits
//! to a copy in memory, which after every frame holds exactly the triangles of morphed
//! emission; drawn from lists in the copy's order, they give the edited buffers' image pixel
//! for pixel. Drawn in emission's own order, the image differs at most where two folded
//! triangles meet at one depth, which the order decides. The edits write a small part of what
//! emission writes.

mod vulkan_support;

use caveclod_core::{CameraConfig, CameraState, Hierarchy, RefineParams};
use caveclod_tests::bake::bake;
use caveclod_tests::meshes;
use caveclod_vulkan::{
    CameraIndices, CameraMorphs, Context, IndexSource, LookAt, MorphStage, RecordCamera, Renderer,
    RendererDesc, RgbaImage, VertexBuffer,
};
use vulkan_support::{
    assert_clean, ok, plain_camera, quadrants, save, sync_context, terrain_camera, EditCopy,
};

const SIZE: u32 = 256;
const MAX_MORPHS: u32 = 4096;
const FRAMES: usize = 300;
/// Holes closed per camera and frame.
const MOVES: u32 = 64;
/// Frames between draws in emission's own order.
const EMISSION_EVERY: usize = 15;

/// Camera `c`'s look in frame `f`: circling the terrain, each at its own speed, distance
/// and height, so fronts split and collapse every frame.
fn look(size: f32, c: usize, f: usize) -> LookAt {
    let t = f as f32 / FRAMES as f32;
    let angle = 1.6 * c as f32 + t * (1.0 + 0.5 * c as f32) * std::f32::consts::TAU;
    let distance = 0.35 + 0.3 * (t * 7.0 + c as f32).sin().abs();
    terrain_camera(size, angle, distance, 0.25 + 0.1 * c as f32)
}

/// Where a side's indices come from.
#[derive(Clone, Copy)]
enum Fill<'a> {
    /// The cameras' edits, copied into the device buffer.
    Edits,
    /// Morphed emission.
    Emission,
    /// Lists in the order of each twin's copy of its edited buffer.
    Copies(&'a [EditCopy]),
}

/// Each surface's triangles in `copy`, holes left out, sorted.
fn triangles(copy: &EditCopy) -> Vec<Vec<[u32; 3]>> {
    copy.lists()
        .iter()
        .map(|l| {
            sorted(
                l.chunks_exact(3)
                    .filter(|t| !(t[0] == t[1] && t[1] == t[2])),
            )
        })
        .collect()
}

/// Triangles, sorted.
fn sorted<'a>(t: impl Iterator<Item = &'a [u32]>) -> Vec<[u32; 3]> {
    let mut v: Vec<[u32; 3]> = t.map(|t| [t[0], t[1], t[2]]).collect();
    v.sort_unstable();
    v
}

/// Morphed emission's triangles per surface, sorted.
fn emitted(h: &Hierarchy<'_>, cam: &CameraState<'_>) -> Vec<Vec<[u32; 3]>> {
    let mut out = vec![0u32; cam.total_index_count()];
    let mut offsets = vec![0u32; h.surface_count() + 1];
    ok(
        cam.emit_indices_packed_morphed(h, &mut out, &mut offsets),
        "emit",
    );
    (0..h.surface_count())
        .map(|s| sorted(out[offsets[s] as usize..offsets[s + 1] as usize].chunks_exact(3)))
        .collect()
}

/// One way of drawing the flight: a renderer with a ring of `in_flight` slots, and per
/// camera its index buffers and morph slots.
struct Side {
    renderer: Renderer,
    indices: Vec<CameraIndices>,
    morphs: Vec<CameraMorphs>,
}

impl Side {
    fn new(
        ctx: &Context,
        h: &Hierarchy<'_>,
        vertices: &VertexBuffer,
        cams: &[CameraState<'_>],
        in_flight: usize,
        edited: bool,
    ) -> Self {
        let surfaces = h.surface_count();
        let desc = RendererDesc {
            refine_morphs: true,
            frames_in_flight: in_flight,
            ..RendererDesc::single(SIZE, SIZE)
        };
        let renderer = ok(Renderer::new(ctx, desc), "renderer");
        let indices = cams
            .iter()
            .enumerate()
            .map(|(c, cam)| {
                let name = format!("camera {c}");
                if edited {
                    let made =
                        CameraIndices::edited(ctx, &name, surfaces, cam.index_places(), in_flight);
                    ok(made, "edited indices")
                } else {
                    CameraIndices::new(&name, surfaces, in_flight)
                }
            })
            .collect();
        let morphs = cams
            .iter()
            .enumerate()
            .map(|(c, cam)| {
                let m = CameraMorphs::new(
                    ctx,
                    renderer.recorder(),
                    &format!("camera {c}"),
                    vertices,
                    MorphStage::Vertex,
                    cam.max_morphs(),
                    in_flight,
                );
                ok(m, "camera morphs")
            })
            .collect();
        Self {
            renderer,
            indices,
            morphs,
        }
    }

    /// Fills the next slot from `fill` and draws the cameras' fronts, leaving the frame in
    /// flight; returns its slot and the index bytes written.
    fn draw(
        &mut self,
        ctx: &Context,
        h: &Hierarchy<'_>,
        vertices: &VertexBuffer,
        cams: &mut [CameraState<'_>],
        looks: &[LookAt],
        fill: Fill<'_>,
    ) -> (usize, u64) {
        let slot = ok(self.renderer.begin_frame(ctx), "begin frame");
        for (c, ((cam, ind), m)) in cams
            .iter_mut()
            .zip(&mut self.indices)
            .zip(&mut self.morphs)
            .enumerate()
        {
            match fill {
                Fill::Edits => {
                    ok(ind.fill_edits(ctx, slot, h, cam, MOVES), "fill edits");
                }
                Fill::Emission => {
                    let source = IndexSource::MorphedCamera {
                        hierarchy: h,
                        camera: cam,
                    };
                    ok(ind.fill(ctx, slot, source), "fill");
                }
                Fill::Copies(copies) => {
                    let lists = copies[c].lists();
                    let lists: Vec<&[u32]> = lists.iter().map(Vec::as_slice).collect();
                    ok(
                        ind.fill(ctx, slot, IndexSource::MorphedLists(&lists)),
                        "fill",
                    );
                }
            }
            ok(m.fill(slot, h.vertices(), cam), "fill morphs");
        }
        let draws: Vec<(usize, RecordCamera<'_>)> = self
            .indices
            .iter()
            .zip(&self.morphs)
            .zip(quadrants(SIZE))
            .zip(looks)
            .map(|(((ind, m), viewport), look)| {
                (
                    0,
                    plain_camera(viewport, look, vertices, ind).refine_morphs(m),
                )
            })
            .collect();
        let stats = ok(self.renderer.render(ctx, &draws), "render");
        (slot, stats.index_bytes)
    }

    /// The image of the frame last drawn in `slot` (waiting for that frame alone).
    fn image(&self, ctx: &Context, slot: usize) -> RgbaImage {
        ok(self.renderer.read_slot_target(ctx, slot, 0), "read back")
    }

    fn destroy(self, ctx: &Context) {
        ok(self.renderer.destroy(ctx), "destroy renderer");
        for i in self.indices {
            ok(i.destroy(ctx), "destroy indices");
        }
        for m in self.morphs {
            ok(m.destroy(ctx), "destroy morphs");
        }
    }
}

/// Cameras of `config` in `memory`, one per memory.
fn cameras<'m>(
    h: &Hierarchy<'_>,
    memory: &'m mut [Vec<u32>],
    config: &CameraConfig,
) -> Vec<CameraState<'m>> {
    memory
        .iter_mut()
        .map(|m| ok(CameraState::with_config(h, m, config), "camera"))
        .collect()
}

/// Flies the four cameras with `in_flight` frames in flight; returns the index bytes the
/// edits and emission wrote.
fn fly(ctx: &Context, h: &Hierarchy<'_>, vertices: &VertexBuffer, in_flight: usize) -> (u64, u64) {
    let config = CameraConfig::full(h)
        .with_morphs(MAX_MORPHS)
        .with_index_edits(8192);
    let words = CameraState::words_needed_for(h, &config);
    let mut memory = vec![vec![0u32; words]; 4];
    let mut twin_memory = vec![vec![0u32; words]; 4];
    let mut cams = cameras(h, &mut memory, &config);
    let mut twins = cameras(h, &mut twin_memory, &config);
    let mut copies: Vec<EditCopy> = twins
        .iter()
        .map(|t| EditCopy::new(h.surface_count(), t))
        .collect();
    let mut edited = Side::new(ctx, h, vertices, &cams, in_flight, true);
    let mut listed = Side::new(ctx, h, vertices, &cams, in_flight, false);
    let mut emitted_side = Side::new(ctx, h, vertices, &cams, in_flight, false);
    let size = h.meta().bounds_max[0] - h.meta().bounds_min[0];
    let params = RefineParams {
        tolerance_px: 0.5,
        dt_s: 1.0 / 60.0,
        ..RefineParams::default()
    };
    let (mut edit_bytes, mut emit_bytes) = (0, 0);
    // Frames drawn and not yet compared: each is compared once the frames after it fill the
    // ring, so `in_flight` frames overlap on the queue.
    let mut pending = std::collections::VecDeque::new();
    for f in 0..FRAMES {
        let looks: Vec<LookAt> = (0..4).map(|c| look(size, c, f)).collect();
        for (c, (l, v)) in looks.iter().zip(quadrants(SIZE)).enumerate() {
            let view = l.view(v.width, v.height);
            ok(cams[c].refine(h, &view, &params), "refine");
            ok(twins[c].refine(h, &view, &params), "refine twin");
            copies[c].update(h, &mut twins[c], MOVES);
            assert_eq!(
                triangles(&copies[c]),
                emitted(h, &twins[c]),
                "frame {f}, camera {c}"
            );
        }
        let (slot, written) = edited.draw(ctx, h, vertices, &mut cams, &looks, Fill::Edits);
        let (listed_slot, _) =
            listed.draw(ctx, h, vertices, &mut cams, &looks, Fill::Copies(&copies));
        assert_eq!(slot, listed_slot);
        if f > 0 {
            edit_bytes += written;
            emit_bytes += cams
                .iter()
                .map(|c| 4 * c.total_index_count() as u64)
                .sum::<u64>();
        }
        if f % EMISSION_EVERY == 0 {
            let (e, _) = emitted_side.draw(ctx, h, vertices, &mut cams, &looks, Fill::Emission);
            let e = emitted_side.image(ctx, e);
            let d = ok(edited.image(ctx, slot).diff(&e), "diff");
            assert!(
                d.pixels - d.equal <= 16,
                "{in_flight} in flight, frame {f}: edited against emission's order {d:?}"
            );
        }
        pending.push_back((f, slot));
        while pending.len() >= in_flight || (f + 1 == FRAMES && !pending.is_empty()) {
            let Some((g, slot)) = pending.pop_front() else {
                break;
            };
            let (a, b) = (edited.image(ctx, slot), listed.image(ctx, slot));
            if a.pixels != b.pixels {
                save(&a, &format!("edited-{in_flight}-{g}.png"));
                save(&b, &format!("listed-{in_flight}-{g}.png"));
                panic!(
                    "{in_flight} in flight, frame {g}: edited {:?}",
                    ok(a.diff(&b), "diff")
                );
            }
            if g == FRAMES / 2 {
                save(&a, &format!("edited-{in_flight}.png"));
            }
        }
    }
    for side in [edited, listed, emitted_side] {
        side.destroy(ctx);
    }
    (edit_bytes, emit_bytes)
}

/// Flies the cameras with `in_flight` frames in flight on a context of its own.
fn flight(in_flight: usize) {
    let ctx = sync_context();
    let baked = bake(&meshes::terrain(64, 64, 11));
    let h = baked.hierarchy();
    let mut made = None;
    ok(
        ctx.submit_and_wait(|cmd| {
            made = Some(VertexBuffer::record_upload(
                &ctx,
                cmd,
                "terrain",
                h.vertices(),
                None,
            ));
        }),
        "upload",
    );
    let (vertices, staging) = ok(made.expect("recorded"), "record upload");
    ok(staging.destroy(&ctx), "destroy staging");
    let (edits, emission) = fly(&ctx, &h, &vertices, in_flight);
    println!("{in_flight} in flight: edits wrote {edits} index bytes, emission {emission}");
    assert!(
        edits * 4 < emission,
        "edits {edits} bytes, emission {emission}"
    );
    ok(vertices.destroy(&ctx), "destroy vertices");
    assert_clean(&ctx, &format!("{in_flight} frames in flight"));
    ok(ctx.destroy(), "destroy context");
}

#[test]
fn edited_index_buffers_one_frame_in_flight() {
    flight(1);
}

#[test]
fn edited_index_buffers_two_frames_in_flight() {
    flight(2);
}

#[test]
fn edited_index_buffers_three_frames_in_flight() {
    flight(3);
}

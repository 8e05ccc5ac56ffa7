//! The egui layer: a panel with each camera's figures, the settings and the keys, and the
//! frozen cameras' view frusta drawn as lines into every viewport.

use caveclod_core::glam::{Mat4, Vec3, Vec4};
use caveclod_vulkan::Viewport;
use egui::{Color32, Pos2, Rect, Stroke};

use crate::controls::KEY_HELP;
use crate::scene::{Frozen, Scene};

/// What the panel shows besides the scene.
pub struct PanelInfo<'a> {
    pub device: &'a str,
    pub fps: f64,
    pub wireframe_available: bool,
    pub validation_messages: usize,
    pub bands: usize,
    /// Hierarchy levels the bands cover.
    pub levels: u32,
}

/// Draws the panel; returns the screen rectangle it covers, in points.
pub fn panel(ctx: &egui::Context, scene: &Scene<'_>, info: &PanelInfo<'_>) -> Option<Rect> {
    let response = egui::Window::new("caveclod viewer")
        .default_pos(Pos2::new(8.0, 8.0))
        .resizable(false)
        .show(ctx, |ui| {
            ui.label(format!("{} | {:.1} fps", info.device, info.fps));
            settings(ui, scene, info);
            ui.separator();
            cameras(ui, scene);
            ui.separator();
            ui.collapsing("keys", |ui| {
                egui::Grid::new("keys").striped(true).show(ui, |ui| {
                    for (key, what) in KEY_HELP {
                        ui.monospace(*key);
                        ui.label(*what);
                        ui.end_row();
                    }
                });
            });
        });
    response.map(|r| r.response.rect)
}

fn settings(ui: &mut egui::Ui, scene: &Scene<'_>, info: &PanelInfo<'_>) {
    let s = &scene.settings;
    ui.label(format!("tolerance {:.2} px", s.tolerance_px));
    ui.label(format!(
        "colour {}{}",
        s.colour.name(),
        if s.colour == crate::scene::ColourMode::Depth {
            format!(
                " ({} bands over {} levels, blue coarse to red fine)",
                info.bands, info.levels
            )
        } else {
            String::new()
        }
    ));
    ui.label(s.morphs.name());
    if let Some(t) = scene.h.streamed().map(|s| s.totals) {
        ui.label(format!(
            "streaming: {} pages installed, {} evicted, {} splits wait, tolerance x{:.2}",
            t.installs, t.evictions, t.deferred, t.pressure
        ));
    }
    ui.label(if !info.wireframe_available {
        "wireframe unavailable (no fillModeNonSolid)"
    } else if s.wireframe {
        "wireframe on"
    } else {
        "wireframe off"
    });
    if info.validation_messages > 0 {
        ui.colored_label(
            Color32::RED,
            format!("{} validation messages", info.validation_messages),
        );
    }
}

fn cameras(ui: &mut egui::Ui, scene: &Scene<'_>) {
    egui::Grid::new("cameras").striped(true).show(ui, |ui| {
        for head in [
            "camera",
            "polygons",
            "ops",
            "morphing",
            "refine ms",
            "emit ms",
            "",
        ] {
            ui.strong(head);
        }
        ui.end_row();
        for (i, c) in scene.cameras.iter().enumerate() {
            let steered = if i == scene.settings.selected {
                " ◀"
            } else {
                ""
            };
            ui.label(format!("{}{steered}", i + 1));
            ui.monospace(format!("{:>9}", c.stats.polygons));
            ui.monospace(format!("{:>6}", c.stats.operations));
            ui.monospace(format!("{:>6}", c.stats.morphing));
            ui.monospace(format!("{:>6.2}", c.stats.refine_ms));
            ui.monospace(format!("{:>6.2}", c.stats.emit_ms));
            ui.label(match (c.frozen.is_some(), c.animated) {
                (true, _) => "frozen",
                (false, true) => "animated",
                (false, false) => "",
            });
            ui.end_row();
        }
    });
}

/// Draws each frozen camera's frustum (out to the point it looked at) into every viewport,
/// projected with that viewport's camera; `pixels_per_point` converts to egui's points.
pub fn frusta(
    ctx: &egui::Context,
    frozen: &[Frozen],
    views: &[(Viewport, Mat4)],
    pixels_per_point: f32,
) {
    if frozen.is_empty() {
        return;
    }
    let painter = ctx.layer_painter(egui::LayerId::background());
    let stroke = Stroke::new(1.5, Color32::from_rgb(255, 240, 80));
    for f in frozen {
        let edges = frustum_edges(f);
        for (vp, view_proj) in views {
            let clip = Rect::from_min_size(
                Pos2::new(vp.x as f32, vp.y as f32) / pixels_per_point,
                egui::vec2(vp.width as f32, vp.height as f32) / pixels_per_point,
            );
            let painter = painter.with_clip_rect(clip);
            for (a, b) in &edges {
                if let Some([p, q]) = project_segment(*view_proj, *a, *b) {
                    let to_points = |ndc: Vec3| {
                        Pos2::new(
                            vp.x as f32 + (ndc.x + 1.0) * 0.5 * vp.width as f32,
                            vp.y as f32 + (ndc.y + 1.0) * 0.5 * vp.height as f32,
                        ) / pixels_per_point
                    };
                    painter.line_segment([to_points(p), to_points(q)], stroke);
                }
            }
        }
    }
}

/// The 12 edges of a frozen view's frustum from the eye's near plane to the distance of the
/// point it looked at, plus the 4 lines from the eye to the far corners.
fn frustum_edges(f: &Frozen) -> Vec<(Vec3, Vec3)> {
    let look = &f.look;
    let forward = (look.target - look.eye).normalize_or_zero();
    let right = forward.cross(look.up).normalize_or_zero();
    let up = right.cross(forward);
    let far = (look.target - look.eye).length();
    let half_h = (look.fov_y * 0.5).tan();
    let half_w = half_h * f.aspect;
    let corners = |d: f32| {
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(x, y)| look.eye + (forward + right * (x * half_w) + up * (y * half_h)) * d)
    };
    let (n, fa) = (corners(look.near), corners(far));
    let mut edges = Vec::with_capacity(16);
    for k in 0..4 {
        let next = (k + 1) % 4;
        edges.push((n[k], n[next]));
        edges.push((fa[k], fa[next]));
        edges.push((n[k], fa[k]));
        edges.push((look.eye, fa[k]));
    }
    edges
}

/// The segment `a`-`b` in normalised device coordinates of `view_proj`, clipped to the part
/// in front of the eye; `None` if none is.
fn project_segment(view_proj: Mat4, a: Vec3, b: Vec3) -> Option<[Vec3; 2]> {
    const MIN_W: f32 = 1e-4;
    let (mut ca, mut cb) = (view_proj * a.extend(1.0), view_proj * b.extend(1.0));
    if ca.w < MIN_W && cb.w < MIN_W {
        return None;
    }
    let cut = |inside: Vec4, outside: Vec4| {
        let t = (inside.w - MIN_W) / (inside.w - outside.w);
        inside + (outside - inside) * t
    };
    if ca.w < MIN_W {
        ca = cut(cb, ca);
    } else if cb.w < MIN_W {
        cb = cut(ca, cb);
    }
    let ndc = |c: Vec4| c.truncate() / c.w;
    Some([ndc(ca), ndc(cb)])
}

#[cfg(test)]
mod tests {
    use super::*;
    use caveclod_core::LookAt;

    fn look() -> LookAt {
        LookAt {
            eye: Vec3::ZERO,
            target: Vec3::new(0.0, 0.0, -1.0),
            up: Vec3::Y,
            fov_y: 1.0,
            near: 0.1,
            far: 100.0,
        }
    }

    #[test]
    fn segments_are_clipped_to_the_front_of_the_eye() {
        let vp = look().view_projection(1.0);
        let ahead = Vec3::new(0.0, 0.0, -5.0);
        let behind = Vec3::new(0.0, 0.0, 5.0);
        let [p, q] = project_segment(vp, ahead, Vec3::new(1.0, 0.0, -5.0)).unwrap();
        assert!(p.x.abs() < 1e-6 && q.x > 0.0, "{p} {q}");
        assert!(project_segment(vp, behind, behind + Vec3::X).is_none());
        let [p, q] = project_segment(vp, ahead + Vec3::X, behind + Vec3::X).unwrap();
        assert!(p.x > 0.0 && q.x.is_finite() && q.x > p.x, "{p} {q}");
    }

    #[test]
    fn a_frustum_has_sixteen_edges_from_the_eye_to_its_target() {
        let f = Frozen {
            look: look(),
            aspect: 2.0,
        };
        let edges = frustum_edges(&f);
        assert_eq!(edges.len(), 16);
        let far = edges
            .iter()
            .map(|(a, b)| a.z.min(b.z))
            .fold(0.0f32, f32::min);
        assert!(
            (far + 1.0).abs() < 1e-5,
            "far plane at the target's distance: {far}"
        );
    }
}

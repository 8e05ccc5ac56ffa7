//! Cameras around a hierarchy: the views a one-shot render or a viewer starts from.

use caveclod_core::{Hierarchy, LookAt};
use glam::Vec3;

/// `n` cameras around the hierarchy's bounding box, 30° above it, evenly spaced in angle,
/// far enough for a 60° field of view to see the whole box.
pub fn orbit(h: &Hierarchy<'_>, n: usize) -> Vec<LookAt> {
    let m = h.meta();
    orbit_box(m.bounds_min, m.bounds_max, n)
}

/// [`orbit`] around a box.
pub fn orbit_box(min: [f32; 3], max: [f32; 3], n: usize) -> Vec<LookAt> {
    let (lo, hi) = (Vec3::from_array(min), Vec3::from_array(max));
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    let fov_y = 60f32.to_radians();
    let distance = radius / (fov_y * 0.5).sin() * 1.05;
    (0..n)
        .map(|i| {
            let angle = 0.6 + std::f32::consts::TAU * i as f32 / n.max(1) as f32;
            let elevation = 30f32.to_radians();
            let dir = Vec3::new(
                angle.sin() * elevation.cos(),
                elevation.sin(),
                angle.cos() * elevation.cos(),
            );
            LookAt {
                eye: centre + dir * distance,
                target: centre,
                up: Vec3::Y,
                fov_y,
                near: distance * 1e-3,
                far: distance + 2.0 * radius,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cameras_look_at_the_centre_from_outside_the_box() {
        let looks = orbit_box([0.0, 0.0, 0.0], [2.0, 1.0, 4.0], 3);
        assert_eq!(looks.len(), 3);
        let centre = Vec3::new(1.0, 0.5, 2.0);
        let radius = Vec3::new(2.0, 1.0, 4.0).length() * 0.5;
        for l in &looks {
            assert_eq!(l.target, centre);
            assert!((l.eye - centre).length() > radius);
            assert!(l.eye.y > centre.y, "above the box's centre");
            assert!(l.near > 0.0 && l.far > (l.eye - centre).length() + radius * 0.99);
        }
        assert_ne!(looks[0].eye, looks[1].eye);
    }
}

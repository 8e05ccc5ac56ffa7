//! Refinement parameters have one check, `RefineParams::validate`, and every call that takes
//! them refuses a value out of range with the field and the value before anything changes:
//! `CameraState::refine` and `CameraState::lag` here, the octree cut's tolerance in
//! `octree.rs`. The defaults and the edges of every range are accepted.

mod common;

use std::f32::consts::FRAC_PI_2;

use caveclod_core::{
    CameraConfig, CameraState, OpError, ParamField, ParamsError, RefineParams, View,
};
use common::{golden_hierarchy, views};

/// Every field out of range, with the error it must give.
fn refused() -> Vec<(RefineParams, ParamsError)> {
    let d = RefineParams::default();
    let mut cases = Vec::new();
    let mut add = |field: ParamField, values: &[f32], set: fn(&mut RefineParams, f32)| {
        for &value in values {
            let mut p = d;
            set(&mut p, value);
            cases.push((p, ParamsError { field, value }));
        }
    };
    add(
        ParamField::TolerancePx,
        &[0.0, -0.0, -1.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY],
        |p, v| p.tolerance_px = v,
    );
    add(
        ParamField::VisitFraction,
        &[0.0, -0.5, 1.0001, f32::NAN, f32::INFINITY],
        |p, v| p.visit_fraction = v,
    );
    add(ParamField::MaxVisits, &[0.0], |p, _| p.max_visits = 0);
    add(
        ParamField::DtS,
        &[-1e-3, f32::NAN, f32::INFINITY],
        |p, v| p.dt_s = v,
    );
    add(
        ParamField::RefineMorphS,
        &[-1.0, f32::NAN, f32::INFINITY],
        |p, v| p.refine_morph_s = v,
    );
    add(
        ParamField::CoarsenMorphS,
        &[-1.0, f32::NAN, f32::INFINITY],
        |p, v| p.coarsen_morph_s = v,
    );
    add(
        ParamField::MorphSpeedPxS,
        &[-1.0, f32::NAN, f32::NEG_INFINITY],
        |p, v| p.morph_speed_px_s = v,
    );
    add(
        ParamField::MorphRadiusTolerances,
        &[-1.0, f32::NAN, f32::NEG_INFINITY],
        |p, v| p.morph_radius_tolerances = v,
    );
    add(
        ParamField::MorphGuardRad,
        &[-0.1, FRAC_PI_2, 2.0, f32::NAN, f32::INFINITY],
        |p, v| p.morph_guard_rad = v,
    );
    cases
}

/// The edges of every range, and the values that mean "none".
fn accepted() -> Vec<RefineParams> {
    let d = RefineParams::default();
    vec![
        d,
        RefineParams {
            tolerance_px: f32::MIN_POSITIVE,
            ..d
        },
        RefineParams {
            tolerance_px: f32::MAX,
            ..d
        },
        RefineParams {
            visit_fraction: 1e-6,
            max_visits: 1,
            ..d
        },
        RefineParams {
            dt_s: 0.0,
            refine_morph_s: 0.0,
            coarsen_morph_s: 0.0,
            ..d
        },
        RefineParams {
            morph_speed_px_s: 0.0,
            morph_radius_tolerances: 0.0,
            morph_guard_rad: 0.0,
            ..d
        },
        RefineParams {
            morph_speed_px_s: f32::INFINITY,
            morph_radius_tolerances: f32::INFINITY,
            morph_guard_rad: FRAC_PI_2 - 1e-3,
            ..d
        },
        RefineParams {
            morph_speed_px_s: 9.0,
            morph_radius_tolerances: 16.0,
            max_ops: 0,
            ..d
        },
    ]
}

/// A refined morphing camera's counts: what a refused call must leave as it was.
fn counts(cam: &CameraState<'_>) -> (u32, u32, u32, u32) {
    (
        cam.active_node_count(),
        cam.active_polygon_count(),
        cam.split_count(),
        cam.morph_count(),
    )
}

#[test]
fn every_field_out_of_range_is_refused_by_refine_and_lag() {
    let h = golden_hierarchy();
    let config = CameraConfig::full(&h).with_morphs(256);
    let mut memory = vec![0u32; CameraState::words_needed_for(&h, &config)];
    let mut cam = CameraState::with_config(&h, &mut memory, &config).expect("camera");
    let all = views(&h, 8);
    let view: &View = &all[1];
    cam.refine(&h, view, &RefineParams::default())
        .expect("refine");
    cam.refine(&h, &all[2], &RefineParams::default())
        .expect("refine");
    let before = counts(&cam);
    assert!(before.2 > 0, "the camera refined");
    let cases = refused();
    for (p, error) in &cases {
        assert_eq!(p.validate(), Err(*error), "{p:?}");
        assert_eq!(
            cam.refine(&h, view, p),
            Err(OpError::InvalidParams(*error)),
            "{p:?}"
        );
        assert_eq!(
            counts(&cam),
            before,
            "a refused pass changed the camera: {p:?}"
        );
        assert_eq!(
            cam.lag(&h, view, p),
            Err(OpError::InvalidParams(*error)),
            "{p:?}"
        );
        // The message names the field, the value and the range.
        let message = OpError::InvalidParams(*error).to_string();
        assert!(message.contains(error.field.name()), "{message}");
        assert!(message.contains(error.field.expected()), "{message}");
    }
    // Every field with a range has a refused case.
    for field in [
        ParamField::TolerancePx,
        ParamField::VisitFraction,
        ParamField::MaxVisits,
        ParamField::DtS,
        ParamField::RefineMorphS,
        ParamField::CoarsenMorphS,
        ParamField::MorphSpeedPxS,
        ParamField::MorphRadiusTolerances,
        ParamField::MorphGuardRad,
    ] {
        assert!(cases.iter().any(|(_, e)| e.field == field), "{field:?}");
    }
}

#[test]
fn the_defaults_and_the_edges_of_every_range_are_accepted() {
    let h = golden_hierarchy();
    let config = CameraConfig::full(&h).with_morphs(256);
    let mut memory = vec![0u32; CameraState::words_needed_for(&h, &config)];
    let mut cam = CameraState::with_config(&h, &mut memory, &config).expect("camera");
    let all = views(&h, 8);
    for (i, p) in accepted().iter().enumerate() {
        assert_eq!(p.validate(), Ok(()), "{p:?}");
        let view = &all[i % all.len()];
        cam.refine(&h, view, p)
            .unwrap_or_else(|e| panic!("{p:?}: {e}"));
        cam.lag(&h, view, p)
            .unwrap_or_else(|e| panic!("{p:?}: {e}"));
    }
}

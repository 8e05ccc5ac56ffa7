//! Properties of g-mesh LOD control: `F(T)` is continuous at every partition boundary,
//! `T < 0` selects level 0 and `T > 1` the coarsest, and the predictive controller always
//! terminates and lands within `ε` of the budget whenever some bias can.

mod common;

use caveclod_core::gmesh::{
    control, scene_polygons, ControlEntry, ControlParams, LodInstance, LodModel, Partitions,
};
use proptest::prelude::*;

/// Boundaries from positive range weights (each range at least 1% of the whole).
fn boundaries(weights: &[f32]) -> Vec<f32> {
    let total: f32 = weights.iter().sum();
    let mut out = vec![0.0];
    let mut acc = 0.0;
    for w in weights {
        acc += w / total;
        out.push(acc);
    }
    *out.last_mut().unwrap() = 1.0;
    out
}

fn next_up(x: f32) -> f32 {
    if x == 0.0 {
        return f32::from_bits(1);
    }
    let b = x.to_bits();
    f32::from_bits(if x > 0.0 { b + 1 } else { b - 1 })
}

fn next_down(x: f32) -> f32 {
    -next_up(-x)
}

/// Level polygon counts, strictly decreasing, from per-level shrink factors.
fn counts(finest: u32, shrink: &[f32]) -> Vec<u32> {
    let mut c = vec![finest];
    for s in shrink {
        let last = *c.last().unwrap();
        c.push(((last as f32 * s) as u32).clamp(1, last.saturating_sub(1).max(1)));
    }
    c
}

proptest! {
    #![proptest_config(common::proptest_config(256, 3))]

    #[test]
    fn f_is_continuous_at_every_boundary(
        weights in prop::collection::vec(1.0f32..100.0, 1..8),
        values in prop::collection::vec(-1000.0f32..1000.0, 9),
    ) {
        let b = boundaries(&weights);
        prop_assume!(b.windows(2).all(|w| w[1] - w[0] > 0.005));
        let p = Partitions::new(&b).unwrap();
        let a = &values[..b.len()];
        for i in 1..b.len() - 1 {
            let r = b[i];
            let at = p.attribute(a, r).unwrap();
            let above = p.attribute(a, next_up(r)).unwrap();
            let below = p.attribute(a, next_down(r)).unwrap();
            // At a boundary F is exactly a_i, and one ulp to either side moves it by at most
            // the slope of the adjacent range times a few ulps.
            prop_assert!((at - a[i]).abs() <= 1e-3, "F(R_{}) = {} vs a = {}", i, at, a[i]);
            prop_assert!((above - at).abs() <= 0.05, "jump above R_{}: {} -> {}", i, at, above);
            prop_assert!((below - at).abs() <= 0.05, "jump below R_{}: {} -> {}", i, below, at);
        }
        // The ends: T <= 0 is level 0 unmorphed, T > 1 the coarsest.
        for t in [-5.0f32, -1e-6, 0.0] {
            let m = p.level_morph(t);
            prop_assert_eq!((m.level, m.t), (0, 0.0));
            prop_assert_eq!(p.attribute(a, t).unwrap(), a[0]);
        }
        for t in [next_up(1.0), 1.5, 1e6] {
            let m = p.level_morph(t);
            prop_assert_eq!((m.level, m.t), (p.coarsest(), 0.0));
            prop_assert_eq!(p.attribute(a, t).unwrap(), a[p.coarsest()]);
        }
        // At T = 1 the last range ends at its far attributes.
        prop_assert!((p.attribute(a, 1.0).unwrap() - a[p.coarsest()]).abs() <= 1e-3);
    }

    #[test]
    fn controller_terminates_and_lands_within_epsilon_when_reachable(
        w0 in prop::collection::vec(1.0f32..100.0, 2..6),
        w1 in prop::collection::vec(1.0f32..100.0, 2..6),
        s0 in prop::collection::vec(0.3f32..0.7, 5),
        ts in prop::collection::vec((-0.5f32..1.5, 0u32..2, prop::bool::weighted(0.9)), 1..40),
        bias in -0.5f32..0.5,
        budget_frac in 0.0f64..1.2,
        eps_kind in 0u32..3,
    ) {
        let b0 = boundaries(&w0);
        let b1 = boundaries(&w1);
        let c0 = counts(2000, &s0[..b0.len() - 1]);
        let c1 = counts(700, &s0[..b1.len() - 1]);
        let models = [
            LodModel::new(Partitions::new(&b0).unwrap(), &c0).unwrap(),
            LodModel::new(Partitions::new(&b1).unwrap(), &c1).unwrap(),
        ];
        let instances: Vec<LodInstance> = ts
            .iter()
            .map(|&(t, model, visible)| LodInstance { model, t, visible })
            .collect();
        let finest = scene_polygons(&models, &instances, -10.0).unwrap();
        let budget = (finest as f64 * budget_frac) as u64;
        let epsilon = match eps_kind {
            0 => models[0].default_epsilon(),
            1 => 1,
            _ => 0,
        };
        let params = ControlParams { budget, epsilon, max_change: f32::INFINITY };
        let mut scratch = vec![ControlEntry::default(); instances.len()];
        let o = control(&models, &instances, bias, &params, &mut scratch).unwrap();

        // The count reported is the count at the bias reported.
        prop_assert_eq!(o.polygons, scene_polygons(&models, &instances, o.bias).unwrap());
        prop_assert_eq!(o.within_epsilon, o.polygons.abs_diff(budget) <= epsilon);

        // Brute force: q(bias) is constant between crossings, so sampling just above and
        // below every crossing (and far out) sees every value it takes.
        let mut reachable = false;
        let mut samples = vec![-10.0f32, 10.0, bias];
        for inst in &instances {
            let m = &models[inst.model as usize];
            for &r in m.partitions().boundaries() {
                let x = r - inst.t;
                let m = inst.t.abs().max(r.abs()).max(x.abs()).max(f32::MIN_POSITIVE);
                let ulp = next_up(m) - m;
                samples.extend((-3..=3).map(|k| x + k as f32 * ulp));
            }
        }
        for s in samples {
            let q = scene_polygons(&models, &instances, s).unwrap();
            if q.abs_diff(budget) <= epsilon {
                reachable = true;
                break;
            }
        }
        if reachable {
            prop_assert!(o.within_epsilon, "reachable but missed: {:?}", o);
            prop_assert!(o.reachable);
        } else {
            prop_assert!(!o.within_epsilon && !o.reachable, "{:?}", o);
        }
        // With a cap, the change never exceeds it.
        let capped = ControlParams { max_change: 0.01, ..params };
        let oc = control(&models, &instances, bias, &capped, &mut scratch).unwrap();
        prop_assert!(oc.change.abs() <= 0.01);
        prop_assert_eq!(oc.polygons, scene_polygons(&models, &instances, oc.bias).unwrap());
    }
}

//! The regulator's unit tests, on simulated fronts whose polygon count falls with a power of
//! the tolerance: convergence, the damping guards, the limits, moving views, and amortised
//! and morphing cameras.

use super::*;

/// A front of `c / tolerance^2` polygons, as a terrain's is roughly.
fn polygons(c: f32, tolerance: f32) -> u32 {
    (c / (tolerance * tolerance)).min(u32::MAX as f32) as u32
}

#[test]
fn converges_on_a_front_falling_with_the_square_of_the_tolerance() {
    for (c, target) in [(80_000.0f32, 20_000u32), (5_000.0, 20_000), (1e6, 1_000)] {
        let mut r = Regulator::new(target);
        let mut last = 0.0f32;
        for _ in 0..200 {
            last = r.update(polygons(c, r.tolerance()));
        }
        let p = polygons(c, last) as f32;
        assert!(
            (p / target as f32 - 1.0).abs() <= 0.011,
            "{c}: {p} for {target}"
        );
        // `last` is about `sqrt(c / target)`.
        let want = c / target as f32;
        assert!(
            (last * last / want - 1.0).abs() < 0.02,
            "{last}² for {want}"
        );
    }
}

#[test]
fn approaches_from_one_side_without_overshoot() {
    let mut r = Regulator::new(20_000);
    let c = 20_000.0 * 9.0; // settles at 3 px
    let mut signs = 0;
    let mut last_sign = 0.0f32;
    for _ in 0..300 {
        let p = polygons(c, r.tolerance());
        r.update(p);
        let s = r.last_step() - 1.0;
        if s != 0.0 {
            if last_sign != 0.0 && s.signum() != last_sign {
                signs += 1;
            }
            last_sign = s.signum();
        }
    }
    assert_eq!(signs, 0, "the step never changes direction on a still view");
    assert!(
        (r.tolerance() / 3.0 - 1.0).abs() < 0.01,
        "{}",
        r.tolerance()
    );
}

#[test]
fn holds_in_the_dead_band_and_clamps_each_step() {
    let mut r = Regulator::new(10_000);
    assert_eq!(r.update(10_050), 1.0);
    assert_eq!(r.last_step(), 1.0);
    let t = r.update(u32::MAX);
    assert!((t - Regulator::DEFAULT_MAX_STEP).abs() < 1e-6, "{t}");
    let mut r = Regulator::new(10_000);
    let t = r.update(0);
    assert!((t - 1.0 / Regulator::DEFAULT_MAX_STEP).abs() < 1e-6, "{t}");
}

#[test]
fn respects_floor_and_ceiling() {
    let mut r = Regulator::new(1_000).with_limits(0.5, 4.0);
    for _ in 0..100 {
        r.update(0);
    }
    assert_eq!(r.tolerance(), 0.5);
    for _ in 0..100 {
        r.update(u32::MAX);
    }
    assert_eq!(r.tolerance(), 4.0);
    let r = Regulator::new(1).with_limits(8.0, 2.0);
    assert_eq!(
        r.tolerance(),
        8.0,
        "a ceiling below the floor is raised to it"
    );
}

#[test]
fn never_gives_a_tolerance_that_is_not_a_positive_number() {
    let odd = [
        0.0f32,
        -1.0,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        1e-30,
        1e30,
    ];
    let counts = [0u32, 1, 7, 20_000, u32::MAX];
    for &a in &odd {
        for &b in &odd {
            let mut r = Regulator::new(0)
                .with_tolerance(a)
                .with_gain(b)
                .with_dead_band(a)
                .with_max_step(b)
                .with_limits(a, b);
            for &n in counts.iter().chain(counts.iter().rev()) {
                let t = r.update(n);
                assert!(t.is_finite() && t > 0.0, "{a} {b} {n}: {t}");
                assert_eq!(t, r.tolerance());
                assert!(r.last_step().is_finite() && r.last_step() > 0.0);
            }
        }
    }
}

/// Sign changes of a regulator's steps over a run (steps of 1 left out).
struct Signs {
    last: f32,
    changes: u32,
}

impl Signs {
    fn new() -> Self {
        Self {
            last: 0.0,
            changes: 0,
        }
    }

    fn step(&mut self, r: &Regulator) {
        let s = r.last_step() - 1.0;
        if s != 0.0 {
            if self.last != 0.0 && s.signum() != self.last {
                self.changes += 1;
            }
            self.last = s.signum();
        }
    }
}

/// A front of `exp(c) / tolerance^a` polygons.
fn front(c: f32, a: f32, tolerance: f32) -> u32 {
    libm::expf(c - a * libm::logf(tolerance)).min(u32::MAX as f32) as u32
}

fn held(p: u32, target: u32, within: f32) -> bool {
    (p as f32 / target as f32 - 1.0).abs() <= within
}

/// A view that offers 1.5% more polygons each frame, to a front that responds weakly:
/// Hoppe's rule alone trails it by `0.015 / (0.5 · 0.4)`, 7.5%; the drift estimate
/// follows it within the dead band, stepping one way only.
#[test]
fn follows_a_view_that_offers_more_each_frame() {
    let (target, a) = (20_000u32, 0.5f32);
    let c0 = libm::logf(target as f32) + a * libm::logf(0.5);
    let mut r = Regulator::new(target);
    let mut signs = Signs::new();
    let mut plain = Regulator::new(target).with_gain(0.4);
    let mut plain_worst = 0.0f32;
    for k in 0..150 {
        let c = c0 + 0.015 * k as f32;
        let p = front(c, a, r.tolerance());
        if k >= 30 {
            assert!(held(p, target, 0.02), "frame {k}: {p}");
        }
        r.update(p);
        if k >= 10 {
            signs.step(&r);
        }
        // Hoppe's rule: the same step without the model's estimates.
        let q = front(c, a, plain.tolerance());
        if k >= 30 {
            plain_worst = plain_worst.max(q as f32 / target as f32 - 1.0);
        }
        let step = libm::powf(q.max(1) as f32 / target as f32, 0.4).clamp(1.0 / 1.15, 1.15);
        plain = plain.with_tolerance(plain.tolerance() * step);
    }
    assert_eq!(signs.changes, 0);
    assert!(plain_worst > 0.05, "Hoppe's rule trails by {plain_worst}");
    assert!(
        (r.drift() / libm::expf(0.015) - 1.0).abs() < 0.005,
        "{}",
        r.drift()
    );
}

/// A front near full resolution barely responds; the regulator learns how little and
/// settles on its target from one side.
#[test]
fn learns_a_weak_response() {
    let (target, a) = (20_000u32, 0.25f32);
    let c = libm::logf(target as f32) + a * libm::logf(0.3);
    let mut r = Regulator::new(target);
    let mut signs = Signs::new();
    for _ in 0..60 {
        r.update(front(c, a, r.tolerance()));
        signs.step(&r);
    }
    let p = front(c, a, r.tolerance());
    assert!(held(p, target, 0.011), "{p}");
    assert_eq!(signs.changes, 0);
    assert!((r.response() - a).abs() < 0.1, "{}", r.response());
}

/// An amortised front shows a change of tolerance over three frames; told so, the
/// regulator settles without oscillating.
#[test]
fn an_amortised_count_settles_without_oscillating() {
    let (target, a) = (20_000u32, 1.0f32);
    let c = libm::logf(target as f32) + a * libm::logf(0.4);
    let mut r = Regulator::new(target).with_response_frames(3);
    assert_eq!(r.response_frames(), 3);
    let mut signs = Signs::new();
    let mut recent = [0.0f32; 3];
    for k in 0..120 {
        recent[k % 3] = libm::logf(r.tolerance());
        let shown = recent.iter().take((k + 1).min(3)).sum::<f32>() / (k + 1).min(3) as f32;
        r.update(front(c, a, libm::expf(shown)));
        signs.step(&r);
    }
    assert!(
        (r.tolerance() / 0.4 - 1.0).abs() < 0.02,
        "{}",
        r.tolerance()
    );
    assert_eq!(signs.changes, 0);
    assert_eq!(
        Regulator::new(1).with_response_frames(0).response_frames(),
        1
    );
    assert_eq!(
        Regulator::new(1)
            .with_response_frames(200)
            .response_frames(),
        Regulator::MAX_RESPONSE_FRAMES
    );
}

/// Collapses that wait 16 frames for their coarsen morphs keep the screen's count up
/// after a raise of tolerance. Regulated on the screen's count, the regulator keeps
/// raising meanwhile, far past the tolerance it settles at; told the settled count, it
/// overshoots less than half as far.
#[test]
fn waiting_collapses_do_not_make_it_overshoot() {
    let (target, a) = (20_000u32, 1.0f32);
    let c = libm::logf(target as f32) + a * libm::logf(2.0);
    let run = |settling: bool| {
        let mut r = Regulator::new(target).with_tolerance(1.6);
        let mut signs = Signs::new();
        let mut settled = [u32::MAX; 16];
        let mut highest = 0.0f32;
        for k in 0..200 {
            settled[k % 16] = front(c, a, r.tolerance());
            // A split shows at once, a collapse 16 frames late.
            let shown = *settled
                .iter()
                .filter(|&&x| x != u32::MAX)
                .max()
                .unwrap_or(&0);
            if settling {
                r.update_settling(shown, settled[k % 16]);
            } else {
                r.update(shown);
            }
            signs.step(&r);
            highest = highest.max(r.tolerance());
        }
        (r.tolerance(), highest, signs.changes)
    };
    let (t, highest, changes) = run(true);
    assert!((t / 2.0 - 1.0).abs() < 0.02, "{t}");
    assert!(changes <= 1, "{changes}");
    let (plain_t, plain_highest, _) = run(false);
    assert!((plain_t / 2.0 - 1.0).abs() < 0.02, "{plain_t}");
    assert!(
        2.0 * highest < plain_highest,
        "settling {highest}, screen's count {plain_highest}"
    );
}

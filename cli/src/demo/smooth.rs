//! The demo's smoothness figures: popping with and without geomorphs, and the regulated
//! flight's hold on its polygon target, against their targets.

use std::fmt::Write as _;

use super::flights::{Flights, REGULATED_TARGET, SPEED_LIMIT_PX_S};
use crate::flyover::pilot::{HELD_WITHIN, SETTLING_FRAMES};
use crate::flyover::Flyover;

/// Acceptance: the largest on-screen move per frame of a vertex, in pixels.
const MAX_JUMP_PX: f32 = 1.0;
/// Acceptance: the 99th percentile of the on-screen moves per frame, in pixels.
const P99_JUMP_PX: f32 = 0.25;
/// Acceptance: the share of frames after the first 30 within 5% of the target.
const HELD_SHARE: f64 = 0.95;

fn verdict(ok: bool) -> &'static str {
    if ok {
        "met"
    } else {
        "not met"
    }
}

/// The worst camera's figure of a flight (0 without pilots).
fn worst(f: &Flyover, of: impl Fn(&crate::flyover::PopMeter) -> f32) -> f32 {
    f.pilots.iter().map(|p| of(&p.meter)).fold(0.0, f32::max)
}

/// The most morphs any camera of a flight held at once.
fn most_morphing(f: &Flyover) -> u32 {
    f.pilots.iter().map(|p| p.max_morphing).max().unwrap_or(0)
}

/// The mean active polygons per camera and frame of a flight.
fn mean_polygons(f: &Flyover) -> f64 {
    crate::flyover::summarise(&f.flight.records).active_mean
}

/// The least share of held frames over the regulated flight's cameras.
fn least_held(f: &Flyover) -> f64 {
    f.pilots
        .iter()
        .zip(&f.flight.records)
        .filter_map(|(p, r)| p.held_share(r))
        .fold(1.0, f64::min)
}

/// The results table's rows for popping and regulation.
pub(super) fn rows(f: &Flights) -> String {
    let mut s = String::new();
    let (m, u) = (&f.morphed, &f.unmorphed);
    for (what, max, p99) in [
        (
            "on-screen move per frame of a vertex that refinement moves",
            crate::flyover::PopMeter::max_px as fn(&crate::flyover::PopMeter) -> f32,
            crate::flyover::PopMeter::p99_px as fn(&crate::flyover::PopMeter) -> f32,
        ),
        (
            "its part along the vertex normal (how far the surface moves)",
            crate::flyover::PopMeter::surface_max_px,
            crate::flyover::PopMeter::surface_p99_px,
        ),
    ] {
        let (mm, mp, um, up) = (worst(m, max), worst(m, p99), worst(u, max), worst(u, p99));
        let _ = writeln!(
            s,
            "| popping, {what}: max / p99, worst camera, 4 cameras at 1 px with geomorphs (without) | {mm:.2} px / {mp:.3} px ({um:.1} px / {up:.2} px) | <= {MAX_JUMP_PX} px / <= {P99_JUMP_PX} px | {} |",
            verdict(mm <= MAX_JUMP_PX && mp <= P99_JUMP_PX)
        );
    }
    let l = &f.speed_limited;
    let (lm, lp) = (worst(l, |p| p.max_px()), worst(l, |p| p.p99_px()));
    let _ = writeln!(
        s,
        "| popping with a {SPEED_LIMIT_PX_S} px/s screen speed limit (not a default): vertex move max / p99, worst camera (surface move; most morphs live at once, against the defaults'; mean polygons per camera against the defaults') | {lm:.2} px / {lp:.3} px ({:.2} px / {:.3} px; {} vs {}; {:.0} vs {:.0}) | <= {MAX_JUMP_PX} px / <= {P99_JUMP_PX} px | {} |",
        worst(l, |p| p.surface_max_px()),
        worst(l, |p| p.surface_p99_px()),
        most_morphing(l),
        most_morphing(m),
        mean_polygons(l),
        mean_polygons(m),
        verdict(lm <= MAX_JUMP_PX && lp <= P99_JUMP_PX)
    );
    let held = least_held(&f.regulated);
    let _ = writeln!(
        s,
        "| frames after the first {SETTLING_FRAMES} within {:.0}% of a {REGULATED_TARGET}-polygon target, regulated tolerance, least of 4 cameras | {:.1}% ({}) | >= {:.0}% on every camera | {} |",
        HELD_WITHIN * 100.0,
        held * 100.0,
        per_camera_held(&f.regulated),
        HELD_SHARE * 100.0,
        verdict(held >= HELD_SHARE)
    );
    s
}

/// Each camera's share of held frames, in words.
fn per_camera_held(f: &Flyover) -> String {
    f.names
        .iter()
        .zip(f.pilots.iter().zip(&f.flight.records))
        .map(|(n, (p, r))| {
            let out = p.out_of_reach_share(r).unwrap_or(0.0);
            let held = format!("{n} {:.1}%", 100.0 * p.held_share(r).unwrap_or(0.0));
            if out > 0.0 {
                format!("{held}, out of reach at the floor {:.1}%", 100.0 * out)
            } else {
                held
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The report's section: a table per camera, then the three flights' own reports.
pub(super) fn section(s: &mut String, f: &Flights) {
    let (m, u, g) = (&f.morphed, &f.unmorphed, &f.regulated);
    let _ = writeln!(
        s,
        "## Popping and regulation\n\nThe four routes flown once more, a state per camera on \
         one thread, with a pilot per camera that measures, between the timed refinement and \
         emission, how far each drawn vertex that refinement moves travels on the screen in a \
         frame (projected with that frame's view, in view and facing the eye; without \
         geomorphs a split moves the floating child from its parent's point to its own at \
         once, with them it glides over {:.0} frames at 60 Hz), and the part of that move \
         along the vertex's normal, which is how far the surface itself moves. Geomorphs at 1 \
         px (morph memory for {} morphs per camera), the same without, and regulated to \
         {REGULATED_TARGET} polygons (geomorphs on, budgeted to the target plus 25%):\n",
        caveclod_core::RefineParams::default().refine_morph_s * 60.0,
        m.max_morphs
    );
    let _ = writeln!(
        s,
        "| camera | max / p99 move, geomorphs | without | max / p99 surface move, geomorphs | without | morphs dropped | refine p99 | held ±5% | out of reach at the floor | sign changes | tolerance mean (min..max) |\n\
         |---|---|---|---|---|---|---|---|---|---|---|"
    );
    for (c, name) in m.names.iter().enumerate() {
        let (Some(pm), Some(pu), Some(pg)) = (m.pilots.get(c), u.pilots.get(c), g.pilots.get(c))
        else {
            continue;
        };
        let (rm, rg) = (&m.flight.records[c], &g.flight.records[c]);
        let (mean, min, max) = pg.tolerance_range();
        let _ = writeln!(
            s,
            "| {name} | {:.2} / {:.3} px | {:.1} / {:.2} px | {:.2} / {:.3} px | {:.1} / {:.2} px | {} of {} | {:.3} ms | {:.1}% | {:.1}% | {} | {mean:.3} px ({min:.3}..{max:.3}) |",
            pm.meter.max_px(),
            pm.meter.p99_px(),
            pu.meter.max_px(),
            pu.meter.p99_px(),
            pm.meter.surface_max_px(),
            pm.meter.surface_p99_px(),
            pu.meter.surface_max_px(),
            pu.meter.surface_p99_px(),
            rm.morphs_dropped,
            rm.morphs_started + rm.morphs_dropped,
            rm.refine_ms_p99(),
            100.0 * pg.held_share(rg).unwrap_or(0.0),
            100.0 * pg.out_of_reach_share(rg).unwrap_or(0.0),
            pg.sign_changes(),
        );
    }
    let _ = writeln!(s);
    for (title, fl) in [
        ("Geomorphs at 1 px", m),
        ("Without geomorphs at 1 px", u),
        ("Regulated", g),
        ("Held to a screen speed", &f.speed_limited),
    ] {
        let _ = writeln!(s, "### {title}\n\n```text\n{}```\n", fl.human());
    }
}

//! The greedy predictive polygon-budget controller (Southern & Gain §5.1).
//!
//! Every instance `j` has a `T_j` from its distance; all of them are offset by one global
//! `T_bias`. The scene's polygon count `q(T_bias)` is then a step function that never increases
//! as the bias grows, with a step wherever some `T_j + T_bias` crosses a partition boundary.
//! The paper's steps 1–8: count `q`; if `|p - q| > ε`, build for every object the bias change
//! that takes it to its next coarser level (`D_next`, removing `P_next` polygons) or finer
//! level (`D_prev`, adding `P_prev`), sort on the one that moves `q` towards `p`, accumulate the
//! polygon changes in that order until the sign of `p - q` flips, apply that bias change,
//! recount, repeat.
//!
//! This implementation walks the same steps exactly, with one refinement: instead of
//! re-sorting after each round it keeps the entries in a binary heap (in caller scratch, one
//! entry per instance), so after an object crosses one boundary its next crossing (the next
//! level) re-enters the order at once. It stops at the first bias — the least correction —
//! where `|p - q| ≤ ε`. Because `q` is monotone in the bias, if that walk jumps over the
//! window `[p - ε, p + ε]` (several objects crossing at the same bias, or single steps larger
//! than `ε`) or runs out of crossings, no bias reaches the budget: the controller says so
//! (`reachable = false`) and keeps the count closest to `p`. Each crossing moves one object one
//! or more levels in one direction, so the walk ends after at most `instances × levels`
//! crossings: it always terminates.
//!
//! The per-frame cap on `|T_change|` (0.01 or 0.1 in the paper) limits popping while the viewer
//! is still; callers lift it (`f32::INFINITY`) while the viewer moves (§5.4).

use super::partition::{GMeshError, LevelMorph, Partitions};

/// One g-mesh as the controller sees it: its partitions and the polygons of each level.
#[derive(Clone, Copy, Debug)]
pub struct LodModel<'a> {
    pub(super) partitions: Partitions<'a>,
    pub(super) level_polygons: &'a [u32],
}

impl<'a> LodModel<'a> {
    /// `level_polygons[i] = |c_i|`, one per level of `partitions`.
    pub fn new(partitions: Partitions<'a>, level_polygons: &'a [u32]) -> Result<Self, GMeshError> {
        if level_polygons.len() != partitions.levels() {
            return Err(GMeshError::LengthMismatch {
                what: "level_polygons",
                expected: partitions.levels(),
                got: level_polygons.len(),
            });
        }
        Ok(Self {
            partitions,
            level_polygons,
        })
    }

    /// The partitions.
    pub fn partitions(&self) -> Partitions<'a> {
        self.partitions
    }

    /// `|c_i|` per level, finest first.
    pub fn level_polygons(&self) -> &'a [u32] {
        self.level_polygons
    }

    /// The paper's tolerance `ε = |c_0| - |c_1|`: the most one object changes the count
    /// when it crosses the finest boundary.
    pub fn default_epsilon(&self) -> u64 {
        let c = self.level_polygons;
        u64::from(c[0]).saturating_sub(u64::from(c[1]))
    }

    /// Polygons drawn at global parameter `t`.
    pub fn polygons_at(&self, t: f32) -> u32 {
        self.level_polygons[self.partitions.level(t)]
    }

    /// Level and morph factor at global parameter `t`.
    pub fn level_morph(&self, t: f32) -> LevelMorph {
        self.partitions.level_morph(t)
    }
}

/// One object in the scene: which model, and its `T` from distance before the bias.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodInstance {
    /// Index into the controller's models.
    pub model: u32,
    /// `T` from distance (see [`super::t_from_distance`]), without `T_bias`.
    pub t: f32,
    /// Culled instances draw nothing and are not adjusted.
    pub visible: bool,
}

/// What the controller aims for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlParams {
    /// Polygon budget `p`.
    pub budget: u64,
    /// Tolerance `ε`: counts within `p ± ε` are left alone (no oscillation).
    pub epsilon: u64,
    /// Largest `|T_change|` this frame; `f32::INFINITY` while the viewer moves.
    pub max_change: f32,
}

/// One entry of the controller's scratch (one per instance); contents are private.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ControlEntry {
    /// Heap key: the bias at which the crossing happens, negated when refining, so the
    /// nearest crossing is the smallest key either way.
    key: f32,
    /// The bias at which the instance crosses.
    bias: f32,
    /// The instance.
    instance: u32,
    /// Its level before the crossing.
    level: u32,
}

/// The controller's decision for one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlOutcome {
    /// The new `T_bias` (the old one plus `change`).
    pub bias: f32,
    /// `T_change` applied this frame.
    pub change: f32,
    /// Polygons before the change.
    pub polygons_before: u64,
    /// Polygons at the new bias (recounted, the paper's step 6).
    pub polygons: u64,
    /// `|p - q| ≤ ε` at the new bias.
    pub within_epsilon: bool,
    /// Some bias reaches `p ± ε` (false: the budget is out of reach — every object already at
    /// its finest or coarsest level, or the count jumps over the window).
    pub reachable: bool,
    /// The per-frame cap on `|T_change|` limited the change.
    pub capped: bool,
    /// Boundary crossings the walk examined.
    pub crossings: u32,
}

/// Polygons of all visible instances at `bias`.
pub fn scene_polygons(
    models: &[LodModel<'_>],
    instances: &[LodInstance],
    bias: f32,
) -> Result<u64, GMeshError> {
    let mut q = 0u64;
    for (j, inst) in instances.iter().enumerate() {
        if !inst.visible {
            continue;
        }
        let model = model_of(models, j, inst)?;
        q += u64::from(model.polygons_at(inst.t + bias));
    }
    Ok(q)
}

fn model_of<'m, 'a>(
    models: &'m [LodModel<'a>],
    j: usize,
    inst: &LodInstance,
) -> Result<&'m LodModel<'a>, GMeshError> {
    models
        .get(inst.model as usize)
        .ok_or(GMeshError::UnknownModel {
            instance: j,
            model: inst.model,
        })
}

/// Runs the controller for one frame from the current `bias`; `scratch` needs one entry per
/// instance. Allocates nothing.
pub fn control(
    models: &[LodModel<'_>],
    instances: &[LodInstance],
    bias: f32,
    params: &ControlParams,
    scratch: &mut [ControlEntry],
) -> Result<ControlOutcome, GMeshError> {
    if !bias.is_finite() {
        return Err(GMeshError::NotFinite {
            what: "bias",
            index: 0,
        });
    }
    if let Some(index) = instances.iter().position(|i| !i.t.is_finite()) {
        return Err(GMeshError::NotFinite {
            what: "instance t",
            index,
        });
    }
    if scratch.len() < instances.len() {
        return Err(GMeshError::ScratchTooSmall {
            needed: instances.len(),
            got: scratch.len(),
        });
    }
    let (p, eps) = (params.budget, params.epsilon);
    let within = |q: u64| q.abs_diff(p) <= eps;
    let q0 = scene_polygons(models, instances, bias)?;
    let mut outcome = ControlOutcome {
        bias,
        change: 0.0,
        polygons_before: q0,
        polygons: q0,
        within_epsilon: within(q0),
        reachable: true,
        capped: false,
        crossings: 0,
    };
    if outcome.within_epsilon {
        return Ok(outcome);
    }
    let coarsen = q0 > p;

    // Steps 3–4: every visible object's nearest crossing in the needed direction.
    let mut heap = Heap {
        entries: scratch,
        len: 0,
    };
    for (j, inst) in instances.iter().enumerate() {
        if !inst.visible {
            continue;
        }
        let model = model_of(models, j, inst)?;
        let level = model.partitions.level(inst.t + bias);
        if let Some(e) = crossing(model, inst.t, j as u32, level, coarsen) {
            heap.push(e);
        }
    }

    // Step 5, repeated: accumulate crossings in order until q reaches p ± ε or passes it.
    let mut q = q0;
    let mut best = (q0.abs_diff(p), bias);
    let mut found = false;
    while let Some(first) = heap.peek() {
        let at = first.bias;
        // All crossings at exactly this bias happen together.
        while let Some(e) = heap.peek() {
            if e.bias != at {
                break;
            }
            heap.pop();
            outcome.crossings += 1;
            let inst = &instances[e.instance as usize];
            let model = model_of(models, e.instance as usize, inst)?;
            let new_level = model.partitions.level(inst.t + at);
            let (old, new) = (
                u64::from(model.level_polygons[e.level as usize]),
                u64::from(model.level_polygons[new_level]),
            );
            q = q - old.min(q) + new;
            if let Some(next) = crossing(model, inst.t, e.instance, new_level, coarsen) {
                heap.push(next);
            }
        }
        let d = q.abs_diff(p);
        if d < best.0 || (d == best.0 && q <= p) {
            best = (d, at);
        }
        if within(q) {
            found = true;
            break;
        }
        let passed = if coarsen { q < p } else { q > p };
        if passed {
            break;
        }
    }
    outcome.reachable = found;

    // Step 8 with the per-frame cap, then step 6: recount at the bias actually applied.
    // The bias found is used as it is (the old bias plus the difference could round to a
    // neighbouring float on the other side of a boundary); only a capped change is added.
    outcome.bias = best.1;
    outcome.change = best.1 - bias;
    if outcome.change.abs() > params.max_change {
        outcome.change = params.max_change.max(0.0).copysign(outcome.change);
        outcome.bias = bias + outcome.change;
        outcome.capped = true;
    }
    outcome.polygons = scene_polygons(models, instances, outcome.bias)?;
    outcome.within_epsilon = within(outcome.polygons);
    Ok(outcome)
}

/// The bias at which instance `j` (at `T = t + bias`, level `level`) leaves its level in the
/// given direction, or `None` at the end of the range.
fn crossing(
    model: &LodModel<'_>,
    t: f32,
    j: u32,
    level: usize,
    coarsen: bool,
) -> Option<ControlEntry> {
    let parts = &model.partitions;
    if coarsen {
        if level >= parts.coarsest() {
            return None;
        }
        // Smallest bias with t + bias > R_{level+1}.
        let r = parts.boundary(level + 1);
        let mut b = r - t;
        let step = spacing(t, r, b);
        let mut tries = 0;
        while t + b <= r {
            b += step;
            tries += 1;
            if tries > 64 || !b.is_finite() {
                return None;
            }
        }
        Some(ControlEntry {
            key: b,
            bias: b,
            instance: j,
            level: level as u32,
        })
    } else {
        if level == 0 {
            return None;
        }
        // Largest bias with t + bias <= R_level.
        let r = parts.boundary(level);
        let mut b = r - t;
        let step = spacing(t, r, b);
        let mut tries = 0;
        while t + b > r {
            b -= step;
            tries += 1;
            if tries > 64 || !b.is_finite() {
                return None;
            }
        }
        Some(ControlEntry {
            key: -b,
            bias: b,
            instance: j,
            level: level as u32,
        })
    }
}

/// The spacing of `f32` values around `T = t + bias` when it is near `r`: the step by which a
/// crossing bias is nudged until `t + bias` lands on the wanted side of `r`: the coarsest
/// spacing of the three values involved, so each step changes both the bias and the sum
/// (stepping by the bias's own, possibly much finer, spacing could take thousands of steps;
/// a finer step than the bias's own would not change it at all).
fn spacing(t: f32, r: f32, b: f32) -> f32 {
    let m = t.abs().max(r.abs()).max(b.abs()).max(f32::MIN_POSITIVE);
    f32::from_bits(m.to_bits() + 1) - m
}

/// A binary min-heap on `key` over caller memory.
struct Heap<'s> {
    entries: &'s mut [ControlEntry],
    len: usize,
}

impl Heap<'_> {
    fn less(&self, a: usize, b: usize) -> bool {
        self.entries[a].key.total_cmp(&self.entries[b].key).is_lt()
    }

    fn push(&mut self, e: ControlEntry) {
        // One entry per instance at a time: the caller's scratch holds them all.
        if self.len >= self.entries.len() {
            return;
        }
        let mut i = self.len;
        self.entries[i] = e;
        self.len += 1;
        while i > 0 {
            let parent = (i - 1) / 2;
            if !self.less(i, parent) {
                break;
            }
            self.entries.swap(i, parent);
            i = parent;
        }
    }

    fn peek(&self) -> Option<ControlEntry> {
        (self.len > 0).then(|| self.entries[0])
    }

    fn pop(&mut self) -> Option<ControlEntry> {
        if self.len == 0 {
            return None;
        }
        let top = self.entries[0];
        self.len -= 1;
        self.entries[0] = self.entries[self.len];
        let mut i = 0;
        loop {
            let (l, r) = (2 * i + 1, 2 * i + 2);
            let mut m = i;
            if l < self.len && self.less(l, m) {
                m = l;
            }
            if r < self.len && self.less(r, m) {
                m = r;
            }
            if m == i {
                break;
            }
            self.entries.swap(i, m);
            i = m;
        }
        Some(top)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    const B: [f32; 4] = [0.0, 0.2, 0.5, 1.0];
    const C: [u32; 4] = [1000, 500, 250, 120];

    fn model() -> LodModel<'static> {
        LodModel::new(Partitions::new(&B).unwrap(), &C).unwrap()
    }

    fn inst(t: f32) -> LodInstance {
        LodInstance {
            model: 0,
            t,
            visible: true,
        }
    }

    #[test]
    fn figure_7_coarsens_the_nearest_objects_first() {
        let models = [model()];
        // Four objects in range 0, at different distances from R_1 = 0.2.
        let insts = [inst(0.05), inst(0.19), inst(0.15), inst(0.1)];
        let mut scratch = [ControlEntry::default(); 4];
        // 4000 polygons; budget 3000 with ε 500: two objects must cross (0.19, then 0.15).
        let params = ControlParams {
            budget: 3000,
            epsilon: 100,
            max_change: f32::INFINITY,
        };
        let o = control(&models, &insts, 0.0, &params, &mut scratch).unwrap();
        assert_eq!(o.polygons_before, 4000);
        assert_eq!(o.polygons, 3000);
        assert!(o.within_epsilon && o.reachable && !o.capped);
        assert!(o.change > 0.05 && o.change < 0.0501, "{}", o.change);
        // Refining back from there to 4000 returns the bias to at most 0.01.
        let back = ControlParams {
            budget: 4000,
            ..params
        };
        let o2 = control(&models, &insts, o.bias, &back, &mut scratch).unwrap();
        assert_eq!(o2.polygons, 4000);
        assert!(o2.bias <= 0.0101, "{}", o2.bias);
    }

    #[test]
    fn within_epsilon_changes_nothing_and_the_cap_holds() {
        let models = [model()];
        let insts = [inst(0.1), inst(0.3)];
        let mut scratch = [ControlEntry::default(); 2];
        let p = ControlParams {
            budget: 1400,
            epsilon: 200,
            max_change: 0.01,
        };
        let o = control(&models, &insts, 0.0, &p, &mut scratch).unwrap();
        assert_eq!((o.change, o.polygons), (0.0, 1500));
        let p = ControlParams {
            budget: 500,
            epsilon: 10,
            max_change: 0.01,
        };
        let o = control(&models, &insts, 0.0, &p, &mut scratch).unwrap();
        assert!(o.capped && o.change == 0.01 && o.reachable && !o.within_epsilon);
    }

    #[test]
    fn unreachable_budgets_are_reported() {
        let models = [model()];
        let insts = [inst(0.1), inst(0.1)];
        let mut scratch = [ControlEntry::default(); 2];
        // Below the coarsest scene (240).
        let p = ControlParams {
            budget: 100,
            epsilon: 10,
            max_change: f32::INFINITY,
        };
        let o = control(&models, &insts, 0.0, &p, &mut scratch).unwrap();
        assert!(!o.reachable && o.polygons == 240);
        // Both objects cross together: 2000 -> 1000 jumps over 1500 ± 10.
        let p = ControlParams {
            budget: 1500,
            epsilon: 10,
            max_change: f32::INFINITY,
        };
        let o = control(&models, &insts, 0.0, &p, &mut scratch).unwrap();
        assert!(!o.reachable);
        assert!(o.polygons == 1000 || o.polygons == 2000);
    }

    #[test]
    fn bad_input_is_an_error() {
        let models = [model()];
        let mut scratch = [ControlEntry::default(); 1];
        let p = ControlParams {
            budget: 1,
            epsilon: 0,
            max_change: 1.0,
        };
        let two = [inst(0.0), inst(0.0)];
        assert!(matches!(
            control(&models, &two, 0.0, &p, &mut scratch),
            Err(GMeshError::ScratchTooSmall { needed: 2, got: 1 })
        ));
        let bad = [LodInstance {
            model: 3,
            t: 0.0,
            visible: true,
        }];
        assert!(matches!(
            control(&models, &bad, 0.0, &p, &mut scratch),
            Err(GMeshError::UnknownModel {
                instance: 0,
                model: 3
            })
        ));
        assert!(matches!(
            control(&models, &[inst(f32::NAN)], 0.0, &p, &mut scratch),
            Err(GMeshError::NotFinite { .. })
        ));
    }
}

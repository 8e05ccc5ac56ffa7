//! `cargo xtask graph`: each crate's modules in layers, bottom first, as the imports order
//! them, and whatever circles break the order.

use std::collections::{BTreeMap, BTreeSet};

use super::{problems, CrateGraph};

/// The parts of `module` (its own file as `(self)`, and each child module) in layers: a part
/// takes items only from parts of lower layers. Parts in a circle are left out.
pub fn layers(g: &CrateGraph, module: &[String]) -> Vec<Vec<String>> {
    let part_of = |file: usize| -> Option<String> {
        let m = &g.files[file].module;
        if !m.starts_with(module) {
            return None;
        }
        Some(
            m.get(module.len())
                .cloned()
                .unwrap_or_else(|| "(self)".into()),
        )
    };
    let mut below: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in 0..g.files.len() {
        if let Some(p) = part_of(f) {
            below.entry(p).or_default();
        }
    }
    for &(a, b) in g.edges.keys() {
        if let (Some(pa), Some(pb)) = (part_of(a), part_of(b)) {
            if pa != pb {
                below.entry(pa).or_default().insert(pb);
            }
        }
    }
    let mut placed: BTreeSet<String> = BTreeSet::new();
    let mut out = Vec::new();
    loop {
        let layer: Vec<String> = below
            .iter()
            .filter(|(p, deps)| !placed.contains(*p) && deps.iter().all(|d| placed.contains(d)))
            .map(|(p, _)| p.clone())
            .collect();
        if layer.is_empty() {
            return out;
        }
        placed.extend(layer.iter().cloned());
        out.push(layer);
    }
}

/// The report of one crate: its modules' layers and its problems.
pub fn describe(g: &CrateGraph) -> String {
    let mut modules: BTreeSet<Vec<String>> = BTreeSet::new();
    for f in &g.files {
        for k in 0..f.module.len() {
            modules.insert(f.module[..k].to_vec());
        }
    }
    let mut text = format!(
        "{}: {} files, {} file-to-file imports\n",
        g.name,
        g.files.len(),
        g.edges.len()
    );
    for m in modules {
        let name = if m.is_empty() {
            "crate".to_string()
        } else {
            m.join("::")
        };
        let layers: Vec<String> = layers(g, &m).iter().map(|l| l.join(" ")).collect();
        text.push_str(&format!("  {name}: {}\n", layers.join(" < ")));
    }
    for p in problems(g) {
        text.push_str(&format!("  PROBLEM {p}\n"));
    }
    text
}

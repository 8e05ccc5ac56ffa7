//! What a bake knows that the hierarchy does not record.
//!
//! What the file cannot tell (the input's triangle count, the surface groups before
//! colouring, the repairs, the bake time) travels in an `INFO` section of UTF-8 JSON, which
//! readers that do not know it skip.

use caveclod_core::format::{ExtraSection, Tag};
use caveclod_core::Hierarchy;
use serde_json::{json, Map, Value};

use crate::weld::Repairs;

/// Tag of the bake-information section.
pub const INFO: Tag = Tag(*b"INFO");

/// What the bake knew that the hierarchy does not record.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BakeInfo {
    /// Triangles read from the input.
    pub input_triangles: u64,
    /// Surface groups before colouring.
    pub surface_groups: u64,
    /// Repairs by kind.
    pub repairs: Repairs,
    /// Wall time of the bake.
    pub bake_seconds: f64,
    /// Independent-set passes of the hierarchy build.
    pub passes: u32,
    /// What the import wants the user to know (skipped statements, a missing MTL file, ...),
    /// a sentence each.
    pub notes: Vec<String>,
}

impl BakeInfo {
    /// As the `INFO` section's JSON.
    pub fn to_json(&self) -> String {
        json!({
            "input_triangles": self.input_triangles,
            "surface_groups": self.surface_groups,
            "repairs": repairs_json(&self.repairs),
            "bake_seconds": self.bake_seconds,
            "passes": self.passes,
            "notes": self.notes,
        })
        .to_string()
    }

    /// The section to write.
    pub fn section(json: &str) -> ExtraSection<'_> {
        ExtraSection {
            tag: INFO,
            record_size: 1,
            bytes: json.as_bytes(),
        }
    }

    /// Reads the section of a hierarchy, if it has one.
    pub fn read(h: &Hierarchy<'_>) -> Option<Self> {
        let v: Value = serde_json::from_slice(h.section(INFO)?).ok()?;
        let u = |k: &str| v.get(k).and_then(Value::as_u64).unwrap_or(0);
        let r = |k: &str| {
            v.get("repairs")
                .and_then(|r| r.get(k))
                .and_then(Value::as_u64)
                .unwrap_or(0)
        };
        Some(Self {
            input_triangles: u("input_triangles"),
            surface_groups: u("surface_groups"),
            repairs: Repairs {
                welded_positions: r("welded_positions"),
                degenerate_triangles: r("degenerate_triangles"),
                duplicate_triangles: r("duplicate_triangles"),
                non_manifold_edges: r("non_manifold_edges"),
                non_manifold_vertices: r("non_manifold_vertices"),
                computed_normals: r("computed_normals"),
                skipped_primitives: r("skipped_primitives"),
            },
            notes: v
                .get("notes")
                .and_then(Value::as_array)
                .map(|n| {
                    n.iter()
                        .filter_map(|s| s.as_str().map(str::to_owned))
                        .collect()
                })
                .unwrap_or_default(),
            bake_seconds: v.get("bake_seconds").and_then(Value::as_f64).unwrap_or(0.0),
            passes: u("passes") as u32,
        })
    }
}

/// The repairs as a JSON object, one key per kind.
pub fn repairs_json(r: &Repairs) -> Value {
    Value::Object(
        r.entries()
            .iter()
            .map(|&(k, n)| (k.to_string(), json!(n)))
            .collect::<Map<_, _>>(),
    )
}

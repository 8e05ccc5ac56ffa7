//! The figures `caveclod bake` and `caveclod info` print, with stable JSON keys for scripts.

use caveclod_bake::report::{repairs_json, BakeInfo};
use caveclod_core::format::materials::{AlphaMode, TextureRef};
use caveclod_core::gmesh::GMesh;
use caveclod_core::{CameraState, Hierarchy, MemoryReport, Octree};
use serde_json::{json, Map, Value};

/// The report of a hierarchy (and its bake information, when known), as a JSON object with
/// the stable keys.
///
/// `camera_bytes` is one camera able to reach full resolution anywhere; `paper_camera_bytes`
/// is the paper's `4n + 4p + 16 + 12n_a + 36p_a` for the same case (every leaf and every
/// polygon active), so the two compare like for like.
pub fn report(h: &Hierarchy<'_>, info: Option<&BakeInfo>) -> Map<String, Value> {
    let m = h.meta();
    let camera_bytes =
        4 * CameraState::words_needed(h) + std::mem::size_of::<CameraState<'static>>();
    let leaves = (m.node_count - m.split_count) as u64;
    let mem = MemoryReport::new(h, camera_bytes, leaves, m.polygon_count as u64);
    let mut o = Map::new();
    let info = info.cloned();
    o.insert(
        "input_triangles".into(),
        json!(info
            .as_ref()
            .map_or(m.polygon_count as u64, |i| i.input_triangles)),
    );
    o.insert("positions".into(), json!(m.position_count));
    o.insert("nodes".into(), json!(m.node_count));
    o.insert("polygons".into(), json!(m.polygon_count));
    o.insert("vertices".into(), json!(m.vertex_count));
    o.insert("surfaces".into(), json!(m.surface_count));
    o.insert(
        "surface_groups".into(),
        json!(info.as_ref().map(|i| i.surface_groups)),
    );
    o.insert("surface_group_ids".into(), json!(m.surface_group_count));
    o.insert("base_polygons".into(), json!(m.base_polygon_count));
    o.insert("depth".into(), json!(m.max_depth));
    o.insert("static_bytes".into(), json!(mem.static_bytes));
    o.insert("camera_bytes".into(), json!(mem.camera_bytes));
    o.insert("paper_static_bytes".into(), json!(mem.paper_static_bytes));
    o.insert("paper_camera_bytes".into(), json!(mem.paper_camera_bytes));
    o.insert(
        "repairs".into(),
        info.as_ref()
            .map_or(Value::Null, |i| repairs_json(&i.repairs)),
    );
    o.insert(
        "notes".into(),
        json!(info.as_ref().map_or(&[][..], |i| &i.notes[..])),
    );
    let (cells, filled) = h.vertex_table_fill();
    o.insert(
        "vertex_table_fill".into(),
        json!(filled as f64 / cells.max(1) as f64),
    );
    o.insert("materials".into(), materials_json(h));
    o.insert("vertex_colours".into(), json!(h.vertex_colours().is_some()));
    // g-mesh levels, when the file has them (their sections were validated here).
    match GMesh::from_hierarchy(h) {
        Ok(Some(g)) => {
            o.insert("gmesh_levels".into(), json!(g.levels()));
            o.insert("gmesh_level_polygons".into(), json!(g.level_polygons()));
            o.insert(
                "gmesh_boundaries".into(),
                json!(g.partitions().boundaries()),
            );
        }
        Ok(None) => {}
        Err(e) => {
            o.insert("gmesh_error".into(), json!(e.to_string()));
        }
    }
    // The out-of-core bake's multiresolution octree, when present (validated here too).
    match Octree::from_hierarchy(h) {
        Ok(Some(t)) => {
            let mut per_level = vec![0u64; t.level_count() as usize];
            for (id, n) in t.nodes().iter().enumerate() {
                let tris: u64 = t
                    .node_ranges(id as u32)
                    .iter()
                    .map(|r| u64::from(r.index_count / 3))
                    .sum();
                if let Some(l) = per_level.get_mut(n.level as usize) {
                    *l += tris;
                }
            }
            o.insert("octree_levels".into(), json!(t.level_count()));
            o.insert("octree_nodes".into(), json!(t.node_count()));
            o.insert("octree_vertices".into(), json!(t.vertices().len()));
            o.insert("octree_level_triangles".into(), json!(per_level));
            let mut errors: Vec<Vec<f32>> = vec![Vec::new(); t.level_count() as usize];
            for n in t.nodes() {
                if let Some(e) = errors.get_mut(n.level as usize) {
                    e.push(n.error);
                }
            }
            let medians: Vec<f32> = errors
                .iter_mut()
                .map(|e| {
                    e.sort_by(f32::total_cmp);
                    e.get(e.len() / 2).copied().unwrap_or(0.0)
                })
                .collect();
            o.insert("octree_level_median_error".into(), json!(medians));
        }
        Ok(None) => {}
        Err(e) => {
            o.insert("octree_error".into(), json!(e.to_string()));
        }
    }
    o
}

/// The surfaces' materials (an empty array for a file without): name, base colour, texture
/// (`{"path": ..}` or `{"embedded_bytes": .., "mime": ..}`, or null), alpha mode (with its
/// cutoff for `MASK`), double-sidedness.
fn materials_json(h: &Hierarchy<'_>) -> Value {
    let Some(materials) = h.materials() else {
        return json!([]);
    };
    materials
        .iter()
        .map(|m| {
            let texture = match m.texture {
                None => Value::Null,
                Some(TextureRef::Path(p)) => json!({ "path": p }),
                Some(TextureRef::Embedded { mime, bytes }) => {
                    json!({ "embedded_bytes": bytes.len(), "mime": mime })
                }
            };
            let cutoff = match m.alpha {
                AlphaMode::Mask { cutoff } => json!(shortest(cutoff)),
                _ => Value::Null,
            };
            json!({
                "name": m.name,
                "base_colour": m.base_colour.map(shortest),
                "texture": texture,
                "alpha_mode": m.alpha.name(),
                "alpha_cutoff": cutoff,
                "double_sided": m.double_sided,
            })
        })
        .collect()
}

/// `x` as the `f64` its shortest decimal form names (0.2, not 0.20000000298023224).
fn shortest(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(f64::from(x))
}

/// One material of [`materials_json`] on one line.
fn material_line(m: &Value) -> String {
    let texture = match &m["texture"] {
        Value::Null => "no texture".to_string(),
        t => match (t["path"].as_str(), t["mime"].as_str()) {
            (Some(p), _) => format!("texture {p}"),
            (None, Some(mime)) => format!("embedded {mime}, {} bytes", t["embedded_bytes"]),
            _ => t.to_string(),
        },
    };
    let alpha = match m["alpha_cutoff"].as_f64() {
        Some(c) => format!("{} {c}", m["alpha_mode"].as_str().unwrap_or("?")),
        None => m["alpha_mode"].as_str().unwrap_or("?").to_string(),
    };
    format!(
        "'{}', base colour {}, {texture}, {alpha}{}",
        m["name"].as_str().unwrap_or(""),
        m["base_colour"],
        if m["double_sided"] == json!(true) {
            ", double-sided"
        } else {
            ""
        }
    )
}

/// The report as aligned `key: value` lines for people; a material, and a note, per line
/// (no `notes` line when there are none).
pub fn human(o: &Map<String, Value>) -> String {
    let mut s = String::new();
    for (k, v) in o {
        if let (true, Value::Array(list)) = (k == "notes", v) {
            if list.is_empty() {
                continue;
            }
            s.push_str(&format!("{k:>20}: {}\n", list.len()));
            for n in list {
                s.push_str(&format!("{:>20}  {}\n", "", n.as_str().unwrap_or("")));
            }
            continue;
        }
        if let (true, Value::Array(list)) = (k == "materials", v) {
            s.push_str(&format!("{k:>20}: {}\n", list.len()));
            for (i, m) in list.iter().enumerate() {
                s.push_str(&format!(
                    "{:>20}: {}\n",
                    format!("material {i}"),
                    material_line(m)
                ));
            }
            continue;
        }
        let v = match v {
            Value::Object(m) => m
                .iter()
                .map(|(k, v)| format!("{k} {v}"))
                .collect::<Vec<_>>()
                .join(", "),
            Value::Null => "unknown".to_string(),
            v => v.to_string(),
        };
        s.push_str(&format!("{k:>20}: {v}\n"));
    }
    s
}

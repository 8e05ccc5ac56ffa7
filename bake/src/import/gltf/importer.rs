//! The mesh being built from a glTF document ([`Importer`]; the other files add its steps),
//! and what its accessors are read as.

use std::collections::HashMap;

use ::gltf::json;

use crate::import::error::Source;
use crate::import::options::ImportReport;
use crate::mesh::Mesh;

/// What an attribute accessor must look like.
pub(super) struct Expect {
    pub(super) semantic: &'static str,
    pub(super) dims: &'static [usize],
}

/// An accessor's values and components per element.
pub(super) struct Raw {
    pub(super) values: Vec<f64>,
    pub(super) dims: usize,
}

/// The mesh being built from a validated document and its loaded buffers.
pub(super) struct Importer<'a> {
    pub(super) source: &'a Source,
    pub(super) root: &'a json::Root,
    pub(super) buffers: &'a [Vec<u8>],
    pub(super) mesh: Mesh,
    /// Material index (`None`: no material) to surface id.
    pub(super) surfaces: HashMap<Option<usize>, u16>,
    pub(super) report: &'a mut ImportReport,
    pub(super) strip_joints: usize,
    pub(super) ignored_targets: usize,
    pub(super) ignored_skins: usize,
}

impl Importer<'_> {
    /// The mesh, with notes about what was dropped or ignored.
    pub(super) fn finish(self) -> Mesh {
        let Importer {
            mesh,
            report,
            strip_joints,
            ignored_targets,
            ignored_skins,
            source,
            ..
        } = self;
        if strip_joints > 0 {
            report.notes.push(format!(
                "{}: {strip_joints} degenerate triangles joining strips or fans dropped",
                source.name
            ));
        }
        if report.skipped_primitives > 0 {
            report.notes.push(format!(
                "{}: {} POINTS or LINES primitives skipped",
                source.name, report.skipped_primitives
            ));
        }
        if ignored_targets > 0 {
            report.notes.push(format!(
                "{}: morph targets of {ignored_targets} primitives ignored (base shape imported)",
                source.name
            ));
        }
        if ignored_skins > 0 {
            report.notes.push(format!(
                "{}: skins of {ignored_skins} nodes ignored (bind pose imported)",
                source.name
            ));
        }
        mesh
    }
}

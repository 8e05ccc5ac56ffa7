//! The module graph of each crate: which file takes which items from which other file, read
//! from the sources (`use` declarations and paths in code, followed through re-exports to the
//! file that defines the item). `cargo xtask graph` prints it; the limits check fails on a
//! circle of files, or on a circle between the sub-modules of any module (an upward import:
//! a module that takes from one that takes from it, though no single file closes the loop).
//! Items under `#[cfg(test)]` and `#[test]` are not part of the graph.

pub mod lex;
pub mod parse;
pub mod report;
mod scc;

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fs;
use std::path::{Path, PathBuf};

use parse::{parse, FileModel, FnSpan};

/// One file of a crate: its path (relative to the workspace), module path and contents.
pub struct FileNode {
    pub path: PathBuf,
    pub module: Vec<String>,
    pub model: FileModel,
}

/// An edge: file `from` takes `names` from file `to`.
pub type Edges = BTreeMap<(usize, usize), BTreeSet<String>>;

/// One crate (a library, a binary or an example), its files reached from its root through
/// `mod` declarations, and the edges between them.
pub struct CrateGraph {
    pub name: String,
    pub files: Vec<FileNode>,
    /// Module path -> (file, scope inside the file).
    modules: HashMap<Vec<String>, (usize, Vec<String>)>,
    pub edges: Edges,
}

impl CrateGraph {
    /// The crate whose root file is `root` (relative to `workspace`).
    pub fn load(workspace: &Path, name: &str, root: &Path) -> Result<Self, String> {
        let mut g = CrateGraph {
            name: name.to_string(),
            files: Vec::new(),
            modules: HashMap::new(),
            edges: Edges::new(),
        };
        g.add_file(workspace, root.to_path_buf(), Vec::new(), true)?;
        g.link();
        Ok(g)
    }

    fn add_file(
        &mut self,
        workspace: &Path,
        path: PathBuf,
        module: Vec<String>,
        owns_dir: bool,
    ) -> Result<(), String> {
        let text = fs::read_to_string(workspace.join(&path))
            .map_err(|e| format!("{}: {e}", path.display()))?;
        let model = parse(&text);
        let index = self.files.len();
        self.modules.insert(module.clone(), (index, Vec::new()));
        let dir = match (owns_dir, path.parent(), path.file_stem()) {
            (true, Some(parent), _) => parent.to_path_buf(),
            (false, Some(parent), Some(stem)) => parent.join(stem),
            _ => PathBuf::new(),
        };
        let declared = model.modules.clone();
        self.files.push(FileNode {
            path,
            module: module.clone(),
            model,
        });
        for (scope, name, inline) in declared {
            let mut child = module.clone();
            child.extend(scope.iter().cloned());
            child.push(name.clone());
            if inline {
                let mut inner = scope.clone();
                inner.push(name);
                self.modules.insert(child, (index, inner));
                continue;
            }
            let base = scope.iter().fold(dir.clone(), |d, s| d.join(s));
            let flat = base.join(format!("{name}.rs"));
            let nested = base.join(&name).join("mod.rs");
            if workspace.join(&flat).is_file() {
                self.add_file(workspace, flat, child, false)?;
            } else if workspace.join(&nested).is_file() {
                self.add_file(workspace, nested, child, true)?;
            }
        }
        Ok(())
    }

    /// Resolves every path each file names to the file that defines it.
    fn link(&mut self) {
        let mut edges = Edges::new();
        for (from, f) in self.files.iter().enumerate() {
            for r in &f.model.refs {
                let mut module = f.module.clone();
                module.extend(r.scope.iter().cloned());
                if let Some((to, name)) = self.resolve(&module, &r.segments, 0) {
                    if to != from {
                        edges.entry((from, to)).or_default().insert(name);
                    }
                }
            }
        }
        self.edges = edges;
    }

    /// The file defining what `segments` names from `module`, and the item's name.
    fn resolve(
        &self,
        module: &[String],
        segments: &[String],
        depth: u32,
    ) -> Option<(usize, String)> {
        if depth > 24 {
            return None;
        }
        let mut m = module.to_vec();
        for (k, seg) in segments.iter().enumerate() {
            match seg.as_str() {
                "crate" if k == 0 => m.clear(),
                "super" => {
                    m.pop();
                }
                "self" => {}
                _ => {
                    let mut child = m.clone();
                    child.push(seg.clone());
                    if self.modules.contains_key(&child) {
                        // A path that ends at a module names no item: a field or a local
                        // of the same name, or a module used through a longer path.
                        if k + 1 == segments.len() {
                            return None;
                        }
                        m = child;
                        continue;
                    }
                    return self.resolve_name(&m, seg, &segments[k + 1..], depth);
                }
            }
        }
        None
    }

    /// `name` (followed by `rest`) looked up among the items of `module`.
    fn resolve_name(
        &self,
        module: &[String],
        name: &str,
        rest: &[String],
        depth: u32,
    ) -> Option<(usize, String)> {
        let (file, scope) = self.modules.get(module)?;
        let model = &self.files[*file].model;
        if model.defs.iter().any(|(s, n)| s == scope && n == name) {
            return Some((*file, name.to_string()));
        }
        let in_scope = model.uses.iter().filter(|u| &u.scope == scope);
        for u in in_scope.clone().filter(|u| !u.glob && u.name == name) {
            let mut path = u.path.clone();
            path.extend(rest.iter().cloned());
            if let Some(found) = self.resolve(module, &path, depth + 1) {
                return Some(found);
            }
        }
        for u in in_scope.filter(|u| u.glob) {
            let mut path = u.path.clone();
            path.push(name.to_string());
            path.extend(rest.iter().cloned());
            if let Some(found) = self.resolve(module, &path, depth + 1) {
                return Some(found);
            }
        }
        None
    }

    /// The file's path as the reports print it.
    pub fn file_name(&self, i: usize) -> String {
        self.files[i].path.display().to_string()
    }

    /// Circles of files: every strongly connected set of two files or more.
    pub fn file_circles(&self) -> Vec<Vec<usize>> {
        let adjacency = self.adjacency(Some);
        scc::circles(self.files.len(), &adjacency)
    }

    /// Circles between the parts of each module: its own file and each child module's
    /// subtree, as (module, parts of the circle by name, the edges between them).
    pub fn module_circles(&self) -> Vec<(Vec<String>, Vec<String>)> {
        let mut parents: BTreeSet<Vec<String>> = BTreeSet::new();
        for f in &self.files {
            for k in 0..f.module.len() {
                parents.insert(f.module[..k].to_vec());
            }
        }
        let mut out = Vec::new();
        for parent in parents {
            let part_of = |file: usize| -> Option<String> {
                let m = &self.files[file].module;
                if !m.starts_with(&parent) {
                    return None;
                }
                Some(
                    m.get(parent.len())
                        .cloned()
                        .unwrap_or_else(|| "(self)".into()),
                )
            };
            let mut names: Vec<String> = (0..self.files.len()).filter_map(part_of).collect();
            names.sort();
            names.dedup();
            let index: HashMap<&String, usize> =
                names.iter().enumerate().map(|(i, n)| (n, i)).collect();
            let mut adjacency = vec![BTreeSet::new(); names.len()];
            for &(a, b) in self.edges.keys() {
                if let (Some(pa), Some(pb)) = (part_of(a), part_of(b)) {
                    if pa != pb {
                        adjacency[index[&pa]].insert(index[&pb]);
                    }
                }
            }
            for circle in scc::circles(names.len(), &adjacency) {
                out.push((
                    parent.clone(),
                    circle.iter().map(|&i| names[i].clone()).collect(),
                ));
            }
        }
        out
    }

    fn adjacency(&self, map: impl Fn(usize) -> Option<usize>) -> Vec<BTreeSet<usize>> {
        let mut adjacency = vec![BTreeSet::new(); self.files.len()];
        for &(a, b) in self.edges.keys() {
            if let (Some(a), Some(b)) = (map(a), map(b)) {
                adjacency[a].insert(b);
            }
        }
        adjacency
    }

    /// The edges among `files`, one line each: `a -> b: names`.
    pub fn describe_edges(&self, files: &[usize]) -> Vec<String> {
        self.edges
            .iter()
            .filter(|((a, b), _)| files.contains(a) && files.contains(b))
            .map(|((a, b), names)| {
                let names: Vec<&str> = names.iter().map(String::as_str).collect();
                format!(
                    "{} -> {}: {}",
                    self.file_name(*a),
                    self.file_name(*b),
                    names.join(", ")
                )
            })
            .collect()
    }

    /// The edges from the files of `module`'s part `from` to those of its part `to`.
    pub fn describe_part_edges(&self, module: &[String], from: &str, to: &str) -> Vec<String> {
        let in_part = |file: usize, part: &str| {
            let m = &self.files[file].module;
            m.starts_with(module) && m.get(module.len()).map_or(part == "(self)", |p| p == part)
        };
        self.edges
            .iter()
            .filter(|((a, b), _)| in_part(*a, from) && in_part(*b, to))
            .map(|((a, b), names)| {
                let names: Vec<&str> = names.iter().map(String::as_str).collect();
                format!(
                    "{} -> {}: {}",
                    self.file_name(*a),
                    self.file_name(*b),
                    names.join(", ")
                )
            })
            .collect()
    }

    /// Every function's span, with its file.
    pub fn functions(&self) -> impl Iterator<Item = (&FileNode, &FnSpan)> {
        self.files
            .iter()
            .flat_map(|f| f.model.fns.iter().map(move |s| (f, s)))
    }
}

/// Every crate of the workspace whose sources are checked: each member's library and
/// binary, its examples and its benchmarks.
pub fn workspace_crates(workspace: &Path) -> Result<Vec<CrateGraph>, String> {
    let mut crates = Vec::new();
    for member in members(workspace)? {
        let dir = Path::new(&member);
        let mut roots: Vec<(String, PathBuf)> = Vec::new();
        for root in ["src/lib.rs", "src/main.rs"] {
            if workspace.join(dir).join(root).is_file() {
                roots.push((format!("{member} ({root})"), dir.join(root)));
            }
        }
        for kind in ["examples", "benches"] {
            let Ok(entries) = fs::read_dir(workspace.join(dir).join(kind)) else {
                continue;
            };
            let mut found: Vec<PathBuf> = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter_map(|p| {
                    if p.join("main.rs").is_file() {
                        Some(p.join("main.rs"))
                    } else {
                        p.extension().is_some_and(|x| x == "rs").then_some(p)
                    }
                })
                .collect();
            found.sort();
            for p in found {
                let rel = p.strip_prefix(workspace).unwrap_or(&p).to_path_buf();
                roots.push((rel.display().to_string(), rel));
            }
        }
        for (name, root) in roots {
            crates.push(CrateGraph::load(workspace, &name, &root)?);
        }
    }
    Ok(crates)
}

/// The workspace's members, as listed in its `Cargo.toml`.
pub fn members(workspace: &Path) -> Result<Vec<String>, String> {
    let manifest =
        fs::read_to_string(workspace.join("Cargo.toml")).map_err(|e| format!("Cargo.toml: {e}"))?;
    let line = manifest
        .lines()
        .find(|l| l.trim_start().starts_with("members"))
        .ok_or("Cargo.toml: no `members` line")?;
    Ok(line
        .split('"')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect())
}

/// The graph's problems: file circles and circles between a module's parts, one entry each.
pub fn problems(g: &CrateGraph) -> Vec<String> {
    let mut out = Vec::new();
    for circle in g.file_circles() {
        let names: Vec<String> = circle.iter().map(|&f| g.file_name(f)).collect();
        let mut text = format!("{}: circle of files: {}", g.name, names.join(", "));
        for e in g.describe_edges(&circle) {
            text.push_str(&format!("\n    {e}"));
        }
        out.push(text);
    }
    for (module, parts) in g.module_circles() {
        let module_name = if module.is_empty() {
            "the crate root".to_string()
        } else {
            module.join("::")
        };
        let mut text = format!(
            "{}: circle between the parts of {module_name}: {}",
            g.name,
            parts.join(", ")
        );
        for a in &parts {
            for b in &parts {
                for e in g.describe_part_edges(&module, a, b) {
                    text.push_str(&format!("\n    {e}"));
                }
            }
        }
        out.push(text);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, files: &[(&str, &str)]) {
        for (path, text) in files {
            let p = dir.join(path);
            fs::create_dir_all(p.parent().unwrap()).unwrap();
            fs::write(p, text).unwrap();
        }
    }

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("xtask-graph-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        dir
    }

    #[test]
    fn a_circle_through_a_re_export_is_found() {
        let dir = scratch("circle");
        write(
            &dir,
            &[
                ("src/lib.rs", "mod a;\nmod b;\npub use a::A;\n"),
                ("src/a.rs", "use crate::b::B;\npub struct A(B);\n"),
                (
                    "src/b.rs",
                    "pub struct B;\nfn f() -> crate::A { todo!() }\n",
                ),
            ],
        );
        let g = CrateGraph::load(&dir, "t", Path::new("src/lib.rs")).unwrap();
        let p = problems(&g);
        assert_eq!(p.len(), 2, "{p:?}");
        assert!(p[0].contains("src/b.rs -> src/a.rs: A"), "{p:?}");
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn an_upward_import_between_modules_is_found_and_layers_pass() {
        let dir = scratch("upward");
        write(
            &dir,
            &[
                ("src/lib.rs", "mod low;\nmod high;\n"),
                ("src/low/mod.rs", "mod x;\nmod y;\n"),
                ("src/low/x.rs", "pub fn x() {}\n"),
                (
                    "src/low/y.rs",
                    "pub fn y() { super::x::x(); crate::high::h(); }\n",
                ),
                ("src/high.rs", "use crate::low::x::x;\npub fn h() { x() }\n"),
            ],
        );
        let g = CrateGraph::load(&dir, "t", Path::new("src/lib.rs")).unwrap();
        let p = problems(&g);
        assert_eq!(p.len(), 1, "{p:?}");
        assert!(p[0].contains("parts of the crate root: high, low"), "{p:?}");
        fs::write(dir.join("src/low/y.rs"), "pub fn y() { super::x::x(); }\n").unwrap();
        let g = CrateGraph::load(&dir, "t", Path::new("src/lib.rs")).unwrap();
        assert!(problems(&g).is_empty());
        let _ = fs::remove_dir_all(&dir);
    }
}

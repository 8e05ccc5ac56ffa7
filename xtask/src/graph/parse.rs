//! What one Rust file says about modules: the modules it declares, the items it defines, the
//! names its `use` declarations bind, the paths its code names, and its functions' spans.
//! Items under `#[cfg(test)]` or `#[test]` are left out: tests are not part of the graph.

use super::lex::{lex, Token};

/// A `use` binding: `name` stands for `path` in `scope` (or, for a glob, every public name
/// of `path`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UseBinding {
    pub scope: Vec<String>,
    pub name: String,
    pub path: Vec<String>,
    pub glob: bool,
}

/// A path named by the code (outside `use` declarations) in `scope` on `line`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PathRef {
    pub scope: Vec<String>,
    pub segments: Vec<String>,
    pub line: usize,
}

/// A function's name and the lines of its first and last tokens.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FnSpan {
    pub name: String,
    pub first: usize,
    pub last: usize,
}

/// What a file holds, by scope (the inline module path inside the file; empty at its top).
#[derive(Clone, Debug, Default)]
pub struct FileModel {
    /// Modules declared `mod name;` (in files) and `mod name { .. }` (inline), by scope.
    pub modules: Vec<(Vec<String>, String, bool)>,
    /// Items defined, by scope.
    pub defs: Vec<(Vec<String>, String)>,
    pub uses: Vec<UseBinding>,
    pub refs: Vec<PathRef>,
    pub fns: Vec<FnSpan>,
}

const ITEM_KEYWORDS: &[&str] = &[
    "fn", "struct", "enum", "trait", "type", "const", "static", "union",
];

/// Words that start a path but are never an item's name.
const NOT_NAMES: &[&str] = &[
    "as", "break", "continue", "else", "enum", "false", "fn", "for", "if", "impl", "in", "let",
    "loop", "match", "move", "mut", "pub", "ref", "return", "static", "struct", "trait", "true",
    "type", "unsafe", "use", "where", "while", "dyn", "const", "async", "await", "mod", "extern",
    "union",
];

struct Parser {
    toks: Vec<Token>,
    i: usize,
    out: FileModel,
    /// Open inline modules: (brace depth inside the module, name).
    scopes: Vec<(usize, String)>,
    depth: usize,
    /// Functions whose body is open: (name, first line, brace depth inside the body).
    open_fns: Vec<(String, usize, usize)>,
    /// A function named, its body not yet open.
    pending_fn: Option<(String, usize)>,
}

/// The model of the Rust source `src`.
pub fn parse(src: &str) -> FileModel {
    let mut p = Parser {
        toks: lex(src),
        i: 0,
        out: FileModel::default(),
        scopes: Vec::new(),
        depth: 0,
        open_fns: Vec::new(),
        pending_fn: None,
    };
    p.run();
    p.out
}

impl Parser {
    fn scope(&self) -> Vec<String> {
        self.scopes.iter().map(|(_, n)| n.clone()).collect()
    }

    /// The brace depth at which items of the current scope stand.
    fn item_depth(&self) -> usize {
        self.scopes.last().map_or(0, |(d, _)| *d)
    }

    fn at(&self, k: usize) -> Option<&Token> {
        self.toks.get(self.i + k)
    }

    fn run(&mut self) {
        while self.i < self.toks.len() {
            self.step();
        }
    }

    fn step(&mut self) {
        let t = self.toks[self.i].clone();
        if t.is("#") {
            self.attribute();
        } else if t.is("{") {
            self.open_brace(t.line);
        } else if t.is("}") {
            self.close_brace(t.line);
        } else if t.is(";") {
            self.pending_fn = None;
            self.i += 1;
        } else if t.is_ident("use") && self.depth == self.item_depth() {
            self.use_declaration();
        } else if t.is_ident("mod") && self.depth == self.item_depth() {
            self.module();
        } else if t.is_ident("macro_rules") && self.at(1).is_some_and(|n| n.is("!")) {
            if let Some(name) = self.at(2).and_then(Token::ident).map(str::to_string) {
                if self.depth == self.item_depth() {
                    self.out.defs.push((self.scope(), name));
                }
            }
            self.i += 3;
        } else if let Some(word) = t.ident().filter(|w| ITEM_KEYWORDS.contains(w)) {
            let word = word.to_string();
            self.item_keyword(&word, t.line);
        } else if t.ident().is_some() || t.is("::") {
            self.path();
        } else {
            self.i += 1;
        }
    }

    /// `#[..]` or `#![..]`; an outer `cfg(test)` or `test` attribute drops the next item.
    fn attribute(&mut self) {
        let inner = self.at(1).is_some_and(|t| t.is("!"));
        let open = self.i + if inner { 2 } else { 1 };
        if !self.toks.get(open).is_some_and(|t| t.is("[")) {
            self.i += 1;
            return;
        }
        let close = self.matching(open, "[", "]");
        let body: Vec<&str> = self.toks[open + 1..close]
            .iter()
            .map(|t| t.ident().unwrap_or(""))
            .collect();
        let test_only = matches!(body.as_slice(), ["test"] | ["cfg", "", "test", ""]);
        self.i = close + 1;
        if test_only && !inner {
            self.skip_item();
        }
    }

    /// The index of the token closing the bracket opened at `open`.
    fn matching(&self, open: usize, o: &str, c: &str) -> usize {
        let mut depth = 0;
        for k in open..self.toks.len() {
            if self.toks[k].is(o) {
                depth += 1;
            } else if self.toks[k].is(c) {
                depth -= 1;
                if depth == 0 {
                    return k;
                }
            }
        }
        self.toks.len().saturating_sub(1)
    }

    /// Skips the item starting here (its further attributes included): up to a `;` outside
    /// brackets, or the end of its first braced block.
    fn skip_item(&mut self) {
        let mut k = self.i;
        while k < self.toks.len() {
            let t = &self.toks[k];
            if t.is("#") {
                let open = if self.toks.get(k + 1).is_some_and(|t| t.is("[")) {
                    k + 1
                } else {
                    k + 2
                };
                k = self.matching(open, "[", "]") + 1;
            } else if t.is("(") {
                k = self.matching(k, "(", ")") + 1;
            } else if t.is("[") {
                k = self.matching(k, "[", "]") + 1;
            } else if t.is("{") {
                k = self.matching(k, "{", "}") + 1;
                break;
            } else if t.is(";") {
                k += 1;
                break;
            } else {
                k += 1;
            }
        }
        self.i = k;
    }

    fn open_brace(&mut self, _line: usize) {
        self.depth += 1;
        if let Some((name, first)) = self.pending_fn.take() {
            self.open_fns.push((name, first, self.depth));
        }
        self.i += 1;
    }

    fn close_brace(&mut self, line: usize) {
        if self.open_fns.last().is_some_and(|f| f.2 == self.depth) {
            if let Some((name, first, _)) = self.open_fns.pop() {
                self.out.fns.push(FnSpan {
                    name,
                    first,
                    last: line,
                });
            }
        }
        if self.scopes.last().is_some_and(|s| s.0 == self.depth) {
            self.scopes.pop();
        }
        self.depth = self.depth.saturating_sub(1);
        self.i += 1;
    }

    fn module(&mut self) {
        let Some(name) = self.at(1).and_then(Token::ident).map(str::to_string) else {
            self.i += 1;
            return;
        };
        let inline = self.at(2).is_some_and(|t| t.is("{"));
        self.out.modules.push((self.scope(), name.clone(), inline));
        if inline {
            self.depth += 1;
            self.scopes.push((self.depth, name));
            self.i += 3;
        } else {
            self.i += 2;
        }
    }

    fn item_keyword(&mut self, word: &str, line: usize) {
        let name = self.at(1).and_then(Token::ident).map(str::to_string);
        let Some(name) = name else {
            self.i += 1;
            return;
        };
        if word == "fn" {
            self.pending_fn = Some((name.clone(), line));
        }
        if self.depth == self.item_depth() && name != "_" {
            self.out.defs.push((self.scope(), name));
        }
        self.i += 2;
    }

    /// A path in code: `a::b::c`, `crate::x`, `::std::y`; a name after `.` is a field or a
    /// method, not a path.
    fn path(&mut self) {
        let after_dot = self.i > 0 && self.toks[self.i - 1].is(".");
        let after_tick = self.i > 0 && self.toks[self.i - 1].is("'");
        let line = self.toks[self.i].line;
        let mut segments = Vec::new();
        if self.toks[self.i].is("::") {
            segments.push(String::new());
            self.i += 1;
        }
        while let Some(word) = self.at(0).and_then(Token::ident) {
            segments.push(word.to_string());
            self.i += 1;
            let more = self.at(0).is_some_and(|t| t.is("::"))
                && self.at(1).and_then(Token::ident).is_some();
            if !more {
                break;
            }
            self.i += 1;
        }
        if segments.is_empty() {
            self.i += 1;
            return;
        }
        let first = segments[0].as_str();
        let bare_root = segments.len() == 1 && ["crate", "self", "super", "Self"].contains(&first);
        if after_dot || after_tick || first.is_empty() || bare_root || NOT_NAMES.contains(&first) {
            return;
        }
        self.out.refs.push(PathRef {
            scope: self.scope(),
            segments,
            line,
        });
    }

    /// `[pub[(..)]] use tree;`
    fn use_declaration(&mut self) {
        let end = (self.i..self.toks.len())
            .find(|&k| self.toks[k].is(";"))
            .unwrap_or(self.toks.len());
        let tree: Vec<Token> = self.toks[self.i + 1..end].to_vec();
        let scope = self.scope();
        let mut bindings = Vec::new();
        use_tree(&tree, &mut 0, Vec::new(), &mut bindings);
        for (name, path, glob) in bindings {
            self.out.uses.push(UseBinding {
                scope: scope.clone(),
                name,
                path,
                glob,
            });
        }
        self.i = end + 1;
    }
}

/// Expands a use tree from `toks[*k..]` under `prefix` into (name, path, glob) bindings.
fn use_tree(
    toks: &[Token],
    k: &mut usize,
    mut prefix: Vec<String>,
    out: &mut Vec<(String, Vec<String>, bool)>,
) {
    if toks.get(*k).is_some_and(|t| t.is("::")) {
        *k += 1;
    }
    while *k < toks.len() {
        let t = &toks[*k];
        if t.is("{") {
            *k += 1;
            loop {
                use_tree(toks, k, prefix.clone(), out);
                match toks.get(*k) {
                    Some(t) if t.is(",") => *k += 1,
                    Some(t) if t.is("}") => {
                        *k += 1;
                        return;
                    }
                    _ => return,
                }
                if toks.get(*k).is_some_and(|t| t.is("}")) {
                    *k += 1;
                    return;
                }
            }
        } else if t.is("*") {
            *k += 1;
            out.push((String::new(), prefix, true));
            return;
        } else if let Some(word) = t.ident() {
            *k += 1;
            if toks.get(*k).is_some_and(|t| t.is("::")) {
                prefix.push(word.to_string());
                *k += 1;
                continue;
            }
            let mut path = prefix.clone();
            let mut name = word.to_string();
            if word == "self" {
                name = prefix.last().cloned().unwrap_or_default();
            } else {
                path.push(word.to_string());
            }
            if toks.get(*k).is_some_and(|t| t.is_ident("as")) {
                name = toks
                    .get(*k + 1)
                    .and_then(Token::ident)
                    .unwrap_or("_")
                    .to_string();
                *k += 2;
            }
            if name != "_" {
                out.push((name, path, false));
            }
            return;
        } else {
            // `pub`, `(crate)` and the like before the tree.
            *k += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn use_trees_expand_to_bindings() {
        let m = parse("pub(crate) use crate::a::{b::{C, D as E}, self, f::*};\nuse super::G;");
        let names: Vec<(&str, String, bool)> = m
            .uses
            .iter()
            .map(|u| (u.name.as_str(), u.path.join("::"), u.glob))
            .collect();
        assert_eq!(
            names,
            vec![
                ("C", "crate::a::b::C".to_string(), false),
                ("E", "crate::a::b::D".to_string(), false),
                ("a", "crate::a".to_string(), false),
                ("", "crate::a::f".to_string(), true),
                ("G", "super::G".to_string(), false),
            ]
        );
    }

    #[test]
    fn test_items_are_left_out_and_spans_are_measured() {
        let src = "mod a;\n#[cfg(test)]\nmod tests {\n    use crate::x::Y;\n    fn t() {}\n}\n\
                   pub fn f() {\n    let v = crate::b::g();\n    v.h();\n}\nstruct S;\n";
        let m = parse(src);
        assert_eq!(m.modules, vec![(vec![], "a".to_string(), false)]);
        assert!(m.uses.is_empty());
        assert_eq!(
            m.fns,
            vec![FnSpan {
                name: "f".into(),
                first: 7,
                last: 10
            }]
        );
        let refs: Vec<String> = m.refs.iter().map(|r| r.segments.join("::")).collect();
        assert!(refs.contains(&"crate::b::g".to_string()));
        assert!(!refs.iter().any(|r| r == "h"));
        let defs: Vec<&str> = m.defs.iter().map(|d| d.1.as_str()).collect();
        assert_eq!(defs, vec!["f", "S"]);
    }
}

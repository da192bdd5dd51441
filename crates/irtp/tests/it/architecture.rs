//! The module layering inside the core crate, checked on the source text.
//!
//! Between crates Cargo enforces the direction (irtp-python → irtp-cli →
//! irtp-paper → irtp-app → irtp); inside the core the rules it cannot see
//! are checked here: {`search`, `mfpt`, `fp`, `sim`, `analytic`} → `model`
//! → `numerics`. A module may import from its own layer's allowed siblings
//! ([`SIBLINGS`]) and from any layer below it. `error`, `rng`, `parallel`,
//! `stats`, `memo`, `stop` are utilities: importable from `model` and above, and
//! importing only each other; `numerics` may import only `error` and `stop`
//! (the stop request its long loops poll). In
//! particular `sim` (the samplers) never imports `mfpt` (first passage,
//! which uses the samplers), and `search` (first passage in position) may
//! import both, never the reverse.
//!
//! An import is any path in code (comments and literals stripped) that
//! starts with `crate::` or `$crate::` (also `use crate::{a, b::c}` groups),
//! or with `super::` chains that climb to the crate root (from a module root
//! such as `src/sim/mod.rs`; inline `mod x { .. }` blocks are tracked). Names
//! at the crate root that are not modules (re-exports in `src/lib.rs`,
//! `#[macro_export]` macros) count as the module that defines them.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Layers of the library's top-level modules, highest first.
const LAYERS: &[&[&str]] = &[
    &["search", "mfpt", "fp", "sim", "analytic"],
    &["model"],
    &["numerics"],
];

/// Utilities: importable from `model` and above (and from each other).
const UTILITIES: &[&str] = &["error", "rng", "parallel", "stats", "memo", "stop"];

/// The allowed imports within one layer, (from, to).
const SIBLINGS: &[(&str, &str)] = &[("mfpt", "sim"), ("search", "mfpt"), ("search", "sim")];

/// Utilities `numerics` may import.
const NUMERICS_UTILITIES: &[&str] = &["error", "stop"];

/// Layer index of a module (0 = highest), `None` for a utility.
fn layer(m: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&m))
}

/// Whether module `from` may import module `to`.
fn allowed(from: &str, to: &str) -> bool {
    if from == to {
        return true;
    }
    let (lf, lt) = (layer(from), layer(to));
    match (lf, lt) {
        (_, None) if UTILITIES.contains(&to) => match lf {
            None => UTILITIES.contains(&from),
            Some(_) if from == "numerics" => NUMERICS_UTILITIES.contains(&to),
            Some(l) => l <= layer("model").expect("model has a layer"),
        },
        (Some(a), Some(b)) => b > a || (a == b && SIBLINGS.contains(&(from, to))),
        _ => false,
    }
}

/// Source text with comments, string and character literals blanked out
/// (lifetimes kept), so only code remains.
fn strip(src: &str) -> String {
    let c: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    while i < c.len() {
        let next = c.get(i + 1).copied();
        if c[i] == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if c[i] == '/' && next == Some('*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            out.push(' ');
        } else if c[i] == 'r' && (next == Some('"') || next == Some('#')) && raw_start(&c, i) {
            i = skip_raw_string(&c, i);
            out.push_str("\"\"");
        } else if c[i] == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if c[i] == '\'' && is_char_literal(&c, i) {
            i += 1;
            while i < c.len() && c[i] != '\'' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("' '");
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// `r"`, `r#"`, ... at `i`, not inside an identifier.
fn raw_start(c: &[char], i: usize) -> bool {
    if i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_') {
        return false;
    }
    let mut j = i + 1;
    while j < c.len() && c[j] == '#' {
        j += 1;
    }
    c.get(j) == Some(&'"')
}

/// Index just past the raw string starting at `i`.
fn skip_raw_string(c: &[char], i: usize) -> usize {
    let mut j = i + 1;
    let mut hashes = 0;
    while c[j] == '#' {
        hashes += 1;
        j += 1;
    }
    j += 1;
    while j < c.len() {
        if c[j] == '"' && (0..hashes).all(|k| c.get(j + 1 + k) == Some(&'#')) {
            return j + 1 + hashes;
        }
        j += 1;
    }
    j
}

/// A character literal (`'a'`, `'\n'`) rather than a lifetime (`'a`).
fn is_char_literal(c: &[char], i: usize) -> bool {
    match c.get(i + 1) {
        Some('\\') => true,
        Some(_) => c.get(i + 2) == Some(&'\''),
        None => false,
    }
}

/// Tokens: identifiers (with a leading `$` for macro variables), `::` and
/// single punctuation characters.
fn tokens(code: &str) -> Vec<String> {
    let c: Vec<char> = code.chars().collect();
    let mut t = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch.is_whitespace() {
            i += 1;
        } else if ch.is_alphanumeric() || ch == '_' || ch == '$' {
            let s = i;
            i += 1;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            t.push(c[s..i].iter().collect());
        } else if ch == ':' && c.get(i + 1) == Some(&':') {
            t.push("::".into());
            i += 2;
        } else {
            t.push(ch.to_string());
            i += 1;
        }
    }
    t
}

fn is_ident(t: &str) -> bool {
    t.chars()
        .next()
        .is_some_and(|c| c.is_alphabetic() || c == '_')
}

/// The first identifier of every entry of the `{ .. }` group opening at
/// `t[i]`, and the index just past the group.
fn group_heads(t: &[String], i: usize) -> (Vec<String>, usize) {
    let (mut heads, mut depth, mut j, mut expect) = (Vec::new(), 0, i, true);
    while j < t.len() {
        match t[j].as_str() {
            "{" => {
                depth += 1;
                expect = depth == 1;
            }
            "}" => {
                depth -= 1;
                if depth == 0 {
                    return (heads, j + 1);
                }
            }
            "," if depth == 1 => expect = true,
            s if expect && depth == 1 && is_ident(s) => {
                heads.push(s.to_string());
                expect = false;
            }
            _ => {}
        }
        j += 1;
    }
    (heads, j)
}

/// The crate-root names (first path segments) that the code of a module
/// at path `module` refers to, with `crate::`, `$crate::` or `super::`.
fn root_names(code: &str, module: &[String]) -> BTreeSet<String> {
    let t = tokens(code);
    let mut names = BTreeSet::new();
    // Inline modules: (name, brace depth at which their block closes).
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut depth = 0usize;
    let mut i = 0;
    while i < t.len() {
        match t[i].as_str() {
            "{" => {
                depth += 1;
                if i >= 2 && t[i - 2] == "mod" && is_ident(&t[i - 1]) {
                    inline.push((t[i - 1].clone(), depth));
                }
            }
            "}" => {
                if inline.last().is_some_and(|m| m.1 == depth) {
                    inline.pop();
                }
                depth = depth.saturating_sub(1);
            }
            "crate" | "$crate" | "super" if t.get(i + 1).map(String::as_str) == Some("::") => {
                let prev = i.checked_sub(1).map(|p| t[p].as_str());
                if prev != Some("::") {
                    let mut path: Vec<String> = module.to_vec();
                    path.extend(inline.iter().map(|m| m.0.clone()));
                    i = resolve(&t, i, path, &mut names);
                    continue;
                }
            }
            _ => {}
        }
        i += 1;
    }
    names
}

/// Resolve the path starting at `t[i]` (`crate`, `$crate` or `super`)
/// from module `path`; record its crate-root name(s) if it reaches the
/// root. Returns the index after the consumed prefix.
fn resolve(
    t: &[String],
    mut i: usize,
    mut path: Vec<String>,
    names: &mut BTreeSet<String>,
) -> usize {
    if t[i] == "crate" || t[i] == "$crate" {
        path.clear();
        i += 2;
    } else {
        while t.get(i).map(String::as_str) == Some("super")
            && t.get(i + 1).map(String::as_str) == Some("::")
        {
            path.pop();
            i += 2;
        }
    }
    if !path.is_empty() {
        return i;
    }
    match t.get(i).map(String::as_str) {
        Some("{") => {
            let (heads, j) = group_heads(t, i);
            names.extend(heads.into_iter().filter(|h| h != "self"));
            j
        }
        Some(s) if is_ident(s) => {
            names.insert(s.to_string());
            i + 1
        }
        _ => i,
    }
}

/// Every `.rs` file under `dir`.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).expect("read src") {
        let p = e.expect("dir entry").path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The module path of a library file relative to `src/` (`sim/mod.rs` →
/// [sim], `model/drag/tan.rs` → [model, drag, tan]).
fn module_path(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().expect("file name");
    let stem = last.trim_end_matches(".rs");
    if stem != "mod" && stem != "lib" {
        parts.push(stem.to_string());
    }
    parts
}

/// Library sources: (path relative to src/, module path, code).
fn library() -> Vec<(PathBuf, Vec<String>, String)> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    files
        .into_iter()
        .map(|p| p.strip_prefix(&src).expect("under src").to_path_buf())
        .map(|rel| {
            let code = strip(&std::fs::read_to_string(src.join(&rel)).expect("read"));
            (rel.clone(), module_path(&rel), code)
        })
        .collect()
}

/// Crate-root names that are not modules, mapped to their home module:
/// `pub use` re-exports in lib.rs and `#[macro_export]` macros.
fn root_items(lib: &[(PathBuf, Vec<String>, String)]) -> BTreeMap<String, String> {
    let mut items = BTreeMap::new();
    for (rel, module, code) in lib {
        let t = tokens(code);
        for w in t.windows(4) {
            if w[0] == "macro_rules" && w[1] == "!" && !module.is_empty() {
                items.insert(w[2].clone(), module[0].clone());
            }
        }
        if rel != Path::new("lib.rs") {
            continue;
        }
        let mut i = 0;
        while i + 1 < t.len() {
            if t[i] == "use" && is_ident(&t[i + 1]) {
                let home = t[i + 1].clone();
                let mut j = i + 1;
                while j < t.len() && t[j] != ";" {
                    let leaf = matches!(t.get(j + 1).map(String::as_str), Some("," | "}" | ";"));
                    if is_ident(&t[j]) && leaf && j > i + 1 {
                        items.insert(t[j].clone(), home.clone());
                    }
                    j += 1;
                }
                i = j;
            }
            i += 1;
        }
    }
    items
}

/// Every import of the library as (file, from module, to module).
fn imports() -> Vec<(PathBuf, String, String)> {
    let lib = library();
    let items = root_items(&lib);
    let modules: BTreeSet<String> = lib
        .iter()
        .filter_map(|(_, m, _)| m.first().cloned())
        .collect();
    let mut out = Vec::new();
    for (rel, module, code) in &lib {
        let Some(from) = module.first() else {
            continue; // lib.rs assembles the crate
        };
        for name in root_names(code, module) {
            if name.starts_with('$') {
                continue; // a macro variable, e.g. `$crate::$callback!`
            }
            let to = if modules.contains(&name) {
                name.clone()
            } else {
                items.get(&name).cloned().unwrap_or_else(|| {
                    panic!(
                        "{}: crate-root item `{name}` of unknown home",
                        rel.display()
                    )
                })
            };
            out.push((rel.clone(), from.clone(), to));
        }
    }
    out
}

#[test]
fn every_module_has_a_layer() {
    for (rel, module, _) in library() {
        if let Some(m) = module.first() {
            assert!(
                layer(m).is_some() || UTILITIES.contains(&m.as_str()),
                "{}: module `{m}` is in no layer of tests/architecture.rs",
                rel.display()
            );
        }
    }
}

#[test]
fn sim_never_imports_mfpt() {
    let bad: Vec<String> = imports()
        .into_iter()
        .filter(|(_, from, to)| from == "sim" && to == "mfpt")
        .map(|(f, _, _)| f.display().to_string())
        .collect();
    assert!(bad.is_empty(), "sim imports mfpt in {bad:?}");
}

#[test]
fn imports_follow_the_layering() {
    let all = imports();
    assert!(all.len() > 100, "the scanner finds imports ({})", all.len());
    let bad: Vec<String> = all
        .into_iter()
        .filter(|(_, from, to)| !allowed(from, to))
        .map(|(f, from, to)| format!("{}: {from} imports {to}", f.display()))
        .collect();
    assert!(
        bad.is_empty(),
        "imports against the layering:\n{}",
        bad.join("\n")
    );
}

#[test]
fn layering_rules() {
    assert!(allowed("mfpt", "sim") && !allowed("sim", "mfpt"));
    assert!(!allowed("fp", "mfpt") && !allowed("analytic", "mfpt"));
    assert!(allowed("model", "numerics") && !allowed("model", "sim"));
    assert!(allowed("model", "rng") && allowed("sim", "stats"));
    assert!(allowed("numerics", "error") && !allowed("numerics", "rng"));
    assert!(!allowed("numerics", "model") && !allowed("rng", "model"));
    assert!(allowed("rng", "error") && !allowed("fp", "sim"));
}

#[test]
fn scanner_finds_every_form_of_import() {
    let m = |s: &[&str]| s.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    let names = |code: &str, module: &[String]| root_names(&strip(code), module);
    let set = |s: &[&str]| s.iter().map(|x| x.to_string()).collect::<BTreeSet<_>>();
    let code = r#"
        use crate::{mfpt::Problem, sim, self};
        use crate::model::{Drag, Params};
        // use crate::figures;
        /* crate::cli */ let s = "crate::fp::x"; let c = '"'; let l: &'a str;
        fn f() -> crate::rng::Rng { $crate::stats::x() }
        use super::io;
        mod tests { use super::*; use super::super::numerics; }
    "#;
    assert_eq!(
        names(code, &m(&["sim"])),
        set(&["mfpt", "sim", "model", "rng", "stats", "io", "numerics"])
    );
    // From a nested module, one `super` stays inside the top-level module.
    assert_eq!(names("use super::io;", &m(&["sim", "exact"])), set(&[]));
    assert_eq!(
        names("use super::super::mfpt;", &m(&["sim", "exact"])),
        set(&["mfpt"])
    );
    assert_eq!(module_path(Path::new("sim/mod.rs")), m(&["sim"]));
    assert_eq!(
        module_path(Path::new("model/drag/tan.rs")),
        m(&["model", "drag", "tan"])
    );
}

/// The core's normal dependencies (its `Cargo.toml`): none of the front
/// ends' crates (argument parsing, plotting, configuration files, JSON), so
/// `cargo tree -p irtp -e normal` shows none of them.
#[test]
fn the_core_depends_on_no_front_end_crate() {
    let manifest =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml"))
            .expect("read Cargo.toml");
    let mut section = String::new();
    let mut deps = Vec::new();
    for line in manifest.lines().map(str::trim) {
        if line.starts_with('[') {
            section = line.to_string();
        } else if section.ends_with("dependencies]") && !section.contains("dev-") {
            if let Some((name, _)) = line.split_once(['=', '.']) {
                deps.push(name.trim().to_string());
            }
        }
    }
    assert!(deps.contains(&"rand".to_string()), "parsed {deps:?}");
    for banned in [
        "clap",
        "plotters",
        "toml",
        "serde_json",
        "indicatif",
        "csv",
        "anyhow",
    ] {
        assert!(
            !deps.iter().any(|d| d == banned),
            "the core depends on {banned}: {deps:?}"
        );
    }
}

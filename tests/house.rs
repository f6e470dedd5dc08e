//! The layout of `src/`: no two files import each other, the scene loader (`scene/`) knows
//! no ECS (`ecs/`), the kernels know no scene format (`scene/format`), and no new circle between
//! folders appears.
//!
//! Imports are read from the source text: `use crate::…`, `use super::…`, `use self::…` (with
//! their `{…}` groups) and paths `crate::a::b`, `super::a`, `self::a` anywhere in code. A
//! path is resolved to the file of its longest module prefix, following the `mod x;`
//! declarations from `lib.rs` and `main.rs` (each its own crate) and the inline modules
//! (`mod tests { use super::*; }` is the file itself). Comments and string literals are
//! skipped. Relative paths through a child module (`use files::Report;` in a `mod.rs`) are not
//! counted: a parent naming its children is what `mod` declares anyway.

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

use common::temp_dir;

/// Folder circles that remain, each with why: the test fails when one of them goes (remove it
/// here) or another appears.
const KNOWN_FOLDER_CIRCLES: &[(&str, &str)] = &[];

/// A token of Rust source with comments and literals removed.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Token {
    Ident(String),
    /// `::`
    Path,
    Punct(char),
}

/// Splits source text into identifiers, `::` and single punctuation, dropping comments,
/// string, byte-string, raw-string and character literals (lifetimes are kept apart from
/// character literals).
fn tokens(text: &str) -> Vec<Token> {
    let c: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    let at = |i: usize, s: &str| {
        s.chars()
            .enumerate()
            .all(|(k, ch)| c.get(i + k) == Some(&ch))
    };
    while i < c.len() {
        let ch = c[i];
        if at(i, "//") {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if at(i, "/*") {
            let mut depth = 0;
            while i < c.len() {
                if at(i, "/*") {
                    depth += 1;
                    i += 2;
                } else if at(i, "*/") {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if ch == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
        } else if ch == '\'' {
            // A character literal ('a', '\n', '\u{1F600}') or a lifetime ('a).
            if c.get(i + 1) == Some(&'\\') {
                i += 3;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                i += 1;
            }
        } else if ch.is_alphabetic() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            let word: String = c[start..i].iter().collect();
            // Raw strings r"…", r#"…"#, br"…" and byte strings b"…".
            let hashes = c[i..].iter().take_while(|&&h| h == '#').count();
            if (word == "r" || word == "br") && c.get(i + hashes) == Some(&'"') {
                let close: String = std::iter::once('"')
                    .chain(std::iter::repeat_n('#', hashes))
                    .collect();
                i += hashes + 1;
                while i < c.len() && !at(i, &close) {
                    i += 1;
                }
                i += close.len();
            } else if word == "b" && c.get(i) == Some(&'"') {
                // The string itself is skipped by the next turn of the loop.
            } else {
                out.push(Token::Ident(word));
            }
        } else if at(i, "::") {
            out.push(Token::Path);
            i += 2;
        } else {
            if !ch.is_whitespace() {
                out.push(Token::Punct(ch));
            }
            i += 1;
        }
    }
    out
}

/// The paths a `use` tree names, each as its segments (`a::{b, c::d}` → `a::b`, `a::c::d`);
/// `*` and `as` names end a path.
fn use_paths(t: &[Token], prefix: &[String], out: &mut Vec<Vec<String>>) {
    let mut path = prefix.to_vec();
    let mut i = 0;
    while i < t.len() {
        match &t[i] {
            Token::Ident(w) if w == "as" => {
                i += 2;
                continue;
            }
            Token::Ident(w) => path.push(w.clone()),
            Token::Punct('{') => {
                // The group runs to its matching brace; its items are split at top-level commas.
                let mut depth = 0;
                let mut start = i + 1;
                let mut j = i;
                while j < t.len() {
                    match t[j] {
                        Token::Punct('{') => depth += 1,
                        Token::Punct('}') => {
                            depth -= 1;
                            if depth == 0 {
                                use_paths(&t[start..j], &path, out);
                                break;
                            }
                        }
                        Token::Punct(',') if depth == 1 => {
                            use_paths(&t[start..j], &path, out);
                            start = j + 1;
                        }
                        _ => {}
                    }
                    j += 1;
                }
                return;
            }
            Token::Punct(',') => {
                out.push(std::mem::replace(&mut path, prefix.to_vec()));
            }
            _ => {}
        }
        i += 1;
    }
    if path.len() > prefix.len() || !prefix.is_empty() {
        out.push(path);
    }
}

/// A source file of a crate.
struct File {
    path: PathBuf,
    /// Which crate root it hangs from (`lib.rs` or `main.rs`).
    krate: usize,
    /// Module path within its crate.
    module: Vec<String>,
    tokens: Vec<Token>,
}

/// The files of the crates under `src`, following `mod x;` declarations from each root.
fn files(src: &Path) -> Vec<File> {
    let mut out = Vec::new();
    for (krate, root) in ["lib.rs", "main.rs"].iter().enumerate() {
        let mut todo = vec![(src.join(root), Vec::<String>::new(), src.to_path_buf())];
        while let Some((path, module, dir)) = todo.pop() {
            let Ok(text) = fs::read_to_string(&path) else {
                continue;
            };
            let tokens = tokens(&text);
            let mut depth = 0;
            for (k, t) in tokens.iter().enumerate() {
                match t {
                    Token::Punct('{') => depth += 1,
                    Token::Punct('}') => depth -= 1,
                    Token::Ident(w) if w == "mod" && depth == 0 => {
                        if let (Some(Token::Ident(name)), Some(Token::Punct(';'))) =
                            (tokens.get(k + 1), tokens.get(k + 2))
                        {
                            let flat = dir.join(format!("{name}.rs"));
                            let (file, child_dir) = if flat.exists() {
                                (flat, dir.join(name))
                            } else {
                                (dir.join(name).join("mod.rs"), dir.join(name))
                            };
                            let mut m = module.clone();
                            m.push(name.clone());
                            todo.push((file, m, child_dir));
                        }
                    }
                    _ => {}
                }
            }
            out.push(File {
                path: path.strip_prefix(src).unwrap_or(&path).to_path_buf(),
                krate,
                module,
                tokens,
            });
        }
    }
    out
}

/// Every file's imports of other files of its crate.
fn imports(src: &Path) -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
    let files = files(src);
    let by_module: BTreeMap<(usize, &[String]), &Path> = files
        .iter()
        .map(|f| ((f.krate, f.module.as_slice()), f.path.as_path()))
        .collect();
    let mut graph = BTreeMap::new();
    for f in &files {
        let mut deps = BTreeSet::new();
        // Inline modules open at each brace depth: `mod tests {` makes `super` the file.
        let mut inline: Vec<(String, usize)> = Vec::new();
        let mut depth = 0;
        let t = &f.tokens;
        let mut i = 0;
        while i < t.len() {
            let mut paths = Vec::new();
            match &t[i] {
                Token::Punct('{') => depth += 1,
                Token::Punct('}') => {
                    if inline.last().is_some_and(|m| m.1 == depth) {
                        inline.pop();
                    }
                    depth -= 1;
                }
                Token::Ident(w) if w == "mod" => {
                    if let (Some(Token::Ident(name)), Some(Token::Punct('{'))) =
                        (t.get(i + 1), t.get(i + 2))
                    {
                        depth += 1;
                        inline.push((name.clone(), depth));
                        i += 3;
                        continue;
                    }
                }
                Token::Ident(w) if w == "use" => {
                    let end = t[i..]
                        .iter()
                        .position(|x| *x == Token::Punct(';'))
                        .map_or(t.len(), |p| i + p);
                    let tree: Vec<Token> = t[i + 1..end]
                        .iter()
                        .filter(|x| **x != Token::Path)
                        .cloned()
                        .collect();
                    use_paths(&tree, &[], &mut paths);
                    i = end;
                }
                Token::Ident(w)
                    if ["crate", "super", "self"].contains(&w.as_str())
                        && t.get(i + 1) == Some(&Token::Path)
                        && (i == 0 || t[i - 1] != Token::Path) =>
                {
                    let mut path = vec![w.clone()];
                    while let (Some(Token::Path), Some(Token::Ident(next))) =
                        (t.get(i + 1), t.get(i + 2))
                    {
                        path.push(next.clone());
                        i += 2;
                    }
                    paths.push(path);
                }
                _ => {}
            }
            for path in paths {
                let mut module: Vec<String> = f.module.clone();
                module.extend(inline.iter().map(|m| m.0.clone()));
                let rest = match path.first().map(String::as_str) {
                    Some("crate") => {
                        module.clear();
                        &path[1..]
                    }
                    Some("super" | "self") => {
                        let mut k = 0;
                        while let Some(s) = path.get(k).filter(|s| *s == "super" || *s == "self") {
                            if s == "super" {
                                module.pop();
                            }
                            k += 1;
                        }
                        &path[k..]
                    }
                    _ => continue,
                };
                module.extend(rest.iter().cloned());
                let target = (0..=module.len())
                    .rev()
                    .find_map(|n| by_module.get(&(f.krate, &module[..n])));
                if let Some(&target) = target.filter(|t| **t != f.path) {
                    deps.insert(target.to_path_buf());
                }
            }
            i += 1;
        }
        graph.insert(f.path.clone(), deps);
    }
    graph
}

/// Pairs of files that import each other.
fn file_circles(graph: &BTreeMap<PathBuf, BTreeSet<PathBuf>>) -> Vec<(PathBuf, PathBuf)> {
    let mut out = Vec::new();
    for (a, deps) in graph {
        for b in deps {
            if a < b && graph.get(b).is_some_and(|d| d.contains(a)) {
                out.push((a.clone(), b.clone()));
            }
        }
    }
    out
}

/// A file's folder under `src/` (`scene` for `scene/load/mod.rs`), or its stem at the top.
fn folder(path: &Path) -> String {
    let mut parts = path.components();
    let first = parts
        .next()
        .map(|c| c.as_os_str().to_string_lossy().into_owned());
    let first = first.unwrap_or_default();
    if parts.next().is_some() {
        first
    } else {
        first.trim_end_matches(".rs").to_string()
    }
}

/// Folders (`folder`) with an import into each other, as ordered pairs.
fn folder_imports(graph: &BTreeMap<PathBuf, BTreeSet<PathBuf>>) -> BTreeSet<(String, String)> {
    graph
        .iter()
        .flat_map(|(a, deps)| deps.iter().map(move |b| (folder(a), folder(b))))
        .filter(|(a, b)| a != b)
        .collect()
}

fn folder_circles(imports: &BTreeSet<(String, String)>) -> BTreeSet<(String, String)> {
    imports
        .iter()
        .filter(|(a, b)| a < b && imports.contains(&(b.clone(), a.clone())))
        .cloned()
        .collect()
}

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn show(pairs: &[(PathBuf, PathBuf)], arrow: &str) -> String {
    pairs
        .iter()
        .map(|(a, b)| format!("\n  {} {arrow} {}", a.display(), b.display()))
        .collect()
}

#[test]
fn no_two_files_import_each_other() {
    let graph = imports(&src());
    // The scan found the crates and their imports: a check that sees none passes anything.
    let count: usize = graph.values().map(BTreeSet::len).sum();
    assert!(
        graph.len() > 80 && count > 200,
        "{} files, {count} imports",
        graph.len()
    );
    let circles = file_circles(&graph);
    assert!(
        circles.is_empty(),
        "files that import each other:{}",
        show(&circles, "<->")
    );
}

#[test]
fn the_loader_knows_no_ecs() {
    let graph = imports(&src());
    let wrong: Vec<(PathBuf, PathBuf)> = graph
        .iter()
        .filter(|(a, _)| folder(a) == "scene")
        .flat_map(|(a, deps)| deps.iter().map(move |b| (a.clone(), b.clone())))
        .filter(|(_, b)| folder(b) == "ecs")
        .collect();
    assert!(
        wrong.is_empty(),
        "scene/ imports ecs/:{}",
        show(&wrong, "->")
    );
}

/// The kernels: code that runs per ray or per pixel and takes plain values, never the scene
/// file's descriptions (`scene/format`), which the ECS and the app convert at their boundary.
const KERNELS: &[&str] = &["render", "shading", "lights", "geometry", "sky"];

/// Imports of `scene/format` (the file, or a folder of that name) by the kernels.
fn kernel_imports_of_the_format(
    graph: &BTreeMap<PathBuf, BTreeSet<PathBuf>>,
) -> Vec<(PathBuf, PathBuf)> {
    graph
        .iter()
        .filter(|(a, _)| KERNELS.contains(&folder(a).as_str()))
        .flat_map(|(a, deps)| deps.iter().map(move |b| (a.clone(), b.clone())))
        .filter(|(_, b)| {
            let b = b.to_string_lossy().replace('\\', "/");
            b == "scene/format.rs" || b.starts_with("scene/format/")
        })
        .collect()
}

#[test]
fn kernels_import_no_scene_format() {
    let wrong = kernel_imports_of_the_format(&imports(&src()));
    assert!(
        wrong.is_empty(),
        "kernels import the scene format:{}",
        show(&wrong, "->")
    );
}

#[test]
fn a_kernel_importing_the_format_is_found() {
    let graph = graph_of(&[
        (
            "lib.rs",
            "mod render;
mod scene;
",
        ),
        (
            "render/mod.rs",
            "use crate::scene::format::Method;
",
        ),
        (
            "scene/mod.rs",
            "pub mod format;
",
        ),
        (
            "scene/format.rs",
            "pub enum Method {}
",
        ),
    ]);
    assert_eq!(
        kernel_imports_of_the_format(&graph),
        vec![(
            PathBuf::from("render/mod.rs"),
            PathBuf::from("scene/format.rs")
        )]
    );
}

#[test]
fn no_new_circle_between_folders() {
    let circles = folder_circles(&folder_imports(&imports(&src())));
    let known: BTreeSet<(String, String)> = KNOWN_FOLDER_CIRCLES
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    assert_eq!(circles, known, "folders that import each other");
}

/// Writes `files` (path, text) under a fresh `src/` and returns the import graph.
fn graph_of(files: &[(&str, &str)]) -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
    let dir = temp_dir("house");
    for (path, text) in files {
        let path = dir.join("src").join(path);
        fs::create_dir_all(path.parent().expect("parent")).expect("mkdir");
        fs::write(path, text).expect("write");
    }
    imports(&dir.join("src"))
}

fn edges(graph: &BTreeMap<PathBuf, BTreeSet<PathBuf>>) -> Vec<String> {
    graph
        .iter()
        .flat_map(|(a, d)| {
            d.iter()
                .map(move |b| format!("{} -> {}", a.display(), b.display()))
        })
        .collect()
}

#[test]
fn the_scan_finds_a_circle_through_use_groups_super_and_qualified_paths() {
    let graph = graph_of(&[
        ("lib.rs", "pub mod a;\npub mod b;\n"),
        ("a/mod.rs", "mod x;\nmod y;\n"),
        ("a/x.rs", "use super::{y::Y, *};\npub struct X;\n"),
        (
            "a/y.rs",
            "pub struct Y;\nfn f() { let _ = crate::a::x::X; }\n",
        ),
        ("b.rs", "pub use crate::{a::{self}, b as _};\n"),
    ]);
    assert_eq!(
        edges(&graph),
        [
            "a/x.rs -> a/mod.rs",
            "a/x.rs -> a/y.rs",
            "a/y.rs -> a/x.rs",
            "b.rs -> a/mod.rs"
        ]
    );
    assert_eq!(
        file_circles(&graph),
        [(PathBuf::from("a/x.rs"), PathBuf::from("a/y.rs"))]
    );
}

#[test]
fn the_scan_skips_comments_strings_and_the_files_own_test_module() {
    let graph = graph_of(&[
        ("lib.rs", "mod a;\nmod b;\n"),
        (
            "a.rs",
            "// use crate::b::B;\n/* crate::b::B /* nested */ crate::b::B */\n\
             const S: &str = \"crate::b::B\";\nconst R: &str = r#\"crate::b::B\"#;\n\
             const C: char = '{';\nconst Q: char = '\\'';\nfn f<'a>(x: &'a str) -> &'a str { x }\n\
             #[cfg(test)]\nmod tests {\n    use super::*;\n    mod deeper { use super::super::f; }\n}\n",
        ),
        ("b.rs", "use crate::a::f;\n"),
    ]);
    assert_eq!(edges(&graph), ["b.rs -> a.rs"]);
}

#[test]
fn folders_that_import_each_other_are_found() {
    let graph = graph_of(&[
        ("lib.rs", "mod scene;\nmod ecs;\n"),
        ("scene/mod.rs", "mod load;\n"),
        ("scene/load.rs", "use crate::ecs::components::Shape;\n"),
        (
            "ecs/mod.rs",
            "mod components;\nfn f(_: crate::scene::load::Loaded) {}\n",
        ),
        ("ecs/components.rs", "pub struct Shape;\n"),
    ]);
    assert!(file_circles(&graph).is_empty());
    assert_eq!(
        folder_circles(&folder_imports(&graph)),
        BTreeSet::from([("ecs".to_string(), "scene".to_string())])
    );
}

/// Every rendered image and layer is encoded by the output sink alone (`film/output.rs`): a
/// render's, each pass of a watch, a denoised image, the viewer's, a merge's. The other encoders
/// write other things: the partial format's exact sums, and `rondo diff`'s pictures.
#[test]
fn images_are_encoded_by_the_output_sink_alone() {
    const ENCODERS: [&str; 3] = ["film/output.rs", "farm/partial/write.rs", "metrics.rs"];
    let wrong: Vec<String> = files(&src())
        .iter()
        .filter(|f| {
            f.tokens
                .iter()
                .any(|t| matches!(t, Token::Ident(w) if w == "write_to" || w == "to_buffered"))
        })
        .map(|f| f.path.display().to_string())
        .filter(|p| !ENCODERS.contains(&p.as_str()))
        .collect();
    assert!(
        wrong.is_empty(),
        "images encoded outside the sink: {wrong:?}"
    );
}

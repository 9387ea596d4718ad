//! The layering of the source tree, checked without Vulkan: no module uses a module above it,
//! and no two files of one module import each other, directly or through a loop.
//!
//! The check reads `src/**/*.rs` (test code excluded: files named `*tests.rs` and items under
//! `#[cfg(test)]`), collects every `use` path and every `crate::…`, `super::…` and `self::…`
//! path in the code, and resolves each to a top-level module and, inside it, to a file (a
//! module's `mod.rs` is its assembly and takes no part in the file graph). It then fails on
//!
//! - an edge from a top-level module to one later in [`LAYERS`] (a lower layer using a
//!   higher one), naming the file and the path, and
//! - a cycle between the files of one module, naming every file on the loop.
//!
//! A new module must be placed in [`LAYERS`]; a module missing from it fails the check too.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The top-level modules in layers from the top down: a module may use the modules of the
/// layers after its own, never one of its own layer or of a layer before it.
const LAYERS: &[&[&str]] = &[
    &["cli"],
    &["app", "bench"],
    &["tune", "profile", "demo"],
    &["render"],
    &["gi"],
    &["voxel", "light", "post"],
    &["export", "eval", "graph", "panel_keys"],
    &["scene"],
    &["imaging", "vk"],
    &["stats", "limits", "assets"],
];

/// One source file: its module path (`["render", "gbuffer"]` for `src/render/gbuffer.rs`,
/// `["render"]` for `src/render/mod.rs`) and its code with comments, strings and test code
/// removed.
struct Source {
    rel: String,
    module: Vec<String>,
    code: String,
}

fn collect_sources(dir: &Path, root: &Path, out: &mut Vec<Source>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            collect_sources(&path, root, out);
            continue;
        }
        if path.extension().and_then(|e| e.to_str()) != Some("rs") {
            continue;
        }
        let rel = path.strip_prefix(root).expect("under src").to_path_buf();
        let stem = rel
            .file_stem()
            .and_then(|s| s.to_str())
            .expect("utf-8 name");
        if stem.ends_with("tests") {
            continue;
        }
        let mut module: Vec<String> = rel
            .parent()
            .into_iter()
            .flat_map(|p| p.components())
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        match stem {
            "lib" | "main" if module.is_empty() => continue,
            "mod" => {}
            _ => module.push(stem.to_string()),
        }
        let text = std::fs::read_to_string(&path).expect("readable source");
        out.push(Source {
            rel: format!("src/{}", rel.display()),
            module,
            code: strip_test_items(&strip_comments_and_strings(&text)),
        });
    }
}

/// The code with comments, string literals and character literals replaced by spaces, so that
/// a path in a doc comment or a message is not taken for a use. Line breaks stay, so a line of
/// the result is that line of the source.
fn strip_comments_and_strings(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < c.len() {
        if c[i] == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if c[i] == '/' && c.get(i + 1) == Some(&'*') {
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
                    if c[i] == '\n' {
                        out.push('\n');
                    }
                    i += 1;
                }
            }
            out.push(' ');
        } else if c[i] == 'r'
            && (c.get(i + 1) == Some(&'"') || c.get(i + 1) == Some(&'#'))
            && !i
                .checked_sub(1)
                .is_some_and(|p| c[p].is_alphanumeric() || c[p] == '_')
        {
            // A raw string r"…" or r#"…"#.
            let mut j = i + 1;
            let mut hashes = 0;
            while c.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if c.get(j) != Some(&'"') {
                out.push(c[i]);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= c.len() {
                    break;
                }
                if c[j] == '"' && (0..hashes).all(|h| c.get(j + 1 + h) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            out.push_str("\"\"");
            push_newlines(&mut out, &c[i..j.min(c.len())]);
            i = j;
        } else if c[i] == '"' {
            let start = i;
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    i += 1;
                }
                i += 1;
            }
            i += 1;
            out.push_str("\"\"");
            push_newlines(&mut out, &c[start..i.min(c.len())]);
        } else if c[i] == '\'' {
            // A character literal ('x', '\n', '\u{..}') or a lifetime ('a).
            if c.get(i + 1) == Some(&'\\') {
                i += 2;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
                out.push_str("' '");
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
                out.push_str("' '");
            } else {
                out.push(c[i]);
                i += 1;
            }
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// Appends the line breaks of `skipped` (a string or comment replaced by blanks) to `out`.
fn push_newlines(out: &mut String, skipped: &[char]) {
    out.extend(skipped.iter().filter(|&&ch| ch == '\n'));
}

/// The code without the items under `#[cfg(test)]` (test modules, test-only imports).
fn strip_test_items(code: &str) -> String {
    const MARK: &str = "#[cfg(test)]";
    let mut out = String::with_capacity(code.len());
    let mut rest = code;
    while let Some(at) = rest.find(MARK) {
        out.push_str(&rest[..at]);
        let item = &rest[at + MARK.len()..];
        // The item ends at its first `;` if that comes before any `{`, else at the brace that
        // closes its first `{`.
        let semi = item.find(';');
        let brace = item.find('{');
        let end = match (semi, brace) {
            (Some(s), Some(b)) if s < b => s + 1,
            (Some(s), None) => s + 1,
            (_, Some(b)) => {
                let mut depth = 0usize;
                let mut end = item.len();
                for (k, ch) in item[b..].char_indices() {
                    match ch {
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = b + k + 1;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                end
            }
            (None, None) => item.len(),
        };
        rest = &item[end..];
    }
    out.push_str(rest);
    out
}

fn is_ident_char(ch: char) -> bool {
    ch.is_alphanumeric() || ch == '_'
}

/// Every path in `use` statements, expanded (`use crate::{a::{b, c}, d}` gives `crate::a::b`,
/// `crate::a::c`, `crate::d`), and every other `crate::`/`super::`/`self::` path in the code.
fn paths_in(code: &str) -> Vec<Vec<String>> {
    let mut paths = Vec::new();
    let chars: Vec<char> = code.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let at_word_start = i == 0 || !is_ident_char(chars[i - 1]);
        if !at_word_start || !is_ident_char(chars[i]) {
            i += 1;
            continue;
        }
        let start = i;
        while i < chars.len() && is_ident_char(chars[i]) {
            i += 1;
        }
        let word: String = chars[start..i].iter().collect();
        if word == "use" {
            let end = chars[i..]
                .iter()
                .position(|&ch| ch == ';')
                .map_or(chars.len(), |p| i + p);
            let tree: String = chars[i..end].iter().collect();
            expand_use_tree(&tree, &mut Vec::new(), &mut paths);
            i = end;
        } else if matches!(word.as_str(), "crate" | "super" | "self") {
            let mut path = vec![word];
            loop {
                let mut j = i;
                while j < chars.len() && chars[j].is_whitespace() {
                    j += 1;
                }
                if chars.get(j) != Some(&':') || chars.get(j + 1) != Some(&':') {
                    break;
                }
                j += 2;
                while j < chars.len() && chars[j].is_whitespace() {
                    j += 1;
                }
                let s = j;
                while j < chars.len() && is_ident_char(chars[j]) {
                    j += 1;
                }
                if s == j {
                    break;
                }
                path.push(chars[s..j].iter().collect());
                i = j;
            }
            paths.push(path);
        }
    }
    paths
}

/// Expands one `use` tree (the text between `use` and `;`) below `prefix`.
fn expand_use_tree(tree: &str, prefix: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    let tree = tree.trim();
    // Split at the top-level `::` before the first `{`.
    if let Some(brace) = tree.find('{') {
        let head = tree[..brace].trim().trim_end_matches("::").trim();
        let close = tree.rfind('}').unwrap_or(tree.len());
        let inner = &tree[brace + 1..close];
        let depth_before = prefix.len();
        prefix.extend(
            head.split("::")
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(String::from),
        );
        let mut depth = 0usize;
        let mut part_start = 0;
        for (k, ch) in inner.char_indices() {
            match ch {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    expand_use_tree(&inner[part_start..k], prefix, out);
                    part_start = k + 1;
                }
                _ => {}
            }
        }
        expand_use_tree(&inner[part_start..], prefix, out);
        prefix.truncate(depth_before);
    } else {
        let tree = tree.split(" as ").next().unwrap_or(tree).trim();
        if tree.is_empty() {
            return;
        }
        let mut path = prefix.clone();
        for seg in tree.split("::").map(str::trim) {
            if seg == "self" && !path.is_empty() {
                continue;
            }
            path.push(seg.to_string());
        }
        out.push(path);
    }
}

/// The absolute module path a path names, seen from `module`; `None` for a path into another
/// crate.
fn resolve(module: &[String], path: &[String]) -> Option<Vec<String>> {
    let mut base: Vec<String> = match path.first().map(String::as_str) {
        Some("crate") => Vec::new(),
        Some("super") | Some("self") => module.to_vec(),
        _ => return None,
    };
    let mut rest = &path[1..];
    if path[0] == "super" {
        base.pop()?;
    }
    while rest.first().map(String::as_str) == Some("super") {
        base.pop()?;
        rest = &rest[1..];
    }
    base.extend(rest.iter().cloned());
    Some(base)
}

/// Edges (from, to), each with one (source file, path) that makes it.
type Edges = BTreeMap<(String, String), (String, String)>;

struct Graph {
    /// Between top-level modules.
    modules: Edges,
    /// Between the files of each module.
    files: BTreeMap<String, Edges>,
}

fn build_graph(sources: &[Source]) -> Graph {
    // The file nodes of each module: `src/m/x.rs` and `src/m/x/` are node `x` of `m`.
    let mut file_nodes: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for s in sources {
        if s.module.len() >= 2 {
            file_nodes
                .entry(s.module[0].clone())
                .or_default()
                .insert(s.module[1].clone());
        }
    }
    let tops: BTreeSet<&str> = sources
        .iter()
        .filter_map(|s| s.module.first())
        .map(String::as_str)
        .collect();
    let mut graph = Graph {
        modules: BTreeMap::new(),
        files: BTreeMap::new(),
    };
    for s in sources {
        let Some(top) = s.module.first() else {
            continue;
        };
        for path in paths_in(&s.code) {
            let Some(target) = resolve(&s.module, &path) else {
                continue;
            };
            let Some(target_top) = target.first() else {
                continue;
            };
            if !tops.contains(target_top.as_str()) {
                // A `#[macro_export]` macro at the crate root, not a module.
                continue;
            }
            let why = (s.rel.clone(), path.join("::"));
            if target_top != top {
                graph
                    .modules
                    .entry((top.clone(), target_top.clone()))
                    .or_insert(why);
                continue;
            }
            let (Some(from), Some(to)) = (s.module.get(1), target.get(1)) else {
                continue;
            };
            let is_file = file_nodes.get(top).is_some_and(|n| n.contains(to));
            if from != to && is_file {
                graph
                    .files
                    .entry(top.clone())
                    .or_default()
                    .insert((from.clone(), to.clone()), why);
            }
        }
    }
    graph
}

/// The groups of nodes that reach each other (the strongly connected components with more
/// than one node): every import loop lies inside one of them.
fn loops(edges: &BTreeSet<(String, String)>) -> Vec<BTreeSet<String>> {
    let mut next: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for (a, b) in edges {
        next.entry(a).or_default().push(b);
    }
    let reach = |from: &str| {
        let mut seen = BTreeSet::new();
        let mut todo = vec![from];
        while let Some(n) = todo.pop() {
            for &m in next.get(n).map_or(&[][..], Vec::as_slice) {
                if seen.insert(m) {
                    todo.push(m);
                }
            }
        }
        seen
    };
    let reaches: BTreeMap<&str, BTreeSet<&str>> = next.keys().map(|&n| (n, reach(n))).collect();
    let mut found: Vec<BTreeSet<String>> = Vec::new();
    for (&n, from_n) in &reaches {
        if !from_n.contains(n) || found.iter().any(|l| l.contains(n)) {
            continue;
        }
        let group = from_n
            .iter()
            .filter(|&&m| reaches.get(m).is_some_and(|r| r.contains(n)))
            .map(|m| m.to_string())
            .collect();
        found.push(group);
    }
    found
}

fn sources() -> Vec<Source> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut out = Vec::new();
    collect_sources(&root, &root, &mut out);
    out
}

#[test]
fn no_module_uses_a_higher_layer() {
    let sources = sources();
    let graph = build_graph(&sources);
    let rank = |m: &str| LAYERS.iter().position(|layer| layer.contains(&m));
    let mut problems = Vec::new();
    let tops: BTreeSet<&str> = sources
        .iter()
        .filter_map(|s| s.module.first())
        .map(String::as_str)
        .collect();
    for top in tops {
        if rank(top).is_none() {
            problems.push(format!(
                "module `{top}` is not in LAYERS (tests/layering.rs): place it in the layer order"
            ));
        }
    }
    for ((from, to), (file, path)) in &graph.modules {
        if let (Some(a), Some(b)) = (rank(from), rank(to)) {
            if b < a {
                problems.push(format!(
                    "`{from}` uses the higher layer `{to}`: {file} names `{path}`"
                ));
            } else if b == a {
                problems.push(format!(
                    "`{from}` uses `{to}` of its own layer: {file} names `{path}`"
                ));
            }
        }
    }
    assert!(
        problems.is_empty(),
        "layering breaks:\n  {}",
        problems.join("\n  ")
    );
}

#[test]
fn no_import_loop_within_a_module() {
    let graph = build_graph(&sources());
    let mut problems = Vec::new();
    for (module, edges) in &graph.files {
        let keys: BTreeSet<(String, String)> = edges.keys().cloned().collect();
        for group in loops(&keys) {
            let steps: Vec<String> = edges
                .iter()
                .filter(|((a, b), _)| group.contains(a) && group.contains(b))
                .map(|((a, b), (file, path))| format!("{a} → {b} ({file}: `{path}`)"))
                .collect();
            let names: Vec<&str> = group.iter().map(String::as_str).collect();
            problems.push(format!(
                "{module}: {} import each other\n    {}",
                names.join(", "),
                steps.join("\n    ")
            ));
        }
    }
    assert!(
        problems.is_empty(),
        "import loops:\n  {}",
        problems.join("\n  ")
    );
}

/// The checker itself: it finds the edges and loops it is meant to find.
#[test]
fn the_checker_sees_uses_and_loops() {
    let code = strip_test_items(&strip_comments_and_strings(
        "use crate::{graph::{ImageDesc, execute}, vk::Context as Ctx};\n\
         // crate::app::ignored\n\
         let s = \"crate::bench::ignored\";\n\
         fn f() { super::stereo::pack(); crate::scene::load(); }\n\
         #[cfg(test)]\nmod tests { use crate::cli::x; }\n",
    ));
    let mut got: Vec<String> = paths_in(&code).iter().map(|p| p.join("::")).collect();
    got.sort();
    assert_eq!(
        got,
        [
            "crate::graph::ImageDesc",
            "crate::graph::execute",
            "crate::scene::load",
            "crate::vk::Context",
            "super::stereo::pack",
        ]
    );
    let module = ["render".to_string(), "gbuffer".to_string()];
    let resolved = resolve(&module, &["super".into(), "stereo".into(), "pack".into()]);
    assert_eq!(
        resolved,
        Some(vec!["render".into(), "stereo".into(), "pack".into()])
    );

    let edges: BTreeSet<(String, String)> = [("a", "b"), ("b", "c"), ("c", "a"), ("c", "d")]
        .iter()
        .map(|&(a, b)| (a.to_string(), b.to_string()))
        .collect();
    let found = loops(&edges);
    assert_eq!(found.len(), 1, "one loop: {found:?}");
    assert_eq!(
        found[0].iter().map(String::as_str).collect::<Vec<_>>(),
        ["a", "b", "c"]
    );
    let acyclic: BTreeSet<(String, String)> =
        edges.iter().filter(|(a, _)| a != "c").cloned().collect();
    assert!(loops(&acyclic).is_empty());
}

/// The longest a function in `src/` may be, in lines from its `fn` line to its closing brace.
/// A longer one is to be split into named steps (issue #34).
const MAX_FUNCTION_LINES: usize = 150;

/// Every function with a body in `code` (stripped of comments and strings, line breaks kept):
/// its name, first line (1-based) and length in lines, `fn` line to closing brace.
fn function_lengths(code: &str) -> Vec<(String, usize, usize)> {
    let chars: Vec<char> = code.chars().collect();
    let line_at = |k: usize| 1 + chars[..k].iter().filter(|&&ch| ch == '\n').count();
    let mut found = Vec::new();
    let mut i = 0;
    while i + 2 < chars.len() {
        let is_fn = chars[i] == 'f'
            && chars[i + 1] == 'n'
            && !chars[i + 2].is_alphanumeric()
            && chars[i + 2] != '_'
            && (i == 0 || !is_ident_char(chars[i - 1]));
        if !is_fn {
            i += 1;
            continue;
        }
        // `fn` then a name (a `fn(…)` pointer type has none).
        let mut j = i + 2;
        while j < chars.len() && chars[j].is_whitespace() {
            j += 1;
        }
        let name: String = chars[j..]
            .iter()
            .take_while(|&&ch| is_ident_char(ch))
            .collect();
        if name.is_empty() {
            i += 2;
            continue;
        }
        // The body's `{`, or a `;` outside brackets for a declaration without one (`-> [u8; 3]`
        // holds a `;` inside brackets).
        let mut depth = 0i32;
        let mut open = None;
        while j < chars.len() {
            match chars[j] {
                '(' | '[' => depth += 1,
                ')' | ']' => depth -= 1,
                ';' if depth == 0 => break,
                '{' if depth == 0 => {
                    open = Some(j);
                    break;
                }
                _ => {}
            }
            j += 1;
        }
        if let Some(open) = open {
            let mut braces = 0usize;
            let mut close = chars.len() - 1;
            for (k, &ch) in chars.iter().enumerate().skip(open) {
                match ch {
                    '{' => braces += 1,
                    '}' => {
                        braces -= 1;
                        if braces == 0 {
                            close = k;
                            break;
                        }
                    }
                    _ => {}
                }
            }
            let first = line_at(i);
            found.push((name, first, line_at(close) - first + 1));
        }
        // Nested functions are measured on their own too.
        i += 2;
    }
    found
}

/// Every `.rs` file under `dir`, test files included.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries =
        std::fs::read_dir(dir).unwrap_or_else(|e| panic!("cannot read {}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().and_then(|e| e.to_str()) == Some("rs") {
            out.push(path);
        }
    }
}

/// No function in `src/` (tests in it included) runs past [`MAX_FUNCTION_LINES`]: a long one
/// is split into named steps, so each reads as one idea.
#[test]
fn no_function_is_longer_than_the_limit() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    files.sort();
    assert!(files.len() > 10, "found only {} source files", files.len());
    let mut problems = Vec::new();
    for path in files {
        let text = std::fs::read_to_string(&path).expect("readable source");
        for (name, line, lines) in function_lengths(&strip_comments_and_strings(&text)) {
            if lines > MAX_FUNCTION_LINES {
                let rel = path.strip_prefix(root).expect("under the crate");
                problems.push(format!("{}:{line} `{name}`: {lines} lines", rel.display()));
            }
        }
    }
    assert!(
        problems.is_empty(),
        "functions over {MAX_FUNCTION_LINES} lines (split them into named steps):\n  {}",
        problems.join("\n  ")
    );
}

/// The measure itself: bodies from `fn` to the closing brace, declarations and `fn` pointer
/// types skipped, braces in strings and comments ignored, nested functions measured too.
#[test]
fn the_function_measure_counts_lines() {
    let code = "trait T {\n    fn declared(&self) -> [u8; 3];\n}\n\
                fn outer(f: fn(u32) -> u32) -> u32 {\n\
                    // a brace { in a comment\n\
                    let s = \"}\n}\";\n\
                    fn inner() {}\n\
                    /* a\n } \n block */\n\
                    f(1)\n\
                }\n";
    let found = function_lengths(&strip_comments_and_strings(code));
    assert_eq!(
        found,
        [("outer".to_string(), 4, 10), ("inner".to_string(), 8, 1)]
    );
}

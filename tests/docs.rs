//! The documentation stays usable (no Vulkan): every relative link in README.md and docs/
//! resolves to a file of the repository (and a `#section` to a heading of that file), the
//! README links every document under docs/, the README and the code map stay short, and
//! docs/commands.md holds the current `--help` of every command and docs/settings.md the
//! current key tables. After changing a command's flags or a key's row, regenerate them with
//!
//! ```sh
//! VOXGI_UPDATE_DOCS=1 cargo test --test docs
//! ```

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The README is the front door: what voxgi is, the quick start, the command table, links.
const README_MAX_LINES: usize = 300;
/// ARCHITECTURE.md is the code map; design notes live in docs/design/.
const ARCHITECTURE_MAX_LINES: usize = 400;
/// Help text in docs/commands.md is wrapped to this width, so that the page reads without
/// scrolling (clap prints each description as one line).
const HELP_WIDTH: usize = 100;
/// The marker before a help block: `<!-- help: voxgi render -->`.
const HELP_MARKER: &str = "<!-- help: ";

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// README.md and every Markdown file under docs/.
fn markdown_files() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir)
            .unwrap_or_else(|e| panic!("reading {}: {e}", dir.display()))
            .map(|e| e.expect("directory entry").path())
            .collect();
        entries.sort();
        for path in entries {
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|x| x == "md") {
                out.push(path);
            }
        }
    }
    let mut files = vec![root().join("README.md")];
    walk(&root().join("docs"), &mut files);
    files
}

/// The targets of the inline links and images (`[text](target)`, `![alt](target)`) outside
/// fenced code blocks and code spans.
fn link_targets(markdown: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let mut fenced = false;
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        let mut in_code = false;
        let bytes = line.as_bytes();
        let mut i = 0;
        while i < bytes.len() {
            match bytes[i] {
                b'`' => in_code = !in_code,
                b']' if !in_code && bytes.get(i + 1) == Some(&b'(') => {
                    if let Some(len) = line[i + 2..].find(')') {
                        let target = line[i + 2..i + 2 + len].trim();
                        // A title after the target: `(path "title")`.
                        let target = target.split_whitespace().next().unwrap_or("");
                        targets.push(target.trim_matches(['<', '>']).to_string());
                        i += 2 + len;
                    }
                }
                _ => {}
            }
            i += 1;
        }
    }
    targets
}

/// GitHub's anchor of a heading: lower case, spaces to hyphens, other punctuation dropped.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            '-' | '_' => Some(c),
            c if c.is_alphanumeric() => Some(c),
            _ => None,
        })
        .flat_map(char::to_lowercase)
        .collect()
}

/// The anchors of a Markdown file's headings, numbered as GitHub numbers repeated ones.
fn anchors(markdown: &str) -> HashSet<String> {
    let mut seen = HashSet::new();
    let mut fenced = false;
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        }
        if fenced || !line.starts_with('#') {
            continue;
        }
        let base = slug(line.trim_start_matches('#'));
        let mut anchor = base.clone();
        let mut n = 0;
        while seen.contains(&anchor) {
            n += 1;
            anchor = format!("{base}-{n}");
        }
        seen.insert(anchor);
    }
    seen
}

#[test]
fn every_relative_link_points_to_a_file_of_the_repository() {
    let root = root().canonicalize().expect("repository root");
    let mut broken = Vec::new();
    let mut checked = 0;
    for file in markdown_files() {
        let text = std::fs::read_to_string(&file).expect("markdown file");
        let rel = file
            .strip_prefix(&root)
            .unwrap_or(&file)
            .display()
            .to_string();
        for target in link_targets(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            checked += 1;
            let (path, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let dest = if path.is_empty() {
                file.clone()
            } else {
                file.parent().expect("file in a directory").join(path)
            };
            let Ok(dest) = dest.canonicalize() else {
                broken.push(format!("{rel}: {target} (no such file)"));
                continue;
            };
            if !dest.starts_with(&root) {
                broken.push(format!("{rel}: {target} (outside the repository)"));
                continue;
            }
            if let Some(anchor) = anchor {
                let is_markdown = dest.extension().is_some_and(|x| x == "md");
                let text = std::fs::read_to_string(&dest).unwrap_or_default();
                if is_markdown && !anchors(&text).contains(anchor) {
                    broken.push(format!("{rel}: {target} (no heading #{anchor})"));
                }
            }
        }
    }
    assert!(
        checked > 50,
        "only {checked} links found: is the parser broken?"
    );
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn readme_links_every_document() {
    let root = root();
    let readme = std::fs::read_to_string(root.join("README.md")).expect("README.md");
    let linked: HashSet<String> = link_targets(&readme)
        .into_iter()
        .map(|t| t.split('#').next().unwrap_or("").to_string())
        .collect();
    let unlinked: Vec<String> = markdown_files()
        .into_iter()
        .skip(1) // README.md itself
        .filter_map(|f| {
            let rel = f.strip_prefix(&root).ok()?.to_string_lossy().into_owned();
            (!linked.contains(&rel)).then_some(rel)
        })
        .collect();
    assert!(
        unlinked.is_empty(),
        "README.md's Documentation list does not link {unlinked:?}"
    );
}

#[test]
fn link_parser_finds_links_and_skips_code() {
    let md = "see [a](x.md#b) and ![i](img.png \"t\") but not `[c](y.md)`\n\
              ```\n[d](z.md)\n```\n[e](<w.md>)";
    assert_eq!(link_targets(md), ["x.md#b", "img.png", "w.md"]);
    let anchors = anchors("# A title\n## `voxgi bench leak`\n## Flags, shared\n## Flags, shared");
    for a in [
        "a-title",
        "voxgi-bench-leak",
        "flags-shared",
        "flags-shared-1",
    ] {
        assert!(anchors.contains(a), "{a} missing from {anchors:?}");
    }
}

#[test]
fn readme_and_code_map_stay_short() {
    for (file, max) in [
        ("README.md", README_MAX_LINES),
        ("docs/ARCHITECTURE.md", ARCHITECTURE_MAX_LINES),
    ] {
        let text = std::fs::read_to_string(root().join(file)).expect(file);
        let lines = text.lines().count();
        assert!(
            lines <= max,
            "{file} has {lines} lines, at most {max}: move detail to docs/"
        );
    }
}

/// `voxgi ARGS --help` as the program prints it.
fn raw_help(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_voxgi"))
        .args(args)
        .arg("--help")
        .output()
        .expect("voxgi runs");
    assert!(out.status.success(), "voxgi {args:?} --help failed");
    String::from_utf8(out.stdout).expect("UTF-8 help")
}

/// `voxgi ARGS --help`, each line wrapped to [`HELP_WIDTH`] at spaces, trailing spaces removed.
fn help(args: &[&str]) -> String {
    let mut wrapped = String::new();
    for line in raw_help(args).lines() {
        wrap(line.trim_end(), &mut wrapped);
    }
    wrapped
}

/// Where a wrapped line continues: under the text of an item (`  -o, --out <PATH>  text`,
/// `  render  text`, `- name: text`), else under the line's own indentation.
fn hanging_indent(line: &str) -> usize {
    let indent = line.len() - line.trim_start().len();
    let body = &line[indent..];
    let text_after = |at: usize| {
        let rest = &body[at..];
        indent + at + rest.len() - rest.trim_start().len()
    };
    if body.starts_with("- ") {
        if let Some(colon) = body.find(": ") {
            return text_after(colon + 1);
        }
    }
    match body.find("  ") {
        Some(gap) if indent > 0 && gap < 40 => text_after(gap),
        _ => indent,
    }
}

fn wrap(line: &str, out: &mut String) {
    let indent = line.len() - line.trim_start().len();
    let hang = hanging_indent(line);
    let mut current = String::new();
    for word in line[indent..].split(' ') {
        let fits = current.chars().count() + 1 + word.chars().count() <= HELP_WIDTH;
        if current.is_empty() {
            current = format!("{}{word}", " ".repeat(indent));
        } else if fits || current.trim().is_empty() {
            current.push(' ');
            current.push_str(word);
        } else {
            out.push_str(current.trim_end());
            out.push('\n');
            current = format!("{}{word}", " ".repeat(hang));
        }
    }
    out.push_str(current.trim_end());
    out.push('\n');
}

/// The subcommands a `--help` lists under "Commands:", without `help`.
fn subcommands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter(|l| l.starts_with("  ") && !l.starts_with("   "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_string)
        .collect()
}

/// docs/commands.md with every help block replaced by the binary's current help.
fn regenerated(doc: &str) -> String {
    let mut out = String::new();
    let mut lines = doc.lines().peekable();
    while let Some(line) = lines.next() {
        out.push_str(line);
        out.push('\n');
        let Some(command) = line
            .strip_prefix(HELP_MARKER)
            .and_then(|l| l.strip_suffix(" -->"))
        else {
            continue;
        };
        let args: Vec<&str> = command.split_whitespace().skip(1).collect();
        // Drop the old block, if any.
        if lines.peek().is_some_and(|l| l.starts_with("```")) {
            lines.next();
            for l in lines.by_ref() {
                if l.starts_with("```") {
                    break;
                }
            }
        }
        out.push_str("```text\n");
        out.push_str(&help(&args));
        out.push_str("```\n");
    }
    out
}

#[test]
fn commands_md_holds_the_current_help_of_every_command() {
    let path = root().join("docs/commands.md");
    let doc = std::fs::read_to_string(&path).expect("docs/commands.md");
    let new = regenerated(&doc);
    if std::env::var_os("VOXGI_UPDATE_DOCS").is_some() {
        std::fs::write(&path, &new).expect("writing docs/commands.md");
    } else {
        assert!(
            new == doc,
            "docs/commands.md is not the current --help output: run \
             `VOXGI_UPDATE_DOCS=1 cargo test --test docs` and commit the file"
        );
    }
    let mut missing = Vec::new();
    let mut commands: Vec<String> = subcommands(&raw_help(&[]))
        .into_iter()
        .map(|c| format!("voxgi {c}"))
        .collect();
    commands.extend(
        subcommands(&raw_help(&["bench"]))
            .into_iter()
            .map(|c| format!("voxgi bench {c}")),
    );
    assert!(commands.len() > 15, "commands found: {commands:?}");
    for command in commands {
        if !doc.contains(&format!("{HELP_MARKER}{command} -->")) {
            missing.push(command);
        }
    }
    assert!(
        missing.is_empty(),
        "docs/commands.md has no help block for {missing:?}: add a section with \
         `{HELP_MARKER}voxgi COMMAND -->` and run `VOXGI_UPDATE_DOCS=1 cargo test --test docs`"
    );
}

/// The marker before a key table of docs/settings.md: `<!-- keys: post -->`.
const KEYS_MARKER: &str = "<!-- keys: ";

/// docs/settings.md with every key table replaced by the schema's current one.
fn settings_regenerated(doc: &str) -> String {
    use voxgi::scene::schema::doc_table;
    let mut out = String::new();
    let mut lines = doc.lines().peekable();
    while let Some(line) = lines.next() {
        out.push_str(line);
        out.push('\n');
        let Some(table) = line
            .strip_prefix(KEYS_MARKER)
            .and_then(|l| l.strip_suffix(" -->"))
        else {
            continue;
        };
        while lines.peek().is_some_and(|l| l.starts_with('|')) {
            lines.next();
        }
        out.push_str(&match table {
            "gi" => doc_table::<voxgi::scene::GiSettings>(),
            "post" => doc_table::<voxgi::scene::PostTable>(),
            "shadow" => doc_table::<voxgi::scene::ShadowSettings>(),
            "voxel" => doc_table::<voxgi::scene::VoxelSettings>(),
            other => panic!("docs/settings.md: no key table `{other}`"),
        });
    }
    out
}

#[test]
fn settings_md_lists_every_key_of_every_table() {
    let path = root().join("docs/settings.md");
    let doc = std::fs::read_to_string(&path).expect("docs/settings.md");
    let new = settings_regenerated(&doc);
    if std::env::var_os("VOXGI_UPDATE_DOCS").is_some() {
        std::fs::write(&path, &new).expect("writing docs/settings.md");
    } else {
        assert!(
            new == doc,
            "docs/settings.md's key tables are not the schema's: run \
             `VOXGI_UPDATE_DOCS=1 cargo test --test docs` and commit the file"
        );
    }
    for table in ["gi", "post", "shadow"] {
        assert!(
            doc.contains(&format!("{KEYS_MARKER}{table} -->")),
            "docs/settings.md has no `{KEYS_MARKER}{table} -->` table"
        );
    }
}

#[test]
fn help_wrapping_keeps_words_and_hangs_under_the_text() {
    let words = "word ".repeat(40);
    for (line, hang) in [
        (format!("      --flag <N>  {words}"), 18),
        (format!("  render  {words}"), 10),
        (format!("          - paraboloid: {words}"), 24),
        (format!("          {words}"), 10),
    ] {
        let mut out = String::new();
        wrap(&line, &mut out);
        assert!(out.lines().count() > 1, "{out}");
        for l in out.lines().skip(1) {
            let indent = l.len() - l.trim_start().len();
            assert_eq!(indent, hang, "{l:?} of {line:?}");
        }
        assert!(out.lines().all(|l| l.chars().count() <= HELP_WIDTH));
        assert_eq!(
            out.split_whitespace().count(),
            line.split_whitespace().count()
        );
    }
}

#[test]
fn subcommands_are_read_from_the_commands_list() {
    let help = "Usage: voxgi <COMMAND>\n\nCommands:\n  render  Renders\n  bench   Runs\n  \
                help    Print this\n\nOptions:\n  -h, --help  Print help\n";
    assert_eq!(subcommands(help), ["render", "bench"]);
}

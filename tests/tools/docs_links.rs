//! The design notes in `docs/` and the citations of them (docs/README.md#citations): every
//! `docs/<file>.md#<anchor>` written anywhere in the source tree, and every relative link inside
//! `docs/`, names a file that exists and a heading it has; and no source file cites the
//! project's steering SPEC, which is not in this repository, as its source.
//!
//! Plain `std`, no build of anything: it reads the tracked tree's text files (a few hundred,
//! well under a second).

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// The repository's root (host-sim's parent).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("host-sim has a parent")
        .to_path_buf()
}

/// Folders never read: build output and version control.
const SKIPPED_DIRS: [&str; 3] = ["target", ".git", "out"];
/// Files read: source, build and documentation text.
const EXTENSIONS: [&str; 7] = ["rs", "md", "toml", "py", "sh", "x", "yml"];

/// Every text file of the tree under `dir` worth reading, sorted.
fn text_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for path in entries {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if path.is_dir() {
            if !SKIPPED_DIRS.contains(&name) {
                text_files(&path, out);
            }
        } else {
            let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
            // `.ci/` holds scripts without an extension.
            let in_ci = path.parent().and_then(|p| p.file_name()) == Some(".ci".as_ref());
            if EXTENSIONS.contains(&ext) || in_ci {
                out.push(path);
            }
        }
    }
}

/// GitHub's anchor of a Markdown heading's text: lower case, letters, digits, `-` and `_`
/// kept, spaces as `-`, everything else dropped.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors of a Markdown file's headings (outside code fences), with GitHub's `-1`,
/// `-2` suffixes for repeats.
fn anchors(markdown: &str) -> BTreeSet<String> {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut out = BTreeSet::new();
    let mut fenced = false;
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced || !line.starts_with('#') {
            continue;
        }
        let text = line.trim_start_matches('#');
        if !text.starts_with(' ') {
            continue;
        }
        let base = slug(text);
        let n = seen.entry(base.clone()).or_insert(0);
        out.insert(if *n == 0 {
            base.clone()
        } else {
            format!("{base}-{n}")
        });
        *n += 1;
    }
    out
}

fn is_path_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '/')
}

fn is_anchor_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '_' | '-')
}

/// `(file, anchor)` of every `docs/<file>.md` or `docs/<file>.md#<anchor>` in `text`.
fn citations(text: &str) -> Vec<(String, Option<String>)> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(at) = rest.find("docs/") {
        // Not the tail of a longer path (`shared/docs/...`, a URL).
        let before = rest[..at].chars().next_back();
        rest = &rest[at + "docs/".len()..];
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '/' || c == '_') {
            continue;
        }
        let file: String = rest.chars().take_while(|&c| is_path_char(c)).collect();
        let file = file.trim_end_matches('.').to_string();
        if !file.ends_with(".md") {
            continue;
        }
        let after = &rest[file.len()..];
        let anchor = after
            .strip_prefix('#')
            .map(|a| a.chars().take_while(|&c| is_anchor_char(c)).collect());
        out.push((file, anchor));
    }
    out
}

/// `(target, anchor)` of every relative Markdown link `](target#anchor)` in `markdown`.
fn relative_links(markdown: &str) -> Vec<(String, Option<String>)> {
    let mut out = Vec::new();
    let mut rest = markdown;
    while let Some(at) = rest.find("](") {
        rest = &rest[at + 2..];
        let Some(end) = rest.find(')') else { break };
        let link = &rest[..end];
        if link.contains("://") || link.starts_with("mailto:") {
            continue;
        }
        let (target, anchor) = match link.split_once('#') {
            Some((t, a)) => (t.to_string(), Some(a.to_string())),
            None => (link.to_string(), None),
        };
        out.push((target, anchor));
    }
    out
}

/// Checks that `file` (relative to the repository's root) exists and, for a Markdown file
/// with an anchor, has that heading; a message when not.
fn check(root: &Path, file: &Path, anchor: Option<&str>) -> Option<String> {
    let path = root.join(file);
    if !path.exists() {
        return Some(format!("{} does not exist", file.display()));
    }
    // Only a Markdown file's headings are read (a figure is not text).
    let anchor = anchor.filter(|a| !a.is_empty())?;
    if file.extension().and_then(|e| e.to_str()) != Some("md") {
        return None;
    }
    let Ok(text) = fs::read_to_string(&path) else {
        return Some(format!("{} cannot be read as text", file.display()));
    };
    let known = anchors(&text);
    (!known.contains(anchor)).then(|| {
        format!(
            "{} has no heading #{anchor} (it has: {})",
            file.display(),
            known.iter().cloned().collect::<Vec<_>>().join(", ")
        )
    })
}

#[test]
fn every_docs_citation_names_a_file_and_heading_that_exist() {
    let root = root();
    let mut files = Vec::new();
    text_files(&root, &mut files);
    assert!(
        files.iter().any(|f| f.ends_with("shared/src/lib.rs")),
        "the walk found the source tree"
    );
    let mut broken = Vec::new();
    let mut cited = 0;
    for path in &files {
        let Ok(text) = fs::read_to_string(path) else {
            continue;
        };
        let shown = path
            .strip_prefix(&root)
            .unwrap_or(path)
            .display()
            .to_string();
        for (file, anchor) in citations(&text) {
            cited += 1;
            let target = Path::new("docs").join(&file);
            if let Some(why) = check(&root, &target, anchor.as_deref()) {
                broken.push(format!("{shown}: docs/{file}: {why}"));
            }
        }
    }
    assert!(cited > 0, "no citation of docs/ found anywhere");
    assert!(
        broken.is_empty(),
        "broken citations of docs/:\n{}",
        broken.join("\n")
    );
}

#[test]
fn links_inside_docs_resolve() {
    let root = root();
    let docs = root.join("docs");
    let mut broken = Vec::new();
    let mut pages = Vec::new();
    text_files(&docs, &mut pages);
    assert!(!pages.is_empty(), "docs/ has pages");
    for page in pages
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
    {
        let text = fs::read_to_string(page).expect("a docs page reads");
        let shown = page
            .strip_prefix(&root)
            .unwrap_or(page)
            .display()
            .to_string();
        for (target, anchor) in relative_links(&text) {
            // A link to the page itself (`#anchor`), or to a path relative to the page.
            let file = if target.is_empty() {
                page.strip_prefix(&root).unwrap_or(page).to_path_buf()
            } else {
                let joined = Path::new("docs").join(&target);
                // Normalise `docs/../README.md` to `README.md`.
                let mut parts: Vec<&std::ffi::OsStr> = Vec::new();
                for c in joined.components() {
                    match c {
                        std::path::Component::ParentDir => {
                            parts.pop();
                        }
                        std::path::Component::Normal(p) => parts.push(p),
                        _ => {}
                    }
                }
                parts.iter().collect()
            };
            if let Some(why) = check(&root, &file, anchor.as_deref()) {
                broken.push(format!(
                    "{shown}: ({target}#{}): {why}",
                    anchor.unwrap_or_default()
                ));
            }
        }
    }
    assert!(
        broken.is_empty(),
        "broken links in docs/:\n{}",
        broken.join("\n")
    );
}

#[test]
fn no_source_cites_the_steering_spec() {
    // Spelt in two parts so this file does not match itself.
    let needle = concat!("SPEC", ".md");
    let root = root();
    let mut files = Vec::new();
    text_files(&root, &mut files);
    let offenders: Vec<String> = files
        .iter()
        .filter(|p| fs::read_to_string(p).is_ok_and(|t| t.contains(needle)))
        .map(|p| p.strip_prefix(&root).unwrap_or(p).display().to_string())
        .collect();
    assert!(
        offenders.is_empty(),
        "{needle} is not in this repository; cite docs/ instead (docs/README.md#citations): {}",
        offenders.join(", ")
    );
}

#[test]
fn anchors_follow_github() {
    assert_eq!(slug(" Lift-off thrust"), "lift-off-thrust");
    assert_eq!(slug(" The paper's cases"), "the-papers-cases");
    assert_eq!(slug(" det(B B^T) and balance"), "detb-bt-and-balance");
    let a = anchors("# A\n## B c\n```\n# not a heading\n```\n## B c\n#nospace\n");
    assert_eq!(
        a.into_iter().collect::<Vec<_>>(),
        ["a", "b-c", "b-c-1"].map(String::from)
    );
    assert_eq!(
        citations("see docs/models.md#lift-off-thrust; docs/system.md. and x/docs/no.md"),
        vec![
            ("models.md".to_string(), Some("lift-off-thrust".to_string())),
            ("system.md".to_string(), None)
        ]
    );
}

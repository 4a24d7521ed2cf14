//! The documentation's links resolve: in README.md, every `docs/**/*.md`, `pipelines/README.md`
//! and any README under `verify/`, every Markdown link or image target `](target)`, reference
//! definition `[label]: target` and HTML `<a href>`/`<img src>` that is a relative path (not
//! `http(s):`, `mailto:` or another scheme, not a pure `#anchor`) names a file or directory that
//! exists, resolved from the document's directory; a `file.md#anchor` or `#anchor` link names a
//! heading of that file by its GitHub slug. And the README stays a front door: at most
//! `README_MAX_LINES` lines. Fenced code blocks and inline code spans hold no links.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

const README_MAX_LINES: usize = 250;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The Markdown files whose links are checked, relative to the root.
fn documents(root: &Path) -> Vec<PathBuf> {
    let mut docs = vec![PathBuf::from("README.md")];
    markdown_under(root, Path::new("docs"), &mut docs);
    for readme in ["pipelines/README.md"] {
        if root.join(readme).is_file() {
            docs.push(PathBuf::from(readme));
        }
    }
    let mut verify = Vec::new();
    markdown_under(root, Path::new("verify"), &mut verify);
    docs.extend(verify.into_iter().filter(|p| {
        p.file_name()
            .is_some_and(|n| n.to_string_lossy().eq_ignore_ascii_case("README.md"))
    }));
    docs
}

fn markdown_under(root: &Path, dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(root.join(dir)) else {
        return;
    };
    let mut entries: Vec<_> = entries.map(|e| e.unwrap().file_name()).collect();
    entries.sort();
    for name in entries {
        let rel = dir.join(&name);
        let path = root.join(&rel);
        if path.is_dir() {
            markdown_under(root, &rel, out);
        } else if rel.extension().is_some_and(|e| e == "md") {
            out.push(rel);
        }
    }
}

/// The lines of a text with those of fenced code blocks (three or more backticks or tildes, closed
/// by a fence of the same character at least as long) blanked, so line numbers hold.
fn outside_fences(text: &str) -> Vec<&str> {
    let mut lines = Vec::new();
    let mut fence: Option<(char, usize)> = None;
    for line in text.lines() {
        let trimmed = line.trim_start_matches(' ');
        let indent = line.len() - trimmed.len();
        let opener = ['`', '~'].into_iter().find_map(|c| {
            let n = trimmed.chars().take_while(|&x| x == c).count();
            (indent <= 3 && n >= 3).then_some((c, n))
        });
        match (fence, opener) {
            (None, Some(f)) => {
                fence = Some(f);
                lines.push("");
            }
            (Some((c, n)), Some((c2, n2)))
                if c == c2 && n2 >= n && trimmed[n2..].trim().is_empty() =>
            {
                fence = None;
                lines.push("");
            }
            (Some(_), _) => lines.push(""),
            (None, None) => lines.push(line),
        }
    }
    lines
}

/// The text with fenced code blocks and inline code spans blanked (newlines kept, so line
/// numbers hold).
fn prose(text: &str) -> String {
    let unfenced = outside_fences(text).join("\n");
    // Code spans: a run of n backticks up to the next run of exactly n, within a paragraph.
    let chars: Vec<char> = unfenced.chars().collect();
    let mut out = chars.clone();
    let mut i = 0;
    while i < chars.len() {
        if chars[i] != '`' {
            i += 1;
            continue;
        }
        let n = chars[i..].iter().take_while(|&&c| c == '`').count();
        let mut j = i + n;
        let mut close = None;
        while j < chars.len() {
            if chars[j] == '\n'
                && chars[j + 1..]
                    .iter()
                    .take_while(|&&c| c != '\n')
                    .all(|c| c.is_whitespace())
            {
                break; // a blank line ends the paragraph
            }
            if chars[j] == '`' {
                let m = chars[j..].iter().take_while(|&&c| c == '`').count();
                if m == n {
                    close = Some(j);
                    break;
                }
                j += m;
            } else {
                j += 1;
            }
        }
        match close {
            Some(j) => {
                for c in &mut out[i..j + n] {
                    if *c != '\n' {
                        *c = ' ';
                    }
                }
                i = j + n;
            }
            None => i += n,
        }
    }
    out.into_iter().collect()
}

/// Every link target of a document, with its line (1-based).
fn links(text: &str) -> Vec<(usize, String)> {
    let prose = prose(text);
    let mut found = Vec::new();
    for (k, line) in prose.lines().enumerate() {
        let number = k + 1;
        // Inline links and images: `](target)` or `](<target>)`, an optional title after a space.
        let mut rest = line;
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            let target = if let Some(inner) = after.strip_prefix('<') {
                inner.split('>').next().unwrap_or("").to_string()
            } else {
                let mut depth = 0usize;
                let mut end = after.len();
                for (p, c) in after.char_indices() {
                    match c {
                        '(' => depth += 1,
                        ')' if depth == 0 => {
                            end = p;
                            break;
                        }
                        ')' => depth -= 1,
                        c if c.is_whitespace() => {
                            end = p;
                            break;
                        }
                        _ => {}
                    }
                }
                after[..end].to_string()
            };
            found.push((number, target));
            rest = after;
        }
        // Reference definitions: `[label]: target`.
        let trimmed = line.trim_start();
        if line.len() - trimmed.len() <= 3
            && trimmed.starts_with('[')
            && let Some(close) = trimmed.find("]:")
            && !trimmed[1..close].contains(']')
            && let Some(target) = trimmed[close + 2..].split_whitespace().next()
        {
            let target = target.trim_start_matches('<').trim_end_matches('>');
            found.push((number, target.to_string()));
        }
        // HTML: `<a … href="…">`, `<img … src="…">`.
        for (tag, attribute) in [("<a ", "href="), ("<img ", "src=")] {
            let lower = line.to_ascii_lowercase();
            let mut from = 0;
            while let Some(start) = lower[from..].find(tag).map(|s| s + from) {
                let end = lower[start..].find('>').map_or(lower.len(), |e| e + start);
                if let Some(a) = lower[start..end]
                    .find(attribute)
                    .map(|a| a + start + attribute.len())
                {
                    let value = &line[a..end];
                    let target = match value.chars().next() {
                        Some(q @ ('"' | '\'')) => value[1..].split(q).next().unwrap_or(""),
                        _ => value.split(char::is_whitespace).next().unwrap_or(""),
                    };
                    found.push((number, target.to_string()));
                }
                from = end.max(start + 1);
            }
        }
    }
    found
}

/// GitHub's anchor for a heading: its text lowercased, every character but letters, marks,
/// digits, `-` and `_` dropped, spaces turned into `-`; a repeated slug gets `-1`, `-2`, ….
fn slug(heading: &str) -> String {
    // A link in a heading shows its text.
    let mut text = String::new();
    let mut rest = heading;
    while let Some(open) = rest.find('[') {
        match rest[open..].find("](").map(|m| m + open) {
            Some(mid) if !rest[open + 1..mid].contains('[') => {
                let close = rest[mid..].find(')').map_or(rest.len(), |c| c + mid);
                text.push_str(&rest[..open]);
                text.push_str(&rest[open + 1..mid]);
                rest = &rest[(close + 1).min(rest.len())..];
            }
            _ => {
                text.push_str(&rest[..=open]);
                rest = &rest[open + 1..];
            }
        }
    }
    text.push_str(rest);
    text.trim()
        .chars()
        .flat_map(char::to_lowercase)
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors of a Markdown file's headings (ATX and setext), outside code blocks.
fn anchors(text: &str) -> BTreeSet<String> {
    // Code spans are kept: GitHub keeps their content in the slug.
    let unfenced = outside_fences(text);
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut out = BTreeSet::new();
    let mut add = |heading: &str| {
        let base = slug(heading);
        let count = seen.entry(base.clone()).or_insert(0);
        out.insert(if *count == 0 {
            base.clone()
        } else {
            format!("{base}-{count}")
        });
        *count += 1;
    };
    for (k, line) in unfenced.iter().enumerate() {
        let trimmed = line.trim_start_matches(' ');
        if line.len() - trimmed.len() > 3 {
            continue;
        }
        let hashes = trimmed.chars().take_while(|&c| c == '#').count();
        if (1..=6).contains(&hashes) {
            let rest = &trimmed[hashes..];
            if rest.is_empty() || rest.starts_with([' ', '\t']) {
                // A closing run of `#` is not part of the heading.
                let rest = rest.trim();
                let rest = rest.trim_end_matches('#');
                add(rest);
            }
            continue;
        }
        let underline = trimmed.trim_end();
        let setext = !underline.is_empty()
            && (underline.chars().all(|c| c == '=') || underline.chars().all(|c| c == '-'));
        if setext && k > 0 {
            let previous = unfenced[k - 1].trim();
            if !previous.is_empty()
                && !previous.starts_with(['#', '|', '-', '*', '>'])
                && (k < 2 || unfenced[k - 2].trim().is_empty())
            {
                add(previous);
            }
        }
    }
    out
}

/// `%XX` escapes decoded.
fn percent_decoded(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%'
            && i + 2 < bytes.len()
            && let Some(b) = std::str::from_utf8(&bytes[i + 1..i + 3])
                .ok()
                .and_then(|h| u8::from_str_radix(h, 16).ok())
        {
            out.push(b);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Whether a target is a URL with a scheme (`https:`, `mailto:`, `file:`, …).
fn has_scheme(target: &str) -> bool {
    let Some(colon) = target.find(':') else {
        return false;
    };
    let scheme = &target[..colon];
    scheme
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic())
        && scheme
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "+.-".contains(c))
}

/// The failures of one document (`file:line: target: why`), and how many links it checked.
fn check(root: &Path, doc: &Path, text: &str) -> (usize, Vec<String>) {
    let dir = doc.parent().unwrap_or(Path::new(""));
    let mut failures = Vec::new();
    let mut checked = 0;
    let mut anchor_cache: BTreeMap<PathBuf, Option<BTreeSet<String>>> = BTreeMap::new();
    for (line, target) in links(text) {
        let at = format!("{}:{line}: `{target}`", doc.display());
        if target.is_empty() {
            failures.push(format!("{at}: an empty link target"));
            continue;
        }
        if has_scheme(&target) {
            continue;
        }
        checked += 1;
        let (path_part, fragment) = match target.split_once('#') {
            Some((p, f)) => (p, Some(f)),
            None => (target.as_str(), None),
        };
        let path_part = path_part.split('?').next().unwrap_or("");
        let file = if path_part.is_empty() {
            doc.to_path_buf()
        } else if let Some(absolute) = path_part.strip_prefix('/') {
            PathBuf::from(percent_decoded(absolute))
        } else {
            dir.join(percent_decoded(path_part))
        };
        let full = root.join(&file);
        if !path_part.is_empty() && !full.exists() {
            failures.push(format!("{at}: {} does not exist", file.display()));
            continue;
        }
        let Some(fragment) = fragment else { continue };
        if file.extension().is_none_or(|e| e != "md") {
            continue; // anchors are checked in Markdown files only
        }
        let known = anchor_cache.entry(file.clone()).or_insert_with(|| {
            if path_part.is_empty() {
                Some(anchors(text)) // the document's own headings
            } else {
                fs::read_to_string(&full).ok().map(|t| anchors(&t))
            }
        });
        match known {
            None => failures.push(format!("{at}: {} cannot be read", file.display())),
            Some(set) => {
                let wanted = percent_decoded(fragment).to_lowercase();
                if !set.contains(&wanted) {
                    failures.push(format!(
                        "{at}: {} has no heading with the anchor #{wanted}",
                        file.display()
                    ));
                }
            }
        }
    }
    (checked, failures)
}

#[test]
fn every_link_of_the_documentation_resolves() {
    let root = root();
    let mut failures = Vec::new();
    let mut summary = Vec::new();
    for doc in documents(&root) {
        let text = fs::read_to_string(root.join(&doc)).unwrap();
        let (checked, mut f) = check(&root, &doc, &text);
        summary.push(format!("{}: {checked}", doc.display()));
        failures.append(&mut f);
    }
    println!(
        "relative links checked per document: {}",
        summary.join(", ")
    );
    assert!(
        failures.is_empty(),
        "{} broken link(s):\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn the_readme_is_a_front_door() {
    let text = fs::read_to_string(root().join("README.md")).unwrap();
    let lines = text.lines().count();
    assert!(
        lines <= README_MAX_LINES,
        "README.md has {lines} lines, more than {README_MAX_LINES}: its depth belongs in docs/"
    );
    // It links the chapters, so the checker above has something to check.
    let (checked, _) = check(&root(), Path::new("README.md"), &text);
    assert!(checked >= 5, "README.md has only {checked} relative links");
}

#[test]
fn the_checker_finds_what_is_broken() {
    let root = root();
    let text = "# A title\n\n## `slidestack design` and λ_code (tests, `cargo test --release`)\n\n\
        [ok](README.md) ![ok](docs/evidence/ida.svg) [ok](#a-title) \
        [ok](#slidestack-design-and-λ_code-tests-cargo-test---release)\n\
        [missing](docs/no-such-file.md) [bad anchor](README.md#no-such-heading)\n\
        `[in code](nowhere.md)` <img src=\"docs/evidence/none.svg\"> [web](https://example.org/x)\n\
        ```\n[fenced](nowhere.md)\n# not a heading\n```\n\
        [not a heading](#not-a-heading)\n";
    let (checked, failures) = check(&root, Path::new("x.md"), text);
    let broken: Vec<&str> = failures
        .iter()
        .map(|f| f.split('`').nth(1).unwrap())
        .collect();
    assert_eq!(checked, 8, "{failures:#?}");
    assert_eq!(
        broken,
        [
            "docs/no-such-file.md",
            "README.md#no-such-heading",
            "docs/evidence/none.svg",
            "#not-a-heading",
        ],
        "{failures:#?}"
    );
    let set = anchors(text);
    assert!(set.contains("a-title"), "{set:?}");
    assert!(
        set.contains("slidestack-design-and-λ_code-tests-cargo-test---release"),
        "{set:?}"
    );
    assert!(!set.contains("not-a-heading"), "{set:?}");
    assert_eq!(
        slug("Two commands (fresh Debian machine with a Rust toolchain)"),
        "two-commands-fresh-debian-machine-with-a-rust-toolchain"
    );
    assert_eq!(
        slug("Performance: the evidence that it is fast and accurate"),
        "performance-the-evidence-that-it-is-fast-and-accurate"
    );
}

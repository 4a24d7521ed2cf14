//! The layers hold: a module of `src/` names with `crate::` only modules of a lower rank of the
//! layer table in `docs/ARCHITECTURE.md` ("Layers"), the table this check reads, so the map and
//! the code cannot drift apart. Test code (`#[cfg(test)]` items) is exempt; the binary (`main.rs`,
//! `cmd/`) is a crate of its own above everything and names the library as `slidestack::`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The ranks of the table between the markers `<!-- layers -->` and `<!-- /layers -->`:
/// rows `| rank | modules |`, modules separated by commas, each in backticks.
fn layer_table(architecture: &str) -> BTreeMap<String, usize> {
    let start = architecture
        .find("<!-- layers -->")
        .expect("docs/ARCHITECTURE.md has the layer table (<!-- layers -->)");
    let end = architecture[start..]
        .find("<!-- /layers -->")
        .expect("the layer table ends with <!-- /layers -->")
        + start;
    let mut ranks = BTreeMap::new();
    for line in architecture[start..end].lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() < 4 {
            continue;
        }
        let Ok(rank) = cells[1].parse::<usize>() else {
            continue;
        };
        for module in cells[3].split(',') {
            let module = module.trim().trim_matches('`');
            assert!(
                ranks.insert(module.to_string(), rank).is_none(),
                "`{module}` twice in the layer table"
            );
        }
    }
    assert!(!ranks.is_empty(), "the layer table has no rows");
    ranks
}

/// `text` without `//` comments and without the items under `#[cfg(test)]`; each kept line with
/// its number.
fn product_lines(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut skipping = false;
    let (mut depth, mut opened) = (0i64, false);
    for (i, line) in text.lines().enumerate() {
        let code = line.find("//").map_or(line, |c| &line[..c]);
        if !skipping && code.trim() == "#[cfg(test)]" {
            (skipping, depth, opened) = (true, 0, false);
            continue;
        }
        if skipping {
            for ch in code.chars() {
                match ch {
                    '{' => (depth, opened) = (depth + 1, true),
                    '}' => depth -= 1,
                    _ => {}
                }
            }
            let ends = (opened && depth == 0) || (!opened && code.trim_end().ends_with(';'));
            if ends {
                skipping = false;
            }
            continue;
        }
        out.push((i + 1, code.to_string()));
    }
    out
}

/// The top-level modules a line names through `crate::` (`crate::a::…`, `crate::{a, b::…}`).
fn named_modules(code: &str) -> Vec<String> {
    named_after(code, "crate::")
}

/// The names a line takes right after `prefix` (`prefix a::…`, `prefix {a, b::…}`).
fn named_after(code: &str, prefix: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find(prefix) {
        let before = rest[..at].chars().last();
        rest = &rest[at + prefix.len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 0;
            let mut item = String::new();
            let mut items = Vec::new();
            for ch in group.chars() {
                match ch {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => items.push(std::mem::take(&mut item)),
                    _ => {}
                }
                if depth == 0 && ch != ',' {
                    item.push(ch);
                }
            }
            items.push(item);
            for it in items {
                let id: String = (it.trim().chars())
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !id.is_empty() {
                    names.push(id);
                }
            }
        } else {
            let id: String = (rest.chars())
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            names.push(id);
        }
    }
    names
}

/// Every `.rs` file under `dir`.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                todo.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                files.push(p);
            }
        }
    }
    files.sort();
    files
}

/// Every upward (or sideways, within one rank) `crate::` name of the library's files under
/// `src`, against `ranks`; and the modules the table does not place.
fn violations(src: &Path, ranks: &BTreeMap<String, usize>) -> Vec<String> {
    let mut found = Vec::new();
    for file in rust_files(src) {
        let rel = file.strip_prefix(src).unwrap();
        let first = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy();
        let module = first.trim_end_matches(".rs").to_string();
        if matches!(module.as_str(), "lib" | "main" | "cmd") {
            continue;
        }
        let Some(&own) = ranks.get(&module) else {
            found.push(format!("src/{}: `{module}` is in no layer", rel.display()));
            continue;
        };
        let text = std::fs::read_to_string(&file).unwrap();
        for (line, code) in product_lines(&text) {
            for named in named_modules(&code) {
                if named == module {
                    continue;
                }
                match ranks.get(&named) {
                    Some(&r) if r < own => {}
                    Some(&r) => found.push(format!(
                        "src/{}:{line}: `{module}` (rank {own}) names `crate::{named}` (rank {r}): \
                         a module may name only lower ranks",
                        rel.display()
                    )),
                    None => found.push(format!(
                        "src/{}:{line}: names `crate::{named}`, which is in no layer",
                        rel.display()
                    )),
                }
            }
        }
    }
    found
}

#[test]
fn no_module_names_a_module_of_its_own_or_a_higher_layer() {
    let architecture = std::fs::read_to_string(root().join("docs/ARCHITECTURE.md")).unwrap();
    let ranks = layer_table(&architecture);
    let found = violations(&root().join("src"), &ranks);
    assert!(
        found.is_empty(),
        "the layers of docs/ARCHITECTURE.md do not hold:\n{}",
        found.join("\n")
    );
}

/// The check itself on a made-up tree: an upward name in product code is found, in a `use`
/// group or a path, with its line; test code, comments and lower ranks are not.
#[test]
fn the_check_finds_an_upward_name_and_only_that() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    std::fs::create_dir(src.join("store")).unwrap();
    std::fs::write(
        src.join("store/fit.rs"),
        "use crate::numeric::x;\n\
         // crate::pipeline in a comment\n\
         use crate::{grid::Grid, study::building::Frame};\n\
         fn f() { crate::store::g(); }\n\
         #[cfg(test)]\n\
         mod tests {\n    use crate::pipeline::StageId;\n    fn t() { if true { } }\n}\n\
         fn h() -> usize { crate::pipeline::fit::FOLDS }\n",
    )
    .unwrap();
    std::fs::write(src.join("lib.rs"), "pub mod store;\n").unwrap();
    std::fs::write(src.join("extra.rs"), "\n").unwrap();
    let ranks = layer_table(
        "<!-- layers -->\n| rank | layer | modules |\n|---|---|---|\n\
         | 1 | kernels | `numeric`, `grid` |\n| 2 | storage | `store` |\n\
         | 3 | study | `study` |\n| 4 | pipeline | `pipeline` |\n<!-- /layers -->",
    );
    let found = violations(src, &ranks);
    assert_eq!(found.len(), 3, "{found:#?}");
    assert!(
        found[0].contains("src/extra.rs: `extra` is in no layer"),
        "{}",
        found[0]
    );
    assert!(found[1].starts_with("src/store/fit.rs:3: `store` (rank 2) names `crate::study`"));
    assert!(found[2].starts_with("src/store/fit.rs:10: `store` (rank 2) names `crate::pipeline`"));
}

/// The stage modules of `src/pipeline/` (one per `StageId`).
const STAGES: [&str; 7] = ["motions", "sweep", "tnew", "fit", "ida", "floors", "report"];

/// Every name of one stage module in another file of `pipeline/` (`mod.rs`, which declares and
/// dispatches them, aside): a stage reads another stage's file through `files.rs` and shares
/// nothing else with it.
fn stage_to_stage(pipeline: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for file in rust_files(pipeline) {
        let rel = file.strip_prefix(pipeline).unwrap();
        let parts: Vec<String> = (rel.components())
            .map(|c| {
                c.as_os_str()
                    .to_string_lossy()
                    .trim_end_matches(".rs")
                    .to_string()
            })
            .collect();
        if parts == ["mod"] {
            continue;
        }
        let own = &parts[0];
        // `super::` from `pipeline/x.rs` and `pipeline/report/mod.rs`, `super::super::` from
        // `pipeline/report/x.rs`, is the pipeline.
        let depth = parts.len() - usize::from(parts.last().is_some_and(|p| p == "mod"));
        let up = "super::".repeat(depth);
        let text = std::fs::read_to_string(&file).unwrap();
        for (line, code) in product_lines(&text) {
            let named = [
                named_after(&code, &up),
                named_after(&code, "crate::pipeline::"),
            ];
            for n in named.iter().flatten() {
                if STAGES.contains(&n.as_str()) && n != own {
                    found.push(format!(
                        "src/pipeline/{}:{line}: names the stage module `{n}`",
                        rel.display()
                    ));
                }
            }
        }
    }
    found
}

/// No stage module (nor `files.rs`, `lock.rs`, …) names another stage's module: what a stage
/// or the report needs of another stage's results it reads through `files.rs`.
#[test]
fn no_stage_names_another_stage() {
    let found = stage_to_stage(&root().join("src/pipeline"));
    assert!(found.is_empty(), "{}", found.join("\n"));
    // The check itself on a made-up tree.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::create_dir(p.join("report")).unwrap();
    std::fs::write(p.join("mod.rs"), "pub mod sweep;\nuse sweep::x;\n").unwrap();
    std::fs::write(p.join("report/mod.rs"), "use super::{Study, fit};\n").unwrap();
    std::fs::write(
        p.join("tnew.rs"),
        "use super::{PipelineError, sweep::building_attr};\nuse super::tnew::x;\n",
    )
    .unwrap();
    std::fs::write(
        p.join("report/ida.rs"),
        "use super::Files;\nuse crate::pipeline::ida::figure;\nfn f() { super::super::floors::g() }\n",
    )
    .unwrap();
    let found = stage_to_stage(p);
    assert_eq!(found.len(), 4, "{found:#?}");
    assert!(found[0].starts_with("src/pipeline/report/ida.rs:2: names the stage module `ida`"));
    assert!(found[1].starts_with("src/pipeline/report/ida.rs:3: names the stage module `floors`"));
    assert!(found[2].starts_with("src/pipeline/report/mod.rs:1: names the stage module `fit`"));
    assert!(found[3].starts_with("src/pipeline/tnew.rs:1: names the stage module `sweep`"));
}

//! The guard of `src/methods.rs`: a stage's stored numbers change only with the version of a
//! method it computes with. `tests/golden/methods.yaml` holds, per config and stage, the
//! methods' versions and the SHA-256 of the numbers the stage file stores
//! (`scripts/stage-hashes.py`: every dataset and attribute but fingerprints and HDF5's
//! bookkeeping). The test runs the stages of `configs/quick.yaml`, `configs/mdof-quick.yaml`
//! and `configs/ida-quick.yaml` and fails when a hash differs:
//! - with the versions unchanged, naming the methods of that stage, one of which must be bumped
//!   (a stage's numbers changed while its fingerprint did not, so old files would be read as
//!   current);
//! - with a version changed, asking for the new hashes to be stored.
//!
//! `SLIDESTACK_BLESS=1 cargo test --release --test methods` stores the hashes and versions of
//! this build (after a version was bumped).

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Per config (its path in the repository), per stage file: `methods`, `variables`.
type Golden = BTreeMap<String, BTreeMap<String, Entry>>;

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
struct Entry {
    /// The methods' tags of the stage and the stages it reads, in order
    /// (`motions-1 spectrum-1 | integrator-1`).
    methods: String,
    /// SHA-256 of the stored numbers.
    variables: String,
}

const CONFIGS: [(&str, &[&str]); 3] = [
    ("configs/quick.yaml", &["motions", "sweep", "tnew", "fit"]),
    (
        "configs/mdof-quick.yaml",
        &["motions", "sweep", "tnew", "fit"],
    ),
    ("configs/ida-quick.yaml", &["motions", "ida"]),
];

fn repo(p: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(p)
}

fn golden_path() -> PathBuf {
    repo("tests/golden/methods.yaml")
}

/// The methods' tag each stage's file was written with (read back from its fingerprint).
fn methods_tag(file: &Path) -> String {
    let fp = slidestack::store::h5::stored_fingerprint(file)
        .unwrap()
        .expect("the stage wrote its file");
    slidestack::methods::methods_of(&fp)
        .expect("a fingerprint names its methods")
        .to_string()
}

fn hashes(files: &[PathBuf]) -> Vec<String> {
    let python = common::test_python();
    let o = Command::new(python)
        .arg(repo("scripts/stage-hashes.py"))
        .args(files)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout)
        .unwrap()
        .lines()
        .map(|l| l.split_once(' ').unwrap().1.to_string())
        .collect()
}

#[test]
fn stored_numbers_change_only_with_a_method_version() {
    let dir = tempfile::tempdir().unwrap();
    let mut now: Golden = BTreeMap::new();
    for (config, stages) in CONFIGS {
        let out = dir.path().join(config.replace('/', "_"));
        for stage in stages {
            let o = Command::new(env!("CARGO_BIN_EXE_slidestack"))
                .args([stage, repo(config).to_str().unwrap(), "--out"])
                .arg(&out)
                .env("RAYON_NUM_THREADS", "2")
                .output()
                .unwrap();
            assert!(
                o.status.success(),
                "{stage} {config}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
        let files: Vec<PathBuf> = stages.iter().map(|s| out.join(format!("{s}.h5"))).collect();
        // A stage's numbers depend on its methods and on those of the stages before it (each
        // config's stages are listed in order, each reading all the ones before).
        let mut chain = Vec::new();
        let entries = stages
            .iter()
            .zip(&files)
            .zip(hashes(&files))
            .map(|((stage, file), variables)| {
                chain.push(methods_tag(file));
                let methods = chain.join(" | ");
                (stage.to_string(), Entry { methods, variables })
            })
            .collect();
        now.insert(config.to_string(), entries);
    }
    if std::env::var_os("SLIDESTACK_BLESS").is_some() {
        let text = format!(
            "# What tests/methods.rs holds the stages to: per config and stage file, the method\n\
             # versions (src/methods.rs) and the SHA-256 of the numbers it stores\n\
             # (scripts/stage-hashes.py). Written by\n\
             #   SLIDESTACK_BLESS=1 cargo test --release --test methods\n{}",
            serde_yaml::to_string(&now).unwrap()
        );
        std::fs::write(golden_path(), text).unwrap();
        return;
    }
    let golden: Golden =
        serde_yaml::from_str(&std::fs::read_to_string(golden_path()).unwrap()).unwrap();
    let mut wrong = Vec::new();
    for (config, entries) in &now {
        for (stage, e) in entries {
            let Some(g) = golden.get(config).and_then(|s| s.get(stage)) else {
                wrong.push(format!(
                    "{config} {stage}: no golden entry; bless this build"
                ));
                continue;
            };
            if g.variables == e.variables && g.methods == e.methods {
                continue;
            }
            wrong.push(if g.methods == e.methods {
                format!(
                    "{config} {stage}.h5: the stored numbers changed but none of the methods \
                     they come from changed version ({}): bump the version of the method you \
                     changed in src/methods.rs, then bless",
                    e.methods
                )
            } else {
                format!(
                    "{config} {stage}.h5: methods {} (golden {}): bless this build",
                    e.methods, g.methods
                )
            });
        }
    }
    assert!(
        wrong.is_empty(),
        "{}\n(bless: SLIDESTACK_BLESS=1 cargo test --release --test methods)",
        wrong.join("\n")
    );
}

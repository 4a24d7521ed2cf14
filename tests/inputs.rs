//! Input the tool used to misread or answer wrongly, each refused before any work with a
//! message naming the file and the key or line (exit code 2), and record names that used to
//! break the CSV files. `docs/faults.md` lists each with its test.

mod common;

use common::fixture;
use std::path::Path;
use std::process::Command;

/// What a run of the binary did.
struct Ran {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

fn run_in(dir: &Path, args: &[&str]) -> Ran {
    let o = Command::new(env!("CARGO_BIN_EXE_slidestack"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    Ran {
        code: o.status.code(),
        stdout: String::from_utf8_lossy(&o.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&o.stderr).into_owned(),
    }
}

/// `args` in `dir` fail with exit code 2 and print exactly `error: {want}`.
fn refused(dir: &Path, args: &[&str], want: &str) {
    let r = run_in(dir, args);
    assert_eq!(r.code, Some(2), "{args:?}: {}{}", r.stdout, r.stderr);
    assert_eq!(r.stderr.trim_end(), format!("error: {want}"), "{args:?}");
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn a_negative_number_or_list_reaches_the_check_that_names_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // `design` checks the question before it opens the study.
    fn design<'a>(alpha: &'a str, mu: &'a str) -> Vec<&'a str> {
        vec![
            "design", "--study", "none", "--zone", "III", "--period", "0.7", "--alpha", alpha,
            "--mu", mu,
        ]
    }
    refused(
        d,
        &design("1,1", "-0.1,0.05"),
        "mu_1 = -0.1 must be finite and > 0",
    );
    refused(
        d,
        &design("0.5,-1", "0.1,0.05"),
        "alpha_2 = -1 must be finite and > 0",
    );
    let mut split = design("1,1", "0.1");
    split.push("-0.05");
    refused(d, &split, "mu_2 = -0.05 must be finite and > 0");
    let mut period = design("1,1", "0.1,0.05");
    period[6] = "-1e-3";
    refused(d, &period, "--period = -0.001 must be finite and > 0");
    let rec = fixture("RSN960_NORTHR_LOS270.AT2");
    for (args, want) in [
        (
            vec!["simulate", "--mu", "-0.1,0.05"],
            "invalid case: mu_1 (kinetic friction of interface 1) must be finite, >= 0 and <= \
             1000, got -0.1",
        ),
        (
            vec!["simulate", "--alpha", "-.5", "0.5"],
            "invalid case: alpha_1 (mass ratio of block 1) must be finite, > 0 and ≤ 10000, got \
             -0.5",
        ),
        (
            vec!["simulate", "--period", "-inf"],
            "invalid case: period_s must be within 0.000001 … 10000 s, got -inf",
        ),
        (
            vec!["spectrum", "--record", s(&rec), "--damping", "0.05,-0.1"],
            "--damping -0.1 must be in [0, 1)",
        ),
        (
            vec!["spectrum", "--record", s(&rec), "--ductility", "-2,2"],
            "RSN960_NORTHR_LOS270.AT2: target ductility must be within 1 … 100, got -2.0",
        ),
    ] {
        refused(d, &args, want);
    }
}

#[test]
fn design_refuses_a_period_no_structure_has_before_reading_the_study() {
    let dir = tempfile::tempdir().unwrap();
    for (period, shown) in [("1e-300", "1e-300"), ("1e9", "1000000000.0")] {
        refused(
            dir.path(),
            &[
                "design",
                "--study",
                "none",
                "--zone",
                "V",
                "--period",
                period,
                "--alpha",
                "1,1",
                "--mu",
                "0.3,0.1",
                "--extrapolate",
            ],
            &format!(
                "--period = {shown} must be within 0.000001 … 10000 s, the periods of a \
                 structure `simulate` runs"
            ),
        );
    }
}

#[test]
fn a_case_file_is_refused_in_its_own_keys_with_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let one_storey_keys = "`record`, `period`, `alpha`, `mu`, `mu_static`, `damping`, \
                           `damping_basis`, `scale`, `integrator`, `rk4_substeps`, `structure`, \
                           `yield_strength_ratio`, `post_yield_ratio`, `aspect`, `history`, `building`, \
                           `stacks`, `floor_spectra`";
    let building = "building:\n  storeys: 2\n  period: 0.5\n";
    let stack = "stacks:\n  - floor: 1\n    alpha: [1]\n    mu: [0.2]\n";
    for (text, want) in [
        (
            format!("{building}{}", stack.replace("    alpha: [1]\n", "")),
            "line 5: `stacks[0]`: missing key `alpha`".to_string(),
        ),
        (
            "building:\n  storeys: 2\n".into(),
            "line 2: `building`: missing key `period`".into(),
        ),
        (
            "period: 1.0\nmu: [0.1]\ndamping: 0.05\n\n# again\ndamping: 0.02\n".into(),
            "line 6: `damping` is given twice".into(),
        ),
        (
            "period: 1.0\nmu: [0.1]\nstiffness: 3\n".into(),
            format!("line 3: unknown key `stiffness`; the keys are {one_storey_keys}"),
        ),
        (
            format!("{building}  stiffness: 3\n"),
            "line 4: `building`: unknown key `stiffness`; the keys of `building` are `storeys`, \
             `period`, `floor_masses`, `storey_stiffnesses`, `structure`, \
             `yield_strength_ratios`, `post_yield_ratio`, `storey_heights_m`"
                .into(),
        ),
        (
            format!("{building}  period: 0.6\n{stack}"),
            "line 4: `building`: `period` is given twice".into(),
        ),
        (
            "building:\n  storeys: -3\n  period: 0.5\n".into(),
            "line 2: `building.storeys`: expected a whole number of storeys ≥ 1, got -3".into(),
        ),
        (
            format!("{building}{}", stack.replace("floor: 1", "floor: 1.5")),
            "line 5: `stacks[0].floor`: expected a floor number (1 the lowest) or `roof`, got 1.5"
                .into(),
        ),
        (
            format!("{building}{}", stack.replace("floor: 1", "floor: [1]")),
            "line 5: `stacks[0].floor`: expected a floor number (1 the lowest) or `roof`, got a \
             list"
                .into(),
        ),
        (
            format!("{building}  storey_heights_m: [3, tall]\n{stack}"),
            "line 4: `building.storey_heights_m`: expected a storey height in m or a list of \
             them, storey 1 first, got `tall`"
                .into(),
        ),
        (
            format!("{building}stacks:\n  - alpha: [1]\n    mu: [0.2]\n"),
            "line 5: `stacks[0]`: missing key `floor`".into(),
        ),
    ] {
        let case = d.join("case.yaml");
        std::fs::write(&case, &text).unwrap();
        // The record is not read: the case file is refused first.
        refused(
            d,
            &[
                "simulate",
                "--config",
                "case.yaml",
                "--record",
                "/nonexistent.AT2",
            ],
            &format!("case.yaml: {want}"),
        );
    }
}

#[test]
fn a_study_config_is_refused_in_plain_words_with_the_key_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let head = "output_dir: out\nzones: [{ name: III, target: \"is1893:zone=III,soil=I\" }]\n\
                motions:\n  seeds:\n    stochastic: { count: 2, seed: 1 }\n";
    let grid = "grid:\n  period_s: [0.5]\n  alpha: [[1]]\n  mu: [[0.2]]\n";
    for (text, want) in [
        (
            format!("{head}building:\n  storeys: [-3]\n{grid}"),
            "line 7: `building.storeys`: expected a whole number of storeys ≥ 1 or a list of \
             them, got -3",
        ),
        (
            format!("{head}building:\n  storeys: [3, 4.5]\n{grid}"),
            "line 7: `building.storeys`: expected a whole number of storeys ≥ 1 or a list of \
             them, got 4.5",
        ),
        (
            format!("{head}building:\n  storeys: 3\n{grid}  stack_floor: [1, 1.5]\n"),
            "line 12: `grid.stack_floor`: expected a floor number, `roof`, `mid` or `all`, or a list \
             of them, got 1.5",
        ),
        (
            format!("{head}{}", grid.replace("[0.5]", "fast")),
            "line 7: `grid.period_s`: expected a list of numbers or a range { from, to, step }, \
             got `fast`",
        ),
        (
            format!("{head}{}", grid.replace("[[1]]", "[[1, x]]")),
            "line 8: `grid.alpha[0]`: expected a number in the list, got `x`",
        ),
    ] {
        std::fs::write(d.join("study.yaml"), &text).unwrap();
        refused(
            d,
            &["motions", "study.yaml"],
            &format!("study.yaml: {want}"),
        );
        assert!(!d.join("out").exists(), "{want}");
    }
}

#[test]
fn an_empty_record_file_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (name, text) in [
        ("empty.AT2", ""),
        ("blank.AT2", " \n\t\n"),
        ("empty.txt", ""),
        ("blank.txt", "\n\n  \n"),
    ] {
        std::fs::write(d.join(name), text).unwrap();
        refused(
            d,
            &["simulate", "--record", name],
            &format!("{name}: empty file"),
        );
    }
}

#[test]
fn an_output_path_that_cannot_be_written_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a-file"), "").unwrap();
    std::fs::write(d.join("study.yaml"), "not: a study\n").unwrap();
    // Each names a record or config that cannot be read: the output path is refused first.
    let missing = "/nonexistent.AT2";
    for (args, want) in [
        (
            vec!["simulate", "--record", missing, "--figure", "out/f.png"],
            "out/f.png: a figure (SVG) must end in .svg",
        ),
        (
            vec!["simulate", "--record", missing, "--figure", "out/f.svg"],
            "out/f.svg: directory out does not exist",
        ),
        (
            vec![
                "simulate",
                "--record",
                missing,
                "--history",
                "/nonexistent/dir/h.h5",
            ],
            "/nonexistent/dir/h.h5: directory /nonexistent/dir does not exist",
        ),
        (
            vec!["simulate", "--record", missing, "--history", "a-file/h.csv"],
            "a-file/h.csv: a-file is not a directory",
        ),
        (
            vec![
                "spectrum",
                "--record",
                missing,
                "--csv",
                "--out",
                "/nonexistent/dir/s.csv",
            ],
            "/nonexistent/dir/s.csv: directory /nonexistent/dir does not exist",
        ),
        (
            vec!["spectrum", "--record", missing, "--out", "."],
            ".: is a directory, not a file",
        ),
        (
            vec!["ida", "study.yaml", "--figure", "ida.png"],
            "ida.png: a figure (SVG) must end in .svg",
        ),
        (
            vec!["ida", "study.yaml", "--figure", "no/ida.svg"],
            "no/ida.svg: directory no does not exist",
        ),
    ] {
        refused(d, &args, want);
    }
    let left: Vec<_> = std::fs::read_dir(d).unwrap().collect();
    assert_eq!(left.len(), 2, "nothing written: {left:?}");
}

/// The records of a CSV text, read by the `csv` crate.
fn csv_records(text: &str) -> Vec<csv::StringRecord> {
    csv::Reader::from_reader(text.as_bytes())
        .records()
        .collect::<Result<_, _>>()
        .unwrap()
}

/// The first column of each row of the CSV file `path` as Python's `csv` module reads it.
fn python_first_column(path: &Path) -> Vec<String> {
    let python = common::test_python();
    let o = Command::new(python)
        .args([
            "-c",
            "import csv, json, sys\n\
             rows = list(csv.reader(open(sys.argv[1], newline='')))\n\
             print(json.dumps([r[0] for r in rows[1:]]))",
        ])
        .arg(path)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn a_record_named_with_a_comma_and_quotes_round_trips_through_every_csv() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let name = "a,\"b\".AT2";
    std::fs::copy(fixture("RSN960_NORTHR_LOS270.AT2"), d.join(name)).unwrap();
    let spectrum = ["spectrum", "--record", name, "--periods", "0.5,1", "--csv"];
    let stdout = run_in(d, &spectrum);
    assert_eq!(stdout.code, Some(0), "{}", stdout.stderr);
    let mut to_file = spectrum.to_vec();
    to_file.extend(["--out", "spectrum.csv"]);
    assert_eq!(run_in(d, &to_file).code, Some(0));
    let file = std::fs::read_to_string(d.join("spectrum.csv")).unwrap();
    assert_eq!(file, stdout.stdout);
    let rows = csv_records(&file);
    assert_eq!(rows.len(), 2);
    for (row, period) in rows.iter().zip(["0.5", "1"]) {
        assert_eq!((&row[0], &row[2]), (name, period));
        assert_eq!(row.len(), 7);
    }
    let mut ductility = spectrum.to_vec();
    ductility.extend(["--ductility", "2"]);
    let r = run_in(d, &ductility);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let rows = csv_records(&r.stdout);
    assert!(rows.iter().all(|row| &row[0] == name && row.len() == 11));

    let r = run_in(
        d,
        &[
            "match",
            "--record",
            name,
            "--target",
            "is1893:zone=V,soil=I",
            "--out",
            "matched",
        ],
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let summary = d.join("matched/summary.csv");
    let rows = csv_records(&std::fs::read_to_string(&summary).unwrap());
    assert_eq!(rows.len(), 1);
    assert_eq!((&rows[0][0], &rows[0][10]), (name, name));
    assert!(d.join("matched").join(name).is_file());

    for path in [d.join("spectrum.csv"), summary] {
        let names = python_first_column(&path);
        assert!(
            !names.is_empty() && names.iter().all(|n| n == name),
            "{}: {names:?}",
            path.display()
        );
    }
}

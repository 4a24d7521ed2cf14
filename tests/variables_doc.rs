//! `docs/variables.md` is the table `slidestack::store::variables_doc()` makes from the stored
//! variables' declarations: a variable renamed, added or relabelled in `src/store/` shows here
//! until the docs are regenerated (`SLIDESTACK_BLESS=1 cargo test --release --test
//! variables_doc`).

use std::path::PathBuf;

#[test]
fn the_variable_table_is_the_declarations() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("docs/variables.md");
    let made = slidestack::store::variables_doc();
    if std::env::var_os("SLIDESTACK_BLESS").is_some() {
        std::fs::write(&path, &made).unwrap();
    }
    let stored = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        stored == made,
        "{} is not the declarations' table: rerun with SLIDESTACK_BLESS=1",
        path.display()
    );
    for name in [
        "u_stack",
        "slip_peak",
        "floor_accel_stack",
        "T_new",
        "lambda_storey_flag",
    ] {
        assert!(
            made.contains(&format!("| `{name}` |")),
            "{name} is declared and missing from the table"
        );
    }
}

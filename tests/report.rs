//! The report of `configs/quick.yaml` (the README's first command) as a reader gets it: every
//! SVG rendered by a real renderer and not blank where its data should be, legends beside the
//! plots, the page referencing only files of the report directory, the numbers of Tables 2 and 3
//! and of the band counts those of the files (and of the paper), and the same bytes on a rerun.
//!
//! The renderer is resvg: a pure-Rust SVG renderer (no system library, no browser), the one with
//! the most complete SVG conformance suite, rendering into a pixel buffer the test can read.
//! Set `SLIDESTACK_REPORT_PNG=DIR` to keep every figure as a PNG in `DIR` for looking at.

mod common;

use common::{ok, slidestack};

use resvg::{tiny_skia, usvg};
use slidestack::dynamics::{ExactOptions, Ground, System, simulate_exact};
use slidestack::pipeline::Study;
use slidestack::render::chart::areas;
use slidestack::store::fit::read_fit;
use slidestack::store::motions::read_zone_motions;
use slidestack::store::tnew::read_zone_tnew;
use slidestack::study::cases::{PAPER_TABLE_2, PAPER_TABLE_3, TABLE_2};
use slidestack::study::physics::SystemKind;
use slidestack::study::tnew::{BAND_FLAGS, BandCounts};
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

/// The `<td>` texts of each row of the table with `id`.
fn table(doc: &roxmltree::Document, id: &str) -> Vec<Vec<String>> {
    let t = doc
        .descendants()
        .find(|n| n.has_tag_name("table") && n.attribute("id") == Some(id))
        .unwrap_or_else(|| panic!("no table `{id}`"));
    t.children()
        .filter(|n| n.has_tag_name("tr"))
        .map(|tr| {
            tr.children()
                .filter(|n| n.has_tag_name("td"))
                .map(|td| {
                    td.descendants()
                        .filter(|d| d.is_text())
                        .filter_map(|d| d.text())
                        .collect()
                })
                .collect::<Vec<String>>()
        })
        .filter(|r| !r.is_empty())
        .collect()
}

fn header(doc: &roxmltree::Document, id: &str) -> Vec<String> {
    let t = doc
        .descendants()
        .find(|n| n.has_tag_name("table") && n.attribute("id") == Some(id))
        .unwrap();
    t.descendants()
        .filter(|n| n.has_tag_name("th"))
        .map(|th| th.text().unwrap_or_default().to_string())
        .collect()
}

fn close(shown: &str, want: f64, tol: f64, what: &str) {
    let v: f64 = shown
        .parse()
        .unwrap_or_else(|_| panic!("{what}: `{shown}` is not a number"));
    assert!(
        (v - want).abs() <= tol,
        "{what}: shown {shown}, file {want}"
    );
}

/// Renders `svg` and checks that every plot area has drawn pixels and no legend overlaps one.
fn check_figure(name: &str, svg: &str, opt: &usvg::Options, png_dir: Option<&Path>) {
    let tree = usvg::Tree::from_str(svg, opt).unwrap_or_else(|e| panic!("{name}: {e}"));
    let size = tree.size().to_int_size();
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height()).unwrap();
    pixmap.fill(tiny_skia::Color::WHITE);
    resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
    if let Some(dir) = png_dir {
        pixmap
            .save_png(dir.join(name).with_extension("png"))
            .unwrap();
    }
    let list = areas(svg);
    let plots: Vec<[i32; 4]> = list
        .iter()
        .filter(|(k, _)| k == "plot")
        .map(|a| a.1)
        .collect();
    assert!(!plots.is_empty(), "{name}: no plot area listed");
    let w = size.width() as i32;
    for p in &plots {
        // Inside the axes (3 px in), pixels darker than the light grid lines (235) are data.
        let mut drawn = 0;
        for y in p[1] + 3..p[3] - 3 {
            for x in p[0] + 3..p[2] - 3 {
                let px = pixmap.pixels()[(y * w + x) as usize].demultiply();
                if px.red().min(px.green()).min(px.blue()) < 225 {
                    drawn += 1;
                }
            }
        }
        assert!(
            drawn >= 30,
            "{name}: plot area {p:?} is blank ({drawn} pixels)"
        );
    }
    for (_, l) in list.iter().filter(|(k, _)| k == "legend") {
        for p in &plots {
            let apart = l[0] >= p[2] || l[2] <= p[0] || l[1] >= p[3] || l[3] <= p[1];
            assert!(apart, "{name}: legend {l:?} overlaps plot area {p:?}");
        }
    }
}

/// `index.html`'s text parsed (its doctype allowed); panics unless well-formed.
fn html_document(html: &str) -> roxmltree::Document<'_> {
    roxmltree::Document::parse_with_options(
        html,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .expect("index.html is well-formed")
}

/// `report/index.html` as every report must be: well-formed, referencing only files of the
/// report directory that its manifest lists, showing every figure of the directory, each one
/// rendered with data in every plot area and its legend beside them. Returns the page's text,
/// the files it references and its figures.
fn checked_page(report: &Path) -> (String, Vec<String>, Vec<String>) {
    let html = std::fs::read_to_string(report.join("index.html")).unwrap();
    let doc = html_document(&html);

    // The page references only files of the report directory (and its own anchors), every one
    // listed in the manifest; every figure in the directory is shown.
    let manifest = std::fs::read_to_string(report.join("MANIFEST.sha256")).unwrap();
    let listed: Vec<&str> = manifest
        .lines()
        .filter_map(|l| l.split_once("  ").map(|p| p.1))
        .collect();
    let ids: Vec<&str> = doc
        .descendants()
        .filter_map(|n| n.attribute("id"))
        .collect();
    let mut shown = Vec::new();
    for n in doc.descendants() {
        for attr in ["src", "href"] {
            let Some(v) = n.attribute(attr) else { continue };
            if let Some(anchor) = v.strip_prefix('#') {
                assert!(ids.contains(&anchor), "no element with id `{anchor}`");
                continue;
            }
            // A query is the design page's question, not part of the file.
            let v = v.split_once('?').map_or(v, |(file, _)| file);
            assert!(
                !v.contains(':') && !v.contains('/') && !v.contains('\\'),
                "`{v}` is not a file of the report directory"
            );
            assert!(report.join(v).is_file(), "`{v}` does not exist");
            assert!(listed.contains(&v), "`{v}` is not in the manifest");
            shown.push(v.to_string());
        }
    }
    let mut svgs: Vec<String> = std::fs::read_dir(report)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".svg"))
        .collect();
    svgs.sort();
    for s in &svgs {
        assert!(shown.contains(s), "{s} is not shown on the page");
    }
    // Every figure rendered, with data in each plot area and its legend beside them.
    let png_dir = std::env::var_os("SLIDESTACK_REPORT_PNG").map(std::path::PathBuf::from);
    if let Some(d) = &png_dir {
        std::fs::create_dir_all(d).unwrap();
    }
    let mut opt = usvg::Options::default();
    // Text only where the machine has fonts: the checks do not depend on it. The figures ask for
    // the generic `sans-serif`, which fontdb maps to Arial unless told otherwise.
    let db = opt.fontdb_mut();
    db.load_system_fonts();
    let family = db
        .faces()
        .flat_map(|f| f.families.iter().map(|(name, _)| name.clone()))
        .find(|name| name == "DejaVu Sans")
        .or_else(|| {
            db.faces()
                .next()
                .and_then(|f| f.families.first().map(|n| n.0.clone()))
        });
    if let Some(f) = family {
        db.set_sans_serif_family(f);
    }
    for s in &svgs {
        let text = std::fs::read_to_string(report.join(s)).unwrap();
        check_figure(s, &text, &opt, png_dir.as_deref());
    }
    (html, shown, svgs)
}

#[test]
fn quick_report_renders_references_its_files_and_shows_the_files_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/quick.yaml");
    let out = dir.path().join("quick");
    let (c, o) = (cfg.to_str().unwrap(), out.to_str().unwrap());
    ok(slidestack(&["run", c, "--out", o], "2"));
    let report = out.join("report");
    let (html, shown, svgs) = checked_page(&report);
    let doc = html_document(&html);
    assert!(
        shown.iter().any(|s| s == "design.html"),
        "no link to the design page"
    );
    for want in [
        "spectra_III.svg",
        "history_V.svg",
        "tnew_construction_III.svg",
        "energy.svg",
        "drr_V.svg",
        "tnew_III.svg",
        "residuals_V.svg",
    ] {
        assert!(svgs.iter().any(|s| s == want), "{want} missing: {svgs:?}");
    }

    // Table 3: the paper's rows are the paper's, ours are fit.yaml's.
    let fit = read_fit(&out.join("fit.yaml")).unwrap().unwrap();
    let rows = table(&doc, "table3");
    let mut seen = 0;
    for z in &fit.zones {
        let zrows: Vec<&Vec<String>> = rows.iter().filter(|r| r[0] == z.zone).collect();
        if let Some((_, p)) = PAPER_TABLE_3.iter().find(|p| p.0 == z.zone) {
            let r = zrows.iter().find(|r| r[1] == "paper Table 3").unwrap();
            for (k, v) in p.iter().enumerate() {
                close(&r[2 + k], *v, 5e-4, "paper Table 3");
            }
        }
        for ff in &z.forms {
            let name = format!("{} form", ff.form.name());
            let r = zrows
                .iter()
                .find(|r| r[1].starts_with(&name))
                .unwrap_or_else(|| panic!("zone {}: no row for the {name}", z.zone));
            let (m, cv) = (&ff.all_cases, &ff.cross_validated);
            for (k, v) in [m.r2, m.r, m.rmse, m.mse, m.mae, cv.r2, cv.rmse]
                .iter()
                .enumerate()
            {
                close(&r[2 + k], *v, 5e-4, &format!("zone {} {name}", z.zone));
            }
            assert_eq!(r[1].ends_with("recommended"), ff.form == z.recommended);
            seen += 1;
        }
        if let Some(m) = &z.published {
            let r = zrows
                .iter()
                .find(|r| r[1].starts_with("paper's equation"))
                .unwrap();
            for (k, v) in [m.r2, m.r, m.rmse, m.mse, m.mae].iter().enumerate() {
                close(&r[2 + k], *v, 5e-4, "published equation");
            }
        }
    }
    assert!(seen >= 2);

    // Table 2: the paper's columns are the paper's; ours are the means over the motions of
    // motions.h5, simulated here again with the study's physics.
    let study = Study::load(&cfg, Some(out.clone())).unwrap();
    let physics = study.physics();
    let case = TABLE_2.case(2);
    let rows = table(&doc, "table2");
    for zc in &study.cfg.zones {
        let r = rows.iter().find(|r| r[0] == zc.name).unwrap();
        let motions = read_zone_motions(&out.join("motions.h5"), &zc.name).unwrap();
        let peak = |spec: slidestack::dynamics::SystemSpec| -> f64 {
            let sys = System::new(&spec).unwrap();
            motions
                .iter()
                .map(|m| {
                    let a = m.accel_mps2(1.0);
                    let g = Ground {
                        dt_s: m.dt_s,
                        accel_mps2: &a,
                    };
                    simulate_exact(&sys, &g, &ExactOptions::default())
                        .unwrap()
                        .peak_displacement_m
                })
                .sum::<f64>()
                / motions.len() as f64
        };
        let single = peak(physics.spec(SystemKind::SingleBlock, &case));
        let stack = peak(physics.spec(SystemKind::Stack, &case));
        close(&r[1], single, 5e-5, "Table 2 single block");
        close(&r[2], stack, 5e-5, "Table 2 stack");
        close(
            &r[3],
            100.0 * (1.0 - stack / single),
            0.05,
            "Table 2 reduction",
        );
        let p = PAPER_TABLE_2.iter().find(|p| p.0 == zc.name).unwrap();
        close(&r[5], p.1, 5e-4, "paper Table 2 single block");
        close(&r[6], p.2, 5e-4, "paper Table 2 stack");
    }

    // The band counts are tnew.h5's.
    let head = header(&doc, "bands");
    let rows = table(&doc, "bands");
    for zc in &study.cfg.zones {
        let (_, t) = read_zone_tnew(&out.join("tnew.h5"), &zc.name, 2).unwrap();
        let band: Vec<u8> = t.vars.band.iter().copied().collect();
        let tn: Vec<f64> = t.vars.t_new.iter().copied().collect();
        let tr: Vec<f64> = t.vars.t_rigid.iter().copied().collect();
        let counts = BandCounts::new(&band, &tn, &tr);
        let r = rows.iter().find(|r| r[0] == zc.name).unwrap();
        let col = |name: &str| head.iter().position(|h| h == name).unwrap();
        for &(code, word) in BAND_FLAGS {
            assert_eq!(
                r[col(word)],
                counts.counts[code as usize].to_string(),
                "{word}"
            );
        }
        assert_eq!(r[col("sliding cases")], counts.sliding().to_string());
        assert_eq!(
            r[col("T_new > 1.005·T_rigid (sliding)")],
            counts.above_1_005.to_string()
        );
    }

    // The same bytes when the report is made again.
    let before: BTreeMap<String, Vec<u8>> = std::fs::read_dir(&report)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    ok(slidestack(&["report", c, "--out", o, "--force"], "2"));
    for (name, bytes) in &before {
        assert!(
            std::fs::read(report.join(name)).unwrap() == *bytes,
            "{name} differs on a rerun"
        );
    }
}

/// The median of the finite values of `v` (the mean of the middle two of an even count).
/// The `p`-th percentile of the finite values of `v`, linearly between order statistics (as
/// NumPy's `nanpercentile`).
fn pct(v: &[f64], p: f64) -> f64 {
    let mut x: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    x.sort_by(f64::total_cmp);
    let pos = p / 100.0 * (x.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = (lo + 1).min(x.len() - 1);
    x[lo] + (pos - lo as f64) * (x[hi] - x[lo])
}

fn median(v: impl Iterator<Item = f64>) -> f64 {
    let mut x: Vec<f64> = v.filter(|x| x.is_finite()).collect();
    x.sort_by(f64::total_cmp);
    let n = x.len();
    if n % 2 == 1 {
        x[n / 2]
    } else {
        (x[n / 2 - 1] + x[n / 2]) / 2.0
    }
}

/// A building study's report (`configs/mdof-quick.yaml` with `configs/mdof-ida-quick.yaml`'s
/// `ida:` section, through `run`): every page check of the one-storey report; the building
/// section's figures and none of the one-storey paper cases'; the answer table's medians
/// recomputed here from `sweep.h5` and `tnew.h5` read through their own axes (the report walks
/// flat strides); the fit's per-frame table that of `fit.yaml`; the IDA's fragilities those of
/// `ida.h5`, each building once; the same bytes from a forced rebuild.
/// Tolerance: half a unit of the printed last digit (3 decimals: 5e-4; λ's 2: 5e-3; shares in
/// whole percent: 0.5).
#[test]
fn a_building_studys_report_shows_the_files_numbers() {
    use ndarray::{ArrayD, Axis, IxDyn};
    use slidestack::store::ida::read_zone_ida;
    use slidestack::store::sweep::read_zone_sweep;
    use slidestack::store::tnew::read_zone_tnew_in;

    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let grid = std::fs::read_to_string(root.join("configs/mdof-quick.yaml")).unwrap();
    let ida = std::fs::read_to_string(root.join("configs/mdof-ida-quick.yaml")).unwrap();
    let cfg = dir.path().join("mdof-quick-ida.yaml");
    std::fs::write(&cfg, grid + &ida[ida.find("\nida:").unwrap()..]).unwrap();
    let out = dir.path().join("mdof-quick");
    let (c, o) = (cfg.to_str().unwrap(), out.to_str().unwrap());
    ok(slidestack(&["run", c, "--out", o], "2"));
    let report = out.join("report");
    let (html, _, svgs) = checked_page(&report);
    assert!(svgs.iter().any(|s| s == "ida.svg"), "{svgs:?}");
    let doc = html_document(&html);
    for zone in ["III", "V"] {
        for want in [
            "building_period",
            "building_profiles",
            "residuals",
            "spectra",
        ] {
            let want = format!("{want}_{zone}.svg");
            assert!(svgs.contains(&want), "{want} missing: {svgs:?}");
        }
    }
    for one_storey in ["history_", "drr_", "tnew_", "energy"] {
        assert!(
            !svgs.iter().any(|s| s.starts_with(one_storey)),
            "a one-storey figure in a building report: {svgs:?}"
        );
    }

    let rows = table(&doc, "building-answer");
    let close_to = |shown: &str, want: f64, tol: f64, what: &str| {
        let first = shown.split_whitespace().next().unwrap();
        close(first, want, tol, what);
    };
    let mut checked = 0;
    for zone in ["III", "V"] {
        let (_, axes, sw) = read_zone_sweep(&out.join("sweep.h5"), zone, 2, true).unwrap();
        let (grid, _, t) = read_zone_tnew_in(&out.join("tnew.h5"), zone, 2, true).unwrap();
        let axes = axes.unwrap();
        let b = sw.building.as_ref().unwrap();
        let l = t.lambda.as_ref().unwrap();
        for (si, &n) in axes.storeys.iter().enumerate() {
            for (fi, floor) in axes.stack_floor.iter().enumerate() {
                // One storey: every stack floor is the same building, shown once.
                if n == 1 && fi > 0 {
                    continue;
                }
                let label = match (n, floor.to_string().as_str()) {
                    (1, _) => "1 storey".to_string(),
                    (_, "all") => format!("{n} storeys, every floor"),
                    (_, "roof") => format!("{n} storeys, roof"),
                    (_, j) => format!("{n} storeys, floor {j}"),
                };
                let row = rows
                    .iter()
                    .find(|r| r[0] == zone && r[1] == label)
                    .unwrap_or_else(|| panic!("no row {zone}, {label}: {rows:?}"));
                // [motion, storeys, stack_floor, T_p, cases…(, level)] → this frame.
                let frame =
                    |a: &ArrayD<f64>| a.index_axis(Axis(1), si).index_axis(Axis(1), fi).to_owned();
                let over_motions = |a: ArrayD<f64>| a.mean_axis(Axis(0)).unwrap();
                // The largest storey or floor of the building (NaN above its roof).
                let peak = |a: &ArrayD<f64>| {
                    let f = frame(a);
                    let last = Axis(f.ndim() - 1);
                    f.slice_axis(last, (0..n).into())
                        .fold_axis(last, f64::NEG_INFINITY, |m, &x| m.max(x))
                };
                let ratios = |s: ArrayD<f64>, r: ArrayD<f64>| {
                    (&s / &r).iter().copied().collect::<Vec<f64>>()
                };
                let roof = ratios(
                    over_motions(frame(&sw.vars.u_stack)),
                    over_motions(frame(&sw.vars.u_rigid)),
                );
                let drift = ratios(
                    over_motions(peak(&b.drift_ratio_stack)),
                    over_motions(peak(&b.drift_ratio_rigid)),
                );
                let accel = ratios(
                    over_motions(peak(&b.floor_accel_stack)),
                    over_motions(peak(&b.floor_accel_rigid)),
                );
                let in_frame =
                    |a: &ArrayD<f64>| a.index_axis(Axis(0), si).index_axis(Axis(0), fi).to_owned();
                let shear = ratios(
                    in_frame(&l.base_shear_stack_mean),
                    in_frame(&l.base_shear_rigid_mean),
                );
                let lambda: Vec<f64> = in_frame(&l.lambda).iter().copied().collect();
                let t_new = in_frame(&t.vars.t_new);
                let t_ratio: Vec<f64> = t_new
                    .indexed_iter()
                    .map(|(ix, v): (IxDyn, &f64)| v / grid.periods_s[ix[0]])
                    .collect();
                let share = |v: &[f64]| {
                    100.0 * v.iter().filter(|&&x| x < 1.0).count() as f64 / v.len() as f64
                };
                let what = |c: &str| format!("zone {zone}, {label}: {c}");
                assert_eq!(row[2], roof.len().to_string());
                close_to(&row[3], median(roof.iter().copied()), 5e-4, &what("roof"));
                close_to(&row[4], median(drift.iter().copied()), 5e-4, &what("drift"));
                close_to(
                    &row[5],
                    median(accel.iter().copied()),
                    5e-4,
                    &what("acceleration"),
                );
                close_to(
                    &row[6],
                    median(shear.iter().copied()),
                    5e-4,
                    &what("base shear"),
                );
                close_to(&row[7], median(lambda.iter().copied()), 5e-3, &what("λ"));
                close_to(
                    &row[8],
                    median(t_ratio.iter().copied()),
                    5e-4,
                    &what("T_new/T_1"),
                );
                for (cell, v) in [(&row[4], &drift), (&row[5], &accel)] {
                    let pct: &str = cell.split('(').nth(1).unwrap().split(' ').next().unwrap();
                    close(pct, share(v), 0.5 + 1e-9, &what("share below 1"));
                }
                // The 10–90 % band of the ratios motion by motion, pooled over cases and motions.
                let each = |s: ArrayD<f64>, r: ArrayD<f64>| {
                    (&s / &r).iter().copied().collect::<Vec<f64>>()
                };
                let bands = [
                    (
                        &row[3],
                        each(frame(&sw.vars.u_stack), frame(&sw.vars.u_rigid)),
                    ),
                    (
                        &row[4],
                        each(peak(&b.drift_ratio_stack), peak(&b.drift_ratio_rigid)),
                    ),
                    (
                        &row[5],
                        each(peak(&b.floor_accel_stack), peak(&b.floor_accel_rigid)),
                    ),
                ];
                for (cell, v) in bands {
                    let inner = cell.split('[').nth(1).unwrap().trim_end_matches(']');
                    let (lo, hi) = inner.split_once(", ").unwrap();
                    close(lo, pct(&v, 10.0), 5e-3, &what("10th percentile"));
                    close(hi, pct(&v, 90.0), 5e-3, &what("90th percentile"));
                }
                let bare: Vec<f64> = in_frame(&l.base_shear_ratio_bare).iter().copied().collect();
                close_to(
                    &row[9],
                    median(bare.iter().copied()),
                    5e-4,
                    &what("vs bare"),
                );
                let code: Vec<f64> = in_frame(&l.lambda_code).iter().copied().collect();
                close_to(
                    &row[10],
                    median(code.iter().copied()),
                    5e-3,
                    &what("λ_code"),
                );
                // The floor holding the largest floor acceleration most often.
                let acc = frame(&b.floor_accel_stack);
                let mut count = vec![0usize; n];
                for lane in acc.lanes(Axis(acc.ndim() - 1)) {
                    let top = (0..n).fold(0, |a, j| if lane[j] > lane[a] { j } else { a });
                    count[top] += 1;
                }
                let (top, most) = (count.iter().enumerate())
                    .fold((0, 0), |b, (j, &k)| if k > b.1 { (j, k) } else { b });
                let name = if top + 1 == n {
                    "roof".to_string()
                } else {
                    format!("floor {}", top + 1)
                };
                assert!(row[11].starts_with(&format!("{name} (")), "{}", row[11]);
                let shown = row[11]
                    .split('(')
                    .nth(1)
                    .unwrap()
                    .split(' ')
                    .next()
                    .unwrap();
                let all: usize = count.iter().sum();
                close(
                    shown,
                    100.0 * most as f64 / all as f64,
                    0.5 + 1e-9,
                    &what("floor"),
                );
                // Interface 1's peak slip: the median over the cases of the mean over motions.
                let slip = frame(&sw.vars.slip_peak);
                let first = slip.index_axis(Axis(slip.ndim() - 1), 0).to_owned();
                let slip: Vec<f64> = over_motions(first).iter().copied().collect();
                close(&row[12], median(slip.iter().copied()), 5e-5, &what("slip"));
                checked += 1;
            }
        }
    }
    assert_eq!(checked, rows.len(), "rows the files do not give: {rows:?}");
    assert_eq!(checked, 2 * 4);

    // The fit frame by frame: fit.yaml's metrics, each building once (on one storey every
    // stack floor is the first's).
    let fit = read_fit(&out.join("fit.yaml")).unwrap().unwrap();
    let frames = table(&doc, "frames");
    assert_eq!(frames.len(), 2 * 4, "{frames:?}");
    let once = |name: &str| !name.starts_with("1 storey,") || name == "1 storey, stack on floor 1";
    for z in &fit.zones {
        assert_eq!(z.frames.len(), 6);
        for f in z.frames.iter().filter(|f| once(&f.frame)) {
            let r = frames
                .iter()
                .find(|r| r[0] == z.zone && r[1] == f.frame)
                .unwrap_or_else(|| panic!("no frame row {} {}", z.zone, f.frame));
            assert_eq!(r[2], f.cases.to_string());
            close(&r[3], f.building.r2, 5e-4, "building R²");
            close(
                &r[5],
                f.one_storey.as_ref().unwrap().r2,
                5e-4,
                "one-storey R²",
            );
            close(&r[8], f.lambda.as_ref().unwrap().r2, 5e-4, "λ R²");
        }
    }

    // The IDA's fragilities: ida.h5's θ and β (frames folded into the case axis, case-major),
    // each building once.
    let rows = table(&doc, "ida-fragility");
    let mut frames_seen = Vec::new();
    for zone in ["III", "V"] {
        let (axes, z) = read_zone_ida(&out.join("ida.h5"), zone).unwrap();
        let b = axes.building.as_ref().unwrap();
        let per = b.stack_floor.len();
        for f in 0..b.frame_count() {
            let (n, floor) = (b.storeys[f / per], b.stack_floor[f % per]);
            let label = match (n, floor.to_string().as_str()) {
                (1, _) => format!(
                    "1 storey, {}",
                    frame_tail(&b.stack_floor[f % per].to_string())
                ),
                (_, j) => format!("{n} storeys, {}", frame_tail(j)),
            };
            let zrows: Vec<&Vec<String>> = rows
                .iter()
                .filter(|r| r[0] == zone && r[1] == "0" && r[2] == label)
                .collect();
            if n == 1 && f % per > 0 {
                assert!(zrows.is_empty(), "{label} shown twice");
                continue;
            }
            assert_eq!(
                zrows.len(),
                axes.systems.len() * axes.limit_states.len(),
                "{label}"
            );
            for r in zrows {
                let s = axes.systems.iter().position(|x| *x == r[3]).unwrap();
                let l = axes.limit_states.iter().position(|x| *x == r[4]).unwrap();
                let what = format!("zone {zone}, {label}, {}, {}", r[3], r[4]);
                close(&r[5], z.vars.theta_sa_g[[s, f, l]], 5e-4, &what);
                close(&r[7], z.vars.beta[[s, f, l]], 5e-4, &what);
            }
            frames_seen.push(label);
        }
    }
    assert_eq!(frames_seen.len(), 2 * 4);

    // A forced rebuild writes the same bytes.
    let manifest = std::fs::read(report.join("MANIFEST.sha256")).unwrap();
    ok(slidestack(&["report", c, "--out", o, "--force"], "2"));
    assert_eq!(
        std::fs::read(report.join("MANIFEST.sha256")).unwrap(),
        manifest
    );
}

/// The end of a frame's label after the storey count (`Frame`'s `Display`).
fn frame_tail(floor: &str) -> String {
    match floor {
        "roof" => "stack on the roof".into(),
        "all" => "a stack on every floor".into(),
        j => format!("stack on floor {j}"),
    }
}

/// `report.compare_with`: the building section sets another study's answer (the same cases
/// under the structure basis) beside this one's, each cell the median of that study's own
/// answer table; refused while the other study has not been run (naming it and the stage to
/// run), and out of date when the other's inputs change.
#[test]
fn a_building_report_compares_the_other_damping_basis_frame_by_frame() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let base = std::fs::read_to_string(root.join("configs/mdof-quick.yaml")).unwrap();
    let (out_r, out_s) = (dir.path().join("r"), dir.path().join("s"));
    let structure = dir.path().join("structure.yaml");
    let mut cfg: serde_yaml::Value = serde_yaml::from_str(&base).unwrap();
    cfg["output_dir"] = serde_yaml::Value::from(out_s.to_str().unwrap());
    cfg["grid"]["damping_basis"] = serde_yaml::Value::from("structure");
    std::fs::write(&structure, serde_yaml::to_string(&cfg).unwrap()).unwrap();
    let rigid = dir.path().join("rigid.yaml");
    std::fs::write(
        &rigid,
        format!("{base}report:\n  compare_with: structure.yaml\n"),
    )
    .unwrap();
    let (r, s) = (rigid.to_str().unwrap(), structure.to_str().unwrap());
    // The compared study not run: refused, naming it.
    let o = Command::new(env!("CARGO_BIN_EXE_slidestack"))
        .args(["run", r, "--out", out_r.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("structure.yaml") && err.contains("is missing"),
        "{err}"
    );
    ok(slidestack(&["run", s], "2"));
    ok(slidestack(
        &["run", r, "--out", out_r.to_str().unwrap()],
        "2",
    ));
    let doc_of = |out: &Path| std::fs::read_to_string(out.join("report/index.html")).unwrap();
    let (mine, theirs) = (doc_of(&out_r), doc_of(&out_s));
    let (mine, theirs) = (html_document(&mine), html_document(&theirs));
    let compare = table(&mine, "building-compare");
    let (own, other) = (
        table(&mine, "building-answer"),
        table(&theirs, "building-answer"),
    );
    assert_eq!(compare.len(), own.len());
    let h = header(&mine, "building-compare");
    assert!(h[2].contains("rigid basis, 3 stochastic motions"), "{h:?}");
    assert!(
        h[3].contains("structure basis, 3 stochastic motions"),
        "{h:?}"
    );
    let first = |cell: &str| cell.split_whitespace().next().unwrap().to_string();
    for ((c, a), b) in compare.iter().zip(&own).zip(&other) {
        assert_eq!((&c[0], &c[1]), (&a[0], &a[1]));
        // Drift ratio (answer column 4), base shear (6), λ (7), λ_code (10), T_new/T_1 (8).
        for (k, col) in [4, 6, 7, 10, 8].iter().enumerate() {
            let (x, y) = (first(&a[*col]), first(&b[*col]));
            let (x, y): (f64, f64) = (x.parse().unwrap(), y.parse().unwrap());
            // The answer table prints λ and λ_code to two digits, the comparison to three:
            // half a unit of the second and of the third.
            close(&c[2 + 2 * k], x, 5.5e-3, "this study's median");
            close(&c[3 + 2 * k], y, 5.5e-3, "the compared study's median");
        }
    }
    // The compared study's inputs changed (its damping): this report is out of date.
    cfg["grid"]["damping"] = serde_yaml::Value::from(0.04);
    std::fs::write(&structure, serde_yaml::to_string(&cfg).unwrap()).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_slidestack"))
        .args([
            "status",
            r,
            "--out",
            out_r.to_str().unwrap(),
            "--format",
            "env",
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("REPORT=stale"), "{text}");
}

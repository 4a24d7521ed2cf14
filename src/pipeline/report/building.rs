//! The building section of a building study's report (docs/model.md, "A study over
//! buildings"): does the sliding stack lower the building's demands, and how does that depend on
//! the floor it stands on? Per zone and distinct frame, from `sweep.h5` and `tnew.h5`:
//!
//! * a table of the medians over the frame's cases of the ratios "mean over the motions of a
//!   peak with the sliding stack / the same with the stack rigidly attached" (roof displacement,
//!   peak interstorey drift ratio, peak floor acceleration, peak base shear), with the share of
//!   cases below 1, and of `λ` and `T_new/T_1`;
//! * `T_new/T_1` and `λ` against `T_1`, a panel per storey count, a line per stack floor (the
//!   median over the mass ratios and friction coefficients, the 10th–90th percentile band);
//! * the drift-ratio and floor-acceleration profiles over the height, with and without sliding
//!   (per storey or floor, the median over the frame's cases of the mean over the motions).
//!
//! A frame that repeats an earlier one's building is shown once ([`crate::study::shape::StudyShape::distinct`]).

use super::text::fixed;
use super::{Files, Inputs, ReportError};
use crate::grid::{BuildingAxes, Grid, StackFloor};
use crate::pipeline::files;
use crate::pipeline::{PipelineError, StageId};
use crate::render::chart::{Axis, Figure, PALETTE, Panel, Series, Stroke};
use crate::render::page::{Section, para, table_with_id};
use crate::store::StoreError;
use crate::study::building::Frame;
use plotters::style::RGBColor;

/// The `p`-th percentile (0–100) of the finite values of `v`, linearly interpolated between
/// order statistics (NumPy's default, `nanpercentile`); NaN when none is finite.
fn percentile(v: &[f64], p: f64) -> f64 {
    let mut x: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if x.is_empty() {
        return f64::NAN;
    }
    x.sort_by(f64::total_cmp);
    let pos = p / 100.0 * (x.len() - 1) as f64;
    let (lo, frac) = (pos.floor() as usize, pos - pos.floor());
    match x.get(lo + 1) {
        Some(hi) if frac > 0.0 => x[lo] + frac * (hi - x[lo]),
        _ => x[lo],
    }
}

/// The share of the finite values of `v` below 1.
fn share_below_1(v: &[f64]) -> f64 {
    let finite: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    finite.iter().filter(|&&x| x < 1.0).count() as f64 / finite.len() as f64
}

/// A peak with the stack and with it rigidly attached: per case the mean over the motions.
struct Pair {
    stack: Vec<f64>,
    rigid: Vec<f64>,
}

impl Pair {
    /// Per case, stack over rigid.
    fn ratio(&self) -> Vec<f64> {
        self.stack
            .iter()
            .zip(&self.rigid)
            .map(|(s, r)| s / r)
            .collect()
    }
}

/// One distinct frame of one zone, per case of the grid (flat order).
struct FrameCases {
    frame: Frame,
    roof: Pair,
    /// The largest storey's peak drift ratio, the largest floor's peak acceleration (g).
    drift: Pair,
    accel: Pair,
    shear: Pair,
    /// Per case and motion (pooled), stack over rigid: the spread the means hide.
    roof_each: Vec<f64>,
    drift_each: Vec<f64>,
    accel_each: Vec<f64>,
    /// Empty on one storey (its sweep gives no base shear per motion).
    shear_each: Vec<f64>,
    /// Per floor (1 the lowest), how often (cases × motions) it held the largest floor
    /// acceleration with the sliding stack.
    accel_floor_count: Vec<usize>,
    /// Per case, the mean over the motions of the peak slip of interface 1, m.
    slip: Vec<f64>,
    /// Per case: `V̄_stack/V̄(0)`, `λ_code`.
    ratio_bare: Vec<f64>,
    lambda_code: Vec<f64>,
    lambda: Vec<f64>,
    /// `T_new / T_1`.
    t_ratio: Vec<f64>,
    /// Per storey (drift ratio) and floor (acceleration, g), the median over the cases.
    drift_profile: (Vec<f64>, Vec<f64>),
    accel_profile: (Vec<f64>, Vec<f64>),
}

/// One zone's distinct frames.
struct BuildingZone {
    name: String,
    frames: Vec<FrameCases>,
}

/// Reads what the section needs of every zone, checking that `sweep.h5` holds the study's
/// grid and frames.
fn load(inp: &Inputs) -> Result<Vec<BuildingZone>, PipelineError> {
    let study = inp.study;
    let axes = study
        .building()
        .expect("the building section of a building study");
    let frames = study.shape.distinct();
    let path = study.path(StageId::Sweep.output());
    let mut out = Vec::new();
    for z in &inp.zones {
        let sweep = files::sweep_zone(study, &z.name, None)?;
        let Some(b) = &sweep.building else {
            let why = format!("zone_{}: has no per-floor peaks", z.name);
            return Err(StoreError::corrupt(&path, why).into());
        };
        let Some(lambda) = &z.tnew.lambda else {
            let why = format!("zone_{}: has no λ", z.name);
            return Err(StoreError::corrupt(&study.path("tnew.h5"), why).into());
        };
        let flat = |v: &ndarray::ArrayD<f64>| v.iter().copied().collect::<Vec<f64>>();
        let columns = ZoneColumns {
            grid: inp.grid,
            motions: sweep.motions.len(),
            frame_count: axes.frame_count(),
            n_max: axes.max_storeys(),
            u_stack: flat(&sweep.vars.u_stack),
            u_rigid: flat(&sweep.vars.u_rigid),
            slip_peak: flat(&sweep.vars.slip_peak),
            d_stack: flat(&b.drift_ratio_stack),
            d_rigid: flat(&b.drift_ratio_rigid),
            a_stack: flat(&b.floor_accel_stack),
            a_rigid: flat(&b.floor_accel_rigid),
            vm_stack: flat(&b.base_shear_stack),
            vm_rigid: flat(&b.base_shear_rigid),
            v_stack: flat(&lambda.base_shear_stack_mean),
            v_rigid: flat(&lambda.base_shear_rigid_mean),
            lambda: flat(&lambda.lambda),
            t_new: flat(&z.tnew.vars.t_new),
            ratio_bare: flat(&lambda.base_shear_ratio_bare),
            lambda_code: flat(&lambda.lambda_code),
        };
        out.push(BuildingZone {
            name: z.name.clone(),
            frames: (frames.iter())
                .map(|(f, frame)| columns.frame_cases(*f, frame))
                .collect(),
        });
    }
    Ok(out)
}

/// One zone's stored variables the section reads, flat in their stored order: the sweep's
/// `[motion, frame, case(, level)]` (level `N_max` long), `tnew.h5`'s `[frame, case]`.
struct ZoneColumns<'a> {
    grid: &'a Grid,
    motions: usize,
    frame_count: usize,
    n_max: usize,
    u_stack: Vec<f64>,
    u_rigid: Vec<f64>,
    slip_peak: Vec<f64>,
    d_stack: Vec<f64>,
    d_rigid: Vec<f64>,
    a_stack: Vec<f64>,
    a_rigid: Vec<f64>,
    vm_stack: Vec<f64>,
    vm_rigid: Vec<f64>,
    v_stack: Vec<f64>,
    v_rigid: Vec<f64>,
    lambda: Vec<f64>,
    t_new: Vec<f64>,
    ratio_bare: Vec<f64>,
    lambda_code: Vec<f64>,
}

impl ZoneColumns<'_> {
    /// Frame `f` (`frame`, stored `f`-th): its cases' means, ratios and profiles.
    fn frame_cases(&self, f: usize, frame: &Frame) -> FrameCases {
        let (per, motions, n_max) = (self.grid.cases(), self.motions, self.n_max);
        let n = frame.storeys();
        // Mean over the motions of `value(m, case)`, per case.
        let over_motions = |value: &dyn Fn(usize, usize) -> f64| -> Vec<f64> {
            (0..per)
                .map(|c| (0..motions).map(|m| value(m, c)).sum::<f64>() / motions as f64)
                .collect()
        };
        let at = |m: usize, c: usize| (m * self.frame_count + f) * per + c;
        let peak_over = |v: &[f64], m: usize, c: usize| {
            let i = at(m, c) * n_max;
            v[i..i + n]
                .iter()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max)
        };
        let profile = |v: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|j| percentile(&over_motions(&|m, c| v[at(m, c) * n_max + j]), 50.0))
                .collect()
        };
        let in_frame = |v: &[f64]| v[f * per..(f + 1) * per].to_vec();
        // Per case and motion (pooled), `value(m, c)`.
        let each = |value: &dyn Fn(usize, usize) -> f64| -> Vec<f64> {
            (0..per)
                .flat_map(|c| (0..motions).map(move |m| (m, c)))
                .map(|(m, c)| value(m, c))
                .collect()
        };
        let (u_stack, u_rigid) = (&self.u_stack, &self.u_rigid);
        let (d_stack, d_rigid) = (&self.d_stack, &self.d_rigid);
        let (a_stack, a_rigid) = (&self.a_stack, &self.a_rigid);
        let (vm_stack, vm_rigid) = (&self.vm_stack, &self.vm_rigid);
        let mut accel_floor_count = vec![0; n];
        for c in 0..per {
            for m in 0..motions {
                let i = at(m, c) * n_max;
                let top = (0..n)
                    .reduce(|a, j| {
                        if a_stack[i + j] > a_stack[i + a] {
                            j
                        } else {
                            a
                        }
                    })
                    .unwrap_or(0);
                accel_floor_count[top] += 1;
            }
        }
        let blocks = self.grid.blocks();
        FrameCases {
            roof_each: each(&|m, c| u_stack[at(m, c)] / u_rigid[at(m, c)]),
            drift_each: each(&|m, c| peak_over(d_stack, m, c) / peak_over(d_rigid, m, c)),
            accel_each: each(&|m, c| peak_over(a_stack, m, c) / peak_over(a_rigid, m, c)),
            shear_each: if n > 1 {
                each(&|m, c| vm_stack[at(m, c)] / vm_rigid[at(m, c)])
            } else {
                Vec::new()
            },
            accel_floor_count,
            slip: over_motions(&|m, c| self.slip_peak[at(m, c) * blocks]),
            ratio_bare: in_frame(&self.ratio_bare),
            lambda_code: in_frame(&self.lambda_code),
            frame: frame.clone(),
            roof: Pair {
                stack: over_motions(&|m, c| u_stack[at(m, c)]),
                rigid: over_motions(&|m, c| u_rigid[at(m, c)]),
            },
            drift: Pair {
                stack: over_motions(&|m, c| peak_over(d_stack, m, c)),
                rigid: over_motions(&|m, c| peak_over(d_rigid, m, c)),
            },
            accel: Pair {
                stack: over_motions(&|m, c| peak_over(a_stack, m, c)),
                rigid: over_motions(&|m, c| peak_over(a_rigid, m, c)),
            },
            shear: Pair {
                stack: in_frame(&self.v_stack),
                rigid: in_frame(&self.v_rigid),
            },
            lambda: in_frame(&self.lambda),
            t_ratio: (0..per)
                .map(|c| self.t_new[f * per + c] / self.grid.case(c).period_s)
                .collect(),
            drift_profile: (profile(d_stack), profile(d_rigid)),
            accel_profile: (profile(a_stack), profile(a_rigid)),
        }
    }
}

/// The answer table's header.
const ANSWER_HEADER: [&str; 13] = [
    "zone",
    "building, stack on",
    "cases",
    "roof displacement (DRR_1) [10–90 % per motion]",
    "peak interstorey drift ratio (share below 1) [10–90 % per motion]",
    "peak floor acceleration (share below 1) [10–90 % per motion]",
    "peak base shear [10–90 % per motion]",
    "λ [25th, 75th percentile] (share below 0)",
    "T_new/T_1",
    "base shear over the bare building's (share below 1)",
    "λ_code [25th, 75th percentile]",
    "floor holding the peak floor acceleration (share of cases × motions)",
    "peak slip of interface 1, m",
];

/// `3 storeys, roof` (`1 storey` alone).
fn frame_name(f: &Frame) -> String {
    let n = f.storeys();
    if n == 1 {
        return "1 storey".into();
    }
    format!("{n} storeys, {}", floor_name(f.stack_floor))
}

/// `floor 2`, `roof`, `every floor`.
fn floor_name(s: StackFloor) -> String {
    match s {
        StackFloor::Floor(j) => format!("floor {j}"),
        StackFloor::Roof => "roof".into(),
        StackFloor::Mid => "mid-height".into(),
        StackFloor::All => "every floor".into(),
    }
}

fn answer_rows(zones: &[BuildingZone]) -> Vec<Vec<String>> {
    let med = |v: &[f64]| fixed(percentile(v, 50.0), 3);
    let band = |v: &[f64]| {
        if v.iter().any(|x| x.is_finite()) {
            format!(
                " [{}, {}]",
                fixed(percentile(v, 10.0), 2),
                fixed(percentile(v, 90.0), 2)
            )
        } else {
            String::new()
        }
    };
    let share = |v: &[f64]| format!(" ({:.0} %)", 100.0 * share_below_1(v));
    let quartiles = |v: &[f64]| {
        format!(
            "{} [{}, {}]",
            fixed(percentile(v, 50.0), 2),
            fixed(percentile(v, 25.0), 2),
            fixed(percentile(v, 75.0), 2)
        )
    };
    let mut rows = Vec::new();
    for z in zones {
        for f in &z.frames {
            let l = &f.lambda;
            let below_0 = l.iter().filter(|&&x| x < 0.0).count() as f64 / l.len() as f64;
            let total: usize = f.accel_floor_count.iter().sum();
            let (top, count) = (f.accel_floor_count.iter().enumerate())
                .fold((0, 0), |b, (j, &k)| if k > b.1 { (j, k) } else { b });
            let top_name = if top + 1 == f.frame.storeys() {
                "roof".to_string()
            } else {
                format!("floor {}", top + 1)
            };
            rows.push(vec![
                z.name.clone(),
                frame_name(&f.frame),
                f.roof.stack.len().to_string(),
                med(&f.roof.ratio()) + &band(&f.roof_each),
                med(&f.drift.ratio()) + &share(&f.drift.ratio()) + &band(&f.drift_each),
                med(&f.accel.ratio()) + &share(&f.accel.ratio()) + &band(&f.accel_each),
                med(&f.shear.ratio()) + &band(&f.shear_each),
                format!("{} ({:.0} %)", quartiles(l), 100.0 * below_0),
                med(&f.t_ratio),
                med(&f.ratio_bare) + &share(&f.ratio_bare),
                quartiles(&f.lambda_code),
                format!("{top_name} ({:.0} %)", 100.0 * count as f64 / total as f64),
                fixed(percentile(&f.slip, 50.0), 4),
            ]);
        }
    }
    rows
}

/// What a study's answer rests on: `rigid basis, 7 stochastic motions`.
fn basis_and_motions(inp: &Inputs) -> String {
    let motions = inp.zones.first().map_or(0, |z| z.motions.len());
    let kind = match inp.study.cfg.motions.seeds.kind() {
        crate::study::config::Seeds::Stochastic(_) => "stochastic motions",
        crate::study::config::Seeds::Records(_) => "matched records",
    };
    format!("{} basis, {motions} {kind}", inp.physics.basis.name())
}

/// The compared quantities of [`comparison`]: header, the frame's median of it.
const COMPARED: [&str; 5] = [
    "peak drift ratio",
    "peak base shear",
    "λ",
    "λ_code",
    "T_new/T_1",
];

/// A frame's medians of the [`COMPARED`] quantities.
fn compared_medians(f: &FrameCases) -> [f64; 5] {
    [
        percentile(&f.drift.ratio(), 50.0),
        percentile(&f.shear.ratio(), 50.0),
        percentile(&f.lambda, 50.0),
        percentile(&f.lambda_code, 50.0),
        percentile(&f.t_ratio, 50.0),
    ]
}

/// Differences below this (in the medians of the ratios and fractions) are not called
/// differences: the table's third digit, well within what a few motions' means resolve.
const SAME_WITHIN: f64 = 0.01;

/// The answer beside the compared study's (`report.compare_with`), frame by frame: the median
/// ratios and fractions of both, and where they differ by more than [`SAME_WITHIN`].
fn comparison(
    inp: &Inputs,
    zones: &[BuildingZone],
    other: &Inputs,
    theirs: &[BuildingZone],
) -> String {
    let (mine, their_label) = (basis_and_motions(inp), basis_and_motions(other));
    let mut header = vec!["zone".to_string(), "building, stack on".to_string()];
    for q in COMPARED {
        header.push(format!("{q}: {mine}"));
        header.push(format!("{q}: {their_label}"));
    }
    header.push("differs by more than 0.01 in".to_string());
    let mut rows = Vec::new();
    let mut differing = 0;
    for (z, t) in zones.iter().zip(theirs) {
        for (f, g) in z.frames.iter().zip(&t.frames) {
            let (a, b) = (compared_medians(f), compared_medians(g));
            let mut row = vec![z.name.clone(), frame_name(&f.frame)];
            let mut which = Vec::new();
            for (k, q) in COMPARED.iter().enumerate() {
                row.push(fixed(a[k], 3));
                row.push(fixed(b[k], 3));
                if (a[k] - b[k]).abs() > SAME_WITHIN {
                    which.push(*q);
                }
            }
            differing += usize::from(!which.is_empty());
            row.push(if which.is_empty() {
                "–".into()
            } else {
                which.join(", ")
            });
            rows.push(row);
        }
    }
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    let frames = rows.len();
    para(&format!(
        "The same buildings and cases under {their_label} ({}, report.compare_with): the medians \
         over each frame's cases of the ratios and fractions above, side by side; {differing} of \
         {frames} frames differ by more than {SAME_WITHIN} in at least one of them (the last \
         column says in which).",
        other.study.config_path.display()
    )) + &table_with_id("building-compare", &header, &rows)
}

/// The storey counts of a zone's frames, increasing, and each one's frames.
fn by_storeys(z: &BuildingZone) -> Vec<(usize, Vec<&FrameCases>)> {
    let mut out: Vec<(usize, Vec<&FrameCases>)> = Vec::new();
    for f in &z.frames {
        let n = f.frame.storeys();
        match out.iter_mut().find(|(m, _)| *m == n) {
            Some((_, v)) => v.push(f),
            None => out.push((n, vec![f])),
        }
    }
    out
}

/// The band of the 10th to 90th percentiles of `at_percentile` over `x` and its median line, in
/// `colour`, named after `name`.
fn band_and_median(
    name: &str,
    colour: RGBColor,
    x: &[f64],
    at_percentile: impl Fn(f64) -> Vec<f64>,
) -> [Series; 2] {
    [
        Series::band(
            format!("{name}: 10th–90th percentile"),
            x.to_vec(),
            at_percentile(10.0),
            at_percentile(90.0),
        )
        .colour(colour),
        Series::line(format!("{name}: median"), x.to_vec(), at_percentile(50.0))
            .colour(colour)
            .stroke(Stroke::Solid, 2),
    ]
}

/// `T_new/T_1` and `λ` against `T_1`: a panel per storey count and quantity.
fn against_period(
    z: &BuildingZone,
    inp: &Inputs,
    files: &mut Files,
) -> Result<String, ReportError> {
    let grid = inp.grid;
    let tp = &grid.periods_s;
    let per_t = grid.cases_per_unit();
    let groups = by_storeys(z);
    // Per T_1, the percentile p over the frame's cases (T_1 the slowest axis).
    let over_t = |v: &[f64], p: f64| -> Vec<f64> {
        (0..tp.len())
            .map(|i| percentile(&v[i * per_t..(i + 1) * per_t], p))
            .collect()
    };
    let black = RGBColor(0, 0, 0);
    let mut panels = Vec::new();
    for (title, y_label, value, reference) in [
        (
            "T_new/T_1",
            "T_new / T_1 (–)",
            (|f: &FrameCases| f.t_ratio.clone()) as fn(&FrameCases) -> Vec<f64>,
            Some(("T_new = T_1 (bare building)", 1.0)),
        ),
        (
            "λ",
            "λ (–)",
            |f: &FrameCases| f.lambda.clone(),
            Some(("λ = 1 (the whole stack as seismic mass)", 1.0)),
        ),
    ] {
        // The row's range: every band of its panels and the reference line.
        let (lo, hi) = (groups.iter().flat_map(|(_, fs)| fs.iter()))
            .flat_map(|f| {
                let v = value(f);
                let mut ends = over_t(&v, 10.0);
                ends.extend(over_t(&v, 90.0));
                ends
            })
            .chain(reference.map(|r| r.1))
            .filter(|x| x.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
        let pad = 0.05 * (hi - lo).max(1e-3);
        for (n, frames) in &groups {
            let mut series = Vec::new();
            for (k, f) in frames.iter().enumerate() {
                let v = value(f);
                let colour = PALETTE[k % PALETTE.len()];
                let name = if *n == 1 {
                    "one storey".to_string()
                } else {
                    format!("stack on {}", floor_name(f.frame.stack_floor))
                };
                series.extend(band_and_median(&name, colour, tp, |p| over_t(&v, p)));
            }
            if let Some((label, y)) = reference {
                series.push(
                    Series::hline(label, tp[0], tp[tp.len() - 1], y)
                        .colour(black)
                        .stroke(Stroke::Dotted, 1),
                );
            }
            let storeys = if *n == 1 { "storey" } else { "storeys" };
            panels.push(Panel::xy(
                format!("{title}, {n} {storeys}"),
                Axis::new("T_1 (s)"),
                Axis::new(y_label).range(lo - pad, hi + pad),
                series,
            ));
        }
    }
    let fig = Figure::grid(
        format!("Zone {}: T_new/T_1 and λ against T_1", z.name),
        panels,
        groups.len(),
    )
    .panel_px(420, 300);
    files.figure(
        &format!("building_period_{}.svg", z.name),
        &fig,
        &format!(
            "Zone {}: T_new of the first mode over the bare building's T_1 (top) and the \
             effective live-load fraction λ (bottom) against T_1, a panel per storey count, a \
             colour per stack floor: the median over the mass ratios and friction coefficients \
             at each T_1 and the band of their 10th to 90th percentiles.",
            z.name
        ),
    )
}

/// The drift-ratio and floor-acceleration profiles over the height of every building of more
/// than one storey, with the sliding stack (solid) and with it rigidly attached (dashed).
fn profiles(z: &BuildingZone, files: &mut Files) -> Result<Option<String>, ReportError> {
    let groups: Vec<_> = by_storeys(z).into_iter().filter(|(n, _)| *n > 1).collect();
    if groups.is_empty() {
        return Ok(None);
    }
    let mut panels = Vec::new();
    for (title, x_label, scale, profile) in [
        (
            "peak interstorey drift ratio",
            "peak drift ratio (%)",
            100.0,
            (|f: &FrameCases| &f.drift_profile) as fn(&FrameCases) -> &(Vec<f64>, Vec<f64>),
        ),
        (
            "peak floor acceleration",
            "peak absolute acceleration (g)",
            1.0,
            |f: &FrameCases| &f.accel_profile,
        ),
    ] {
        // The row's range, from 0: every profile of its panels.
        let top = (groups.iter().flat_map(|(_, fs)| fs.iter()))
            .flat_map(|f| {
                let (s, r) = profile(f);
                s.iter().chain(r).copied().collect::<Vec<f64>>()
            })
            .filter(|x| x.is_finite())
            .fold(0.0, f64::max)
            * scale;
        for (n, frames) in &groups {
            let levels: Vec<f64> = (1..=*n).map(|j| j as f64).collect();
            let mut series = Vec::new();
            for (k, f) in frames.iter().enumerate() {
                let (stack, rigid) = profile(f);
                let colour = PALETTE[k % PALETTE.len()];
                let name = format!("stack on {}", floor_name(f.frame.stack_floor));
                let scaled = |v: &[f64]| v.iter().map(|x| x * scale).collect::<Vec<f64>>();
                series.push(
                    Series::line(
                        format!("{name}, rigidly attached"),
                        scaled(rigid),
                        levels.clone(),
                    )
                    .colour(colour)
                    .stroke(Stroke::Dashed, 1),
                );
                series.push(
                    Series::line(format!("{name}, sliding"), scaled(stack), levels.clone())
                        .colour(colour)
                        .stroke(Stroke::Solid, 2),
                );
            }
            let level = if scale == 1.0 { "floor" } else { "storey" };
            panels.push(Panel::xy(
                format!("{title}, {n} storeys"),
                Axis::new(x_label).range(0.0, 1.05 * top.max(f64::MIN_POSITIVE)),
                Axis::new(level).range(0.5, *n as f64 + 0.5),
                series,
            ));
        }
    }
    let fig = Figure::grid(
        format!(
            "Zone {}: drift and floor acceleration over the height",
            z.name
        ),
        panels,
        groups.len(),
    )
    .panel_px(420, 320);
    let html = files.figure(
        &format!("building_profiles_{}.svg", z.name),
        &fig,
        &format!(
            "Zone {}: per storey the peak interstorey drift ratio (top) and per floor the peak \
             absolute acceleration (bottom), the median over the frame's cases of the mean over \
             the motions, with the sliding stack (solid) and with it rigidly attached (dashed), \
             a panel per storey count, a colour per stack floor.",
            z.name
        ),
    )?;
    Ok(Some(html))
}

/// The building section.
pub(super) fn building_section(
    inp: &Inputs,
    compared: Option<&Inputs>,
    files: &mut Files,
) -> Result<Section, PipelineError> {
    let zones = load(inp)?;
    let axes: &BuildingAxes = inp.study.building().expect("a building study");
    let mut body = para(&format!(
        "Does a sliding stack lower a building's demands as it lowers one storey's, and how \
         does it depend on the floor it stands on? Buildings of {} storeys, the stack on {} \
         (one storey: its only floor); each ratio \
         is the mean over the motions of a peak with the sliding stack over the same with the \
         stack rigidly attached, and the table gives its median over the frame's {} cases \
         (the grid's T_1, α and μ) and, for the drift and the floor acceleration, the share of \
         cases below 1. The peak drift ratio is the largest storey's, the peak floor \
         acceleration the largest floor's; the peak base shear is the mean over the motions \
         (tnew.h5). In brackets, the 10th and 90th percentiles of the same ratio motion by motion \
         (each case's peak under one motion over its rigid peak under that motion; pooled over \
         the cases and motions): the spread the means over few motions hide. λ is the effective \
         live-load fraction (the part of the stack's mass that, rigidly attached, gives the \
         sliding stack's mean peak base shear; below 0 where the stack lowers the base shear \
         below the bare building's, as removing that part of its mass would; docs/model.md, \
         \"The attached fraction\"), λ_code the fraction a code's equivalent lateral force with \
         the zone's mean spectrum needs to give the same base shear. The floor column says \
         which floor holds the largest floor acceleration with the sliding stack, and how often; \
         the slip is the median over the cases of the mean over the motions of interface 1's \
         peak slip (with a stack on every floor, the largest over them). A frame that is an \
         earlier one's building (on one storey every stack floor) is shown once.",
        axes.storeys
            .iter()
            .map(|n| n.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        axes.stack_floor
            .iter()
            .map(|s| floor_name(*s))
            .collect::<Vec<_>>()
            .join(" or "),
        inp.grid.cases()
    ));
    body += &table_with_id("building-answer", &ANSWER_HEADER, &answer_rows(&zones));
    if let Some(other) = compared {
        body += &comparison(inp, &zones, other, &load(other)?);
    }
    for z in &zones {
        body += &against_period(z, inp, files)?;
        if let Some(p) = profiles(z, files)? {
            body += &p;
        }
    }
    Ok(Section::new(
        "building",
        "The building: demands with and without sliding, T_new and λ",
        body,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_as_numpy() {
        // numpy.nanpercentile([3, 1, nan, 2, 10], [0, 25, 50, 90, 100]) = 1, 1.75, 2.5, 7.9, 10
        let v = [3.0, 1.0, f64::NAN, 2.0, 10.0];
        let got: Vec<f64> = [0.0, 25.0, 50.0, 90.0, 100.0]
            .iter()
            .map(|&p| percentile(&v, p))
            .collect();
        let want = [1.0, 1.75, 2.5, 7.9, 10.0];
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 1e-12, "{got:?}");
        }
        assert!(percentile(&[f64::NAN], 50.0).is_nan());
        assert_eq!(share_below_1(&[0.5, 1.0, f64::NAN, 2.0]), 1.0 / 3.0);
    }
}

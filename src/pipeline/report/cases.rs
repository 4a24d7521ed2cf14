//! The paper's two named cases: Section 7.1 (histories, the construction of `T_new` of Fig. 12,
//! the energy partition) and Table 2 (stack against single block).

use super::runs::{section71_tnew, simulate};
use super::text::{fixed, mean, nums, sig};
use super::{Files, Inputs, ReportError, Zone};
use crate::render::chart::{Axis, Figure, Mark, PALETTE, Panel, Plot, Segment, Series, Stroke};
use crate::render::page::{Section, para, table_with_id};
use crate::study::cases::{PAPER_SECTION_7_1, PAPER_TABLE_2, SECTION_7_1};
use crate::study::physics::{Physics, SystemKind};
use crate::study::tnew::TnewFlag;
use plotters::style::RGBColor;

pub(super) fn section71_section(inp: &Inputs, files: &mut Files) -> Result<Section, ReportError> {
    let physics = &inp.physics;
    let n = inp.grid.blocks();
    let first = &inp.zones[0].paper().section71;
    let mut body = para(&format!(
        "The paper's Section 7.1 example: {}{}. Each system runs under every motion of the zone \
         with the study's physics (ζ = {} of the {} basis, μ_s = {} × μ_k).",
        first.describe(),
        if n == SECTION_7_1.alpha.len() {
            String::new()
        } else {
            format!(
                " (the paper's two-block case {} carried to {n} blocks: same total mass in equal \
                 blocks, μ_1 kept, upper interfaces at the paper's top coefficient)",
                nums(SECTION_7_1.alpha)
            )
        },
        physics.damping,
        physics.basis.name(),
        physics.mu_static_ratio
    ));
    let mut rows = Vec::new();
    let mut energy_rows = Vec::new();
    let mut energy_panels = Vec::new();
    for z in &inp.zones {
        body += &histories(z, physics, files)?;
        let (fig, row) = construction(z, files)?;
        body += &fig;
        rows.push(row);
        let (e_rows, panel) = energy(z, n);
        energy_rows.extend(e_rows);
        energy_panels.push(panel);
    }
    body += &table_with_id(
        "section71",
        &[
            "zone",
            "mean peak displacement ū (cm)",
            "paper ū (cm)",
            "T_new (s)",
            "paper T_new (s)",
            "T_rigid (s)",
            "how T_new was found",
        ],
        &rows,
    );
    let cols = inp.zones.len().min(2);
    let mut fig = Figure::grid(
        format!(
            "Energy partition of the Section 7.1 case ({}), mean over the motions",
            first.describe()
        ),
        energy_panels,
        cols,
    )
    .panel_px(460, 240);
    fig.share_x = true;
    body += &files.figure(
        "energy.svg",
        &fig,
        "Where the input energy of the Section 7.1 case goes, per system: viscous damping, \
         friction at each interface, and what is left as kinetic and strain energy when the \
         record ends (shares of the input energy, mean over the motions).",
    )?;
    let mut header: Vec<String> = [
        "zone",
        "system",
        "input (J/kg)",
        "kinetic at end (J/kg)",
        "strain at end (J/kg)",
        "damping (J/kg)",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    header.extend((1..=n).map(|i| format!("friction, interface {i} (J/kg)")));
    header.extend(
        [
            "balance residual (J/kg)",
            "damping share (%)",
            "friction share (%)",
        ]
        .iter()
        .map(|s| s.to_string()),
    );
    let h: Vec<&str> = header.iter().map(String::as_str).collect();
    body += &para(
        "Energy per kg of structure mass, mean over the motions; input = kinetic + strain + \
         damping + friction up to the residual. The paper discusses the friction dissipated \
         within the stack but gives no numbers.",
    );
    body += &table_with_id("energy", &h, &energy_rows);
    Ok(Section::new(
        "section71",
        "The Section 7.1 case: histories, T_new (Fig. 12), energy",
        body,
    ))
}

/// Histories of the structure in the three systems under the zone's median motion, then all
/// three around their peaks.
fn histories(z: &Zone, physics: &Physics, files: &mut Files) -> Result<String, ReportError> {
    let c = &z.paper().section71;
    let k = c.median_motion();
    let rec = &z.motions[k];
    // Histories under the median motion, then all three around their peaks.
    let mut panels = Vec::new();
    let mut lines = Vec::new();
    for (i, s) in SystemKind::ALL.into_iter().enumerate() {
        let r = simulate(physics, s, &c.case, rec, true)?;
        let h = r.history.as_ref().expect("history requested");
        let u: Vec<f64> = h
            .displacement_m
            .chunks(h.bodies)
            .map(|row| row[0] * 100.0)
            .collect();
        panels.push(Panel::xy(
            format!(
                "{}: peak {:.2} cm at {:.2} s",
                s.name(),
                r.peak_displacement_m * 100.0,
                r.peak_displacement_time_s
            ),
            Axis::new("time t (s)"),
            Axis::new("u_p (cm)"),
            vec![
                Series::line("", h.time_s.clone(), u.clone())
                    .colour(PALETTE[i])
                    .stroke(Stroke::Solid, 1),
            ],
        ));
        lines.push((s, h.time_s.clone(), u, r.peak_displacement_time_s));
    }
    let end = lines[0].1.last().copied().unwrap_or(0.0);
    let first = lines.iter().map(|l| l.3).fold(f64::INFINITY, f64::min);
    let last = lines.iter().map(|l| l.3).fold(0.0, f64::max);
    let t0 = (first - 3.0).min(last - 5.0).max(0.0);
    let window = (t0, (last + 3.0).max(t0 + 8.0).min(end));
    let overlay = lines
        .into_iter()
        .enumerate()
        .map(|(i, (s, t, u, _))| {
            let (t, u): (Vec<f64>, Vec<f64>) = t
                .into_iter()
                .zip(u)
                .filter(|(t, _)| (window.0..=window.1).contains(t))
                .unzip();
            Series::line(s.name(), t, u)
                .colour(PALETTE[i])
                .stroke(Stroke::Solid, if i == 0 { 2 } else { 1 })
        })
        .collect();
    panels.push(Panel::xy(
        "the three together, around their peaks",
        Axis::new("time t (s)").range(window.0, window.1),
        Axis::new("u_p (cm)"),
        overlay,
    ));
    let fig = Figure::grid(
        format!(
            "Zone {}, Section 7.1 case ({}) under motion {}",
            z.name,
            c.describe(),
            rec.name
        ),
        panels,
        1,
    )
    .panel_px(900, 200);
    files.figure(
        &format!("history_{}.svg", z.name),
        &fig,
        &format!(
            "Zone {}: structure displacement with the stack, the single block and the load \
             rigidly attached (u_p, relative to the ground), under {} (the motion with the \
             median stack peak of the {}); the last panel overlays them around their \
             peaks.",
            z.name,
            rec.name,
            z.motions.len()
        ),
    )
}

/// The construction of `T_new` (paper Fig. 12) and its row of the Section 7.1 table.
fn construction(z: &Zone, files: &mut Files) -> Result<(String, Vec<String>), ReportError> {
    let c = &z.paper().section71;
    let (u, tr, tn, flag) = section71_tnew(z);
    let paper = (PAPER_SECTION_7_1.0 == z.name).then_some(PAPER_SECTION_7_1);
    let t = &z.tnew.period_sd_s;
    let t_max = (1.6 * tr).max(2.5).min(t[t.len() - 1]);
    let keep: Vec<usize> = (0..t.len()).filter(|&i| t[i] <= t_max).collect();
    let sd_cm: Vec<f64> = keep.iter().map(|&i| z.tnew.sd_mean_m[i] * 100.0).collect();
    let tk: Vec<f64> = keep.iter().map(|&i| t[i]).collect();
    let y_top = sd_cm.iter().copied().fold(0.0, f64::max) * 1.05;
    let black = RGBColor(0, 0, 0);
    let mut series = vec![
        Series::line("mean 5 %-damped Sd of the motions", tk, sd_cm).colour(PALETTE[0]),
        Series::vline("T_p (bare structure)", c.case.period_s, 0.0, y_top)
            .colour(black)
            .stroke(Stroke::Dotted, 1),
        Series::vline("T_rigid (load rigidly attached)", tr, 0.0, y_top)
            .colour(black)
            .stroke(Stroke::Dashed, 1),
        Series::hline("mean peak displacement ū (stack)", 0.0, t_max, u * 100.0)
            .colour(PALETTE[1])
            .stroke(Stroke::Dashed, 2),
    ];
    if tn.is_finite() {
        series.push(
            Series::vline("T_new", tn, 0.0, u * 100.0)
                .colour(PALETTE[1])
                .stroke(Stroke::Solid, 2),
        );
        series.push(
            Series::points("crossing (T_new, ū)", vec![tn], vec![u * 100.0])
                .mark(Mark::Points {
                    radius: 5,
                    opacity: 1.0,
                })
                .colour(PALETTE[1]),
        );
    }
    if let Some((_, pu, pt)) = paper {
        series.push(
            Series::points(
                format!("paper: {pt} s, {:.2} cm", pu * 100.0),
                vec![pt],
                vec![pu * 100.0],
            )
            .mark(Mark::Points {
                radius: 5,
                opacity: 1.0,
            })
            .colour(PALETTE[2]),
        );
    }
    let paper_text = paper.map_or(String::new(), |(_, pu, pt)| {
        format!(" (paper {pt} s, {:.2} cm)", pu * 100.0)
    });
    let fig = Figure::single(
        format!("Zone {}: T_new of the Section 7.1 case (Fig. 12)", z.name),
        Panel::xy(
            format!(
                "T_new = {} s, ū = {:.2} cm{paper_text}",
                fixed(tn, 3),
                u * 100.0
            ),
            Axis::new("period T (s)").range(0.0, t_max),
            Axis::new("spectral displacement Sd (cm)").range(0.0, y_top),
            series,
        ),
    )
    .panel_px(700, 440);
    let fig = files.figure(
        &format!("tnew_construction_{}.svg", z.name),
        &fig,
        &format!(
            "Zone {}: the mean over the motions of the stack's peak structure displacement, \
             read off the zone's mean 5 %-damped displacement spectrum (paper Fig. 12).",
            z.name
        ),
    )?;
    let row = vec![
        z.name.clone(),
        format!("{:.2}", u * 100.0),
        paper.map_or("–".into(), |p| format!("{:.2}", p.1 * 100.0)),
        fixed(tn, 3),
        paper.map_or("–".into(), |p| format!("{:.2}", p.2)),
        format!("{tr:.3}"),
        match flag {
            TnewFlag::Unique => "one crossing".into(),
            TnewFlag::Several => "several crossings, nearest T_rigid".into(),
            TnewFlag::OutsideRange => "no crossing".into(),
            TnewFlag::NoSlide => "nothing slid: T_rigid".into(),
        },
    ];
    Ok((fig, row))
}

/// The energy partition of the three systems, mean over the motions: table rows and a panel.
fn energy(z: &Zone, n: usize) -> (Vec<Vec<String>>, Panel) {
    let c = &z.paper().section71;
    let mut rows = Vec::new();
    let mut segs: Vec<(String, Vec<f64>)> = vec![("viscous damping".into(), Vec::new())];
    for i in 0..n {
        segs.push((format!("friction, interface {}", i + 1), Vec::new()));
    }
    segs.push(("kinetic + strain at the end".into(), Vec::new()));
    for s in SystemKind::ALL {
        // The rigid system is one body of the whole mass: its terms per kg of that mass,
        // times (1 + α), are per kg of structure mass like the others'.
        let scale = if s == SystemKind::Rigid {
            1.0 + c.case.alpha_total()
        } else {
            1.0
        };
        let e = |f: &dyn Fn(&crate::dynamics::Energy) -> f64| {
            scale * mean(c.runs.iter().map(|r| f(&r[s as usize].energy)))
        };
        let input = e(&|e| e.input);
        let per: Vec<f64> = (0..n)
            .map(|i| e(&|e| e.friction_per_interface.get(i).copied().unwrap_or(0.0)))
            .collect();
        let (kin, strain, damp) = (e(&|e| e.kinetic), e(&|e| e.strain), e(&|e| e.damping));
        let resid = e(&|e| e.residual());
        let mut row = vec![
            z.name.clone(),
            s.name().to_string(),
            sig(input, 4),
            sig(kin, 3),
            sig(strain, 3),
            sig(damp, 4),
        ];
        row.extend(per.iter().map(|v| sig(*v, 4)));
        row.push(sig(resid, 2));
        row.push(format!("{:.1}", 100.0 * damp / input));
        row.push(format!("{:.1}", 100.0 * per.iter().sum::<f64>() / input));
        rows.push(row);
        let pct = |v: f64| 100.0 * v / input;
        segs[0].1.push(pct(damp));
        for i in 0..n {
            segs[1 + i].1.push(pct(per[i]));
        }
        segs[n + 1].1.push(pct(kin + strain));
    }
    let panel = Panel {
        title: format!("Zone {}", z.name),
        x: Axis::new("share of the input energy (%)").range(0.0, 100.0),
        y: Axis::new(""),
        plot: Plot::StackedBars {
            categories: SystemKind::ALL
                .iter()
                .map(|s| s.name().to_string())
                .collect(),
            segments: segs
                .into_iter()
                .enumerate()
                .map(|(i, (label, values))| Segment {
                    label,
                    values,
                    colour: Some(if i == 0 {
                        PALETTE[0]
                    } else if i == n + 1 {
                        RGBColor(170, 170, 170)
                    } else {
                        PALETTE[(i + 2) % PALETTE.len()]
                    }),
                })
                .collect(),
        },
    };
    (rows, panel)
}

pub(super) fn table2_section(inp: &Inputs) -> Section {
    let c0 = &inp.zones[0].paper().table2;
    let mut rows = Vec::new();
    for z in &inp.zones {
        let c = &z.paper().table2;
        let (single, stack) = (
            c.mean_peak(SystemKind::SingleBlock),
            c.mean_peak(SystemKind::Stack),
        );
        let reductions: Vec<f64> = c
            .runs
            .iter()
            .map(|r| 100.0 * (1.0 - r[0].peak_displacement_m / r[1].peak_displacement_m))
            .collect();
        let (rmin, rmax) = reductions
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let paper = PAPER_TABLE_2.iter().find(|p| p.0 == z.name);
        let dash = || "–".to_string();
        rows.push(vec![
            z.name.clone(),
            format!("{single:.4}"),
            format!("{stack:.4}"),
            format!("{:.1}", 100.0 * (1.0 - stack / single)),
            format!("{rmin:.1} to {rmax:.1}"),
            paper.map_or_else(dash, |p| format!("{:.3}", p.1)),
            paper.map_or_else(dash, |p| format!("{:.3}", p.2)),
            paper.map_or_else(dash, |p| format!("{:.2}", 100.0 * (1.0 - p.2 / p.1))),
        ]);
    }
    let mut body = para(&format!(
        "Table 2 of the paper: peak structure displacement with the whole stack as one sliding \
         block and with the stack, {}. The paper's values are for its record #11 alone; ours are \
         means over the zone's {} motions, with the range of the reduction over the motions.",
        c0.describe(),
        inp.zones[0].motions.len()
    ));
    body += &table_with_id(
        "table2",
        &[
            "zone",
            "single block u_p (m)",
            "stack u_p (m)",
            "reduction (%)",
            "reduction over the motions (%)",
            "paper single block u_p (m)",
            "paper stack u_p (m)",
            "paper reduction (%)",
        ],
        &rows,
    );
    Section::new("table2", "Stack against single block (Table 2)", body)
}

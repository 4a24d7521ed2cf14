//! The design equations: Table 3 next to the paper's, the recommended form's coefficients with
//! their standard errors, and the residuals of every fitted form.

use super::text::{fixed, mean, paper_equation_name, sig};
use super::{Files, Inputs, ReportError, Zone};
use crate::fit::{Form, Metrics, Sample};
use crate::grid::Grid;
use crate::render::chart::{Axis, Figure, Mark, PALETTE, Panel, Series, Stroke};
use crate::render::page::{Section, para, table_with_id};
use crate::store::fit::FormFit;
use crate::study::building::{fit_features, repeats};
use crate::study::cases::PAPER_TABLE_3;
use crate::study::tnew::{building_samples, samples};
use plotters::style::RGBColor;

pub(super) fn fit_section(inp: &Inputs, files: &mut Files) -> Result<Section, ReportError> {
    let building = inp.study.building().is_some();
    let mut body = para(&if building {
        format!(
            "The design equation for T_new of the first mode, fitted over every case of the \
             study's distinct frames with the building's features ({}; docs/fit.md, \"A study \
             over buildings\"): the paper's Eqs. 16–17 as printed with T_p = T_1, and each form \
             fitted here (5-fold cross-validated columns from fits that did not see the \
             predicted cases).",
            inp.fit().features.join(", ")
        )
    } else {
        format!(
            "Table 3 of the paper next to ours: the paper's fit quality of its Eqs. 16–17, those \
             equations as printed evaluated on our T_new, and each form fitted here (features \
             {}; 5-fold cross-validated columns from fits that did not see the predicted \
             cases).",
            inp.fit().features.join(", ")
        )
    });
    let table3: Vec<Vec<String>> = (inp.zones.iter())
        .flat_map(|z| table3_rows(z, !building))
        .collect();
    body += &table_with_id(
        "table3",
        &[
            "zone",
            "equation",
            "R²",
            "R",
            "RMSE (s)",
            "MSE (s²)",
            "MAE (s)",
            "5-fold CV R²",
            "5-fold CV RMSE (s)",
        ],
        &table3,
    );
    for z in &inp.zones {
        if let Some(ff) = z.fit().recommended_fit() {
            body += &coefficients(z, ff, "T_new's recommended");
        }
    }
    if building {
        body += &frames_table(inp);
        for z in &inp.zones {
            if let Some(ff) = &z.fit().lambda {
                body += &coefficients(z, ff, "λ's");
            }
        }
    }
    body += &para(&format!(
        "Residuals (computed − predicted T_new) of every fitted form against T_p{}, the \
         recommended one first; each case coloured by its T_new band category (the categories \
         side by side within each T_p column), with the mean and the 5th/95th percentiles per \
         T_p.",
        if building {
            " (the bare building's T_1; every case of the distinct frames)"
        } else {
            ""
        }
    ));
    for z in &inp.zones {
        body += &residuals(z, inp, files)?;
    }
    let title = if building {
        "Design equations over the buildings"
    } else {
        "Design equations (Table 3)"
    };
    Ok(Section::new("fit", title, body))
}

/// The building equations frame by frame: `T_new`'s (the recommended form with the building's
/// features), the one-storey equation's and the paper's there, and `λ`'s.
fn frames_table(inp: &Inputs) -> String {
    let f3 =
        |m: Option<&Metrics>, v: fn(&Metrics) -> f64| m.map_or("–".into(), |m| fixed(v(m), 3));
    // fit.yaml lists every frame; one that repeats an earlier one's building is shown once.
    let distinct: Vec<String> = (inp.study.shape.distinct().iter())
        .map(|(_, f)| f.to_string())
        .collect();
    let mut rows = Vec::new();
    for z in &inp.zones {
        for f in z
            .fit()
            .frames
            .iter()
            .filter(|f| distinct.contains(&f.frame))
        {
            rows.push(vec![
                z.name.clone(),
                f.frame.clone(),
                f.cases.to_string(),
                f3(Some(&f.building), |m| m.r2),
                f3(Some(&f.building), |m| m.rmse),
                f3(f.one_storey.as_ref(), |m| m.r2),
                f3(f.one_storey.as_ref(), |m| m.rmse),
                f3(f.published.as_ref(), |m| m.r2),
                f3(f.lambda.as_ref(), |m| m.r2),
                f3(f.lambda.as_ref(), |m| m.rmse),
            ]);
        }
    }
    if rows.is_empty() {
        return String::new();
    }
    para(
        "Frame by frame: the building equation for T_new (the recommended form above, fitted \
         over every frame) beside the one-storey equation (every form fitted to the study's \
         one-storey frame with the one-storey features and recommended as on one storey, read at \
         T_p = T_1), which holds where the first mode dominates and fails where the stack \
         changes the building's higher modes, and the paper's equation as printed; then λ's \
         fitted fraction equation (fit.yaml, zones[].frames).",
    ) + &table_with_id(
        "frames",
        &[
            "zone",
            "frame",
            "cases",
            "building equation R²",
            "building equation RMSE (s)",
            "one-storey equation R²",
            "one-storey equation RMSE (s)",
            "paper's equation R²",
            "λ equation R²",
            "λ equation RMSE",
        ],
        &rows,
    )
}

/// A zone's rows of Table 3: the paper's (`paper`: on one storey), its equation on our
/// `T_new`, each fitted form.
fn table3_rows(z: &Zone, paper: bool) -> Vec<Vec<String>> {
    let f3 = |v: f64| fixed(v, 3);
    let zf = z.fit();
    let mut rows = Vec::new();
    if let Some((_, p)) = (PAPER_TABLE_3.iter())
        .find(|p| p.0 == z.name)
        .filter(|_| paper)
    {
        let mut row = vec![z.name.clone(), "paper Table 3".into()];
        row.extend(p.iter().map(|&v| f3(v)));
        row.extend(["–".to_string(), "–".to_string()]);
        rows.push(row);
    }
    if let Some(m) = &zf.published {
        rows.push(vec![
            z.name.clone(),
            format!(
                "paper's equation ({}) as printed, on our T_new",
                paper_equation_name(&z.name)
            ),
            f3(m.r2),
            f3(m.r),
            f3(m.rmse),
            f3(m.mse),
            f3(m.mae),
            "–".into(),
            "–".into(),
        ]);
    }
    for ff in &zf.forms {
        let (m, cv) = (&ff.all_cases, &ff.cross_validated);
        let rec = if ff.form == zf.recommended {
            ", recommended"
        } else {
            ""
        };
        rows.push(vec![
            z.name.clone(),
            format!("{} form, fitted here{rec}", ff.form.name()),
            f3(m.r2),
            f3(m.r),
            f3(m.rmse),
            f3(m.mse),
            f3(m.mae),
            f3(cv.r2),
            f3(cv.rmse),
        ]);
    }
    rows
}

/// A fitted form's coefficients with their standard errors (`what`: `T_new's recommended`).
fn coefficients(z: &Zone, ff: &FormFit, what: &str) -> String {
    let rows: Vec<Vec<String>> = ff
        .coefficients
        .iter()
        .enumerate()
        .map(|(i, (name, v))| {
            let se = ff.standard_errors.get(i).copied().unwrap_or(f64::NAN);
            vec![
                name.clone(),
                sig(*v, 6),
                if se.is_finite() {
                    sig(se, 3)
                } else {
                    "not estimated".into()
                },
                if se.is_finite() && *v != 0.0 {
                    format!("{:.1}", 100.0 * se / v.abs())
                } else {
                    "–".into()
                },
            ]
        })
        .collect();
    let (id, cases) = match ff.form {
        Form::Fraction => (format!("lambda_coefficients_{}", z.name), "cases with a λ"),
        _ => (format!("coefficients_{}", z.name), "cases"),
    };
    para(&format!(
        "Zone {}: coefficients of {what} {} form (fitted to {} {cases}).",
        z.name,
        ff.form.name(),
        ff.all_cases.n
    )) + &table_with_id(
        &id,
        &[
            "coefficient",
            "value",
            "standard error",
            "standard error / |value| (%)",
        ],
        &rows,
    )
}

/// The fit's samples of a zone with each one's `T_new` band code: every case with a `T_new`,
/// in a study of several frames those of its distinct frames with the building's features
/// (as the fit stage takes them).
fn fitted_samples(z: &Zone, inp: &Inputs) -> (Vec<Sample>, Vec<u8>) {
    let (grid, v) = (inp.grid, &z.tnew.vars);
    let tn: Vec<f64> = v.t_new.iter().copied().collect();
    let tr: Vec<f64> = v.t_rigid.iter().copied().collect();
    let band: Vec<u8> = v.band.iter().copied().collect();
    let with_t_new = (0..tn.len()).filter(|&c| tn[c].is_finite());
    let frames = inp.study.frames();
    match fit_features(grid.blocks(), frames) {
        None => (
            samples(grid, &tr, &tn),
            with_t_new.map(|c| band[c]).collect(),
        ),
        Some(features) => {
            let repeated = repeats(frames);
            let every = building_samples(grid, frames, features, &tr, &tn);
            (every.into_iter().zip(with_t_new))
                .filter(|((f, _), _)| !repeated[*f])
                .map(|((_, s), c)| (s, band[c]))
                .unzip()
        }
    }
}

/// A zone's figure of the residuals of every fitted form, the recommended one first.
fn residuals(z: &Zone, inp: &Inputs, files: &mut Files) -> Result<String, ReportError> {
    let grid = inp.grid;
    let building = inp.study.building().is_some();
    let (data, bands) = fitted_samples(z, inp);
    let mut forms: Vec<_> = z.fit().forms.iter().collect();
    forms.sort_by_key(|f| f.form != z.fit().recommended);
    let panels: Vec<Panel> = forms
        .into_iter()
        .map(|ff| residual_panel(z, ff, grid, &data, &bands, building))
        .collect();
    let cols = panels.len().min(2);
    let fig = Figure::grid(
        format!(
            "Zone {}: residuals of the design equations for T_new{}",
            z.name,
            if building { ", every frame" } else { "" }
        ),
        panels,
        cols,
    )
    .panel_px(460, 340);
    files.figure(
        &format!("residuals_{}.svg", z.name),
        &fig,
        &format!(
            "Zone {}: computed − predicted T_new against T_p for every fitted form, the \
             recommended ({}) first.",
            z.name,
            z.fit().recommended.name()
        ),
    )
}

/// One form's residuals against `T_p` over the cases `data` (band codes `bands`): the cases by
/// band, side by side within each `T_p` column so none hides another, with the mean and the
/// 5th/95th percentiles per `T_p`.
fn residual_panel(
    z: &Zone,
    ff: &FormFit,
    grid: &Grid,
    data: &[Sample],
    bands: &[u8],
    building: bool,
) -> Panel {
    let f = ff.fitted();
    let resid: Vec<f64> = data.iter().map(|s| s.t_new_s - f.predict(s)).collect();
    let mut series = Vec::new();
    let present: Vec<&(u8, String)> = z
        .band_flags
        .iter()
        .filter(|(code, _)| bands.contains(code))
        .collect();
    let step = grid
        .periods_s
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    let step = if step.is_finite() { step } else { 0.1 };
    let dodge = 0.6 * step / present.len().max(1) as f64;
    for (k, (code, word)) in present.iter().enumerate() {
        let shift = (k as f64 - (present.len() - 1) as f64 / 2.0) * dodge;
        let (xs, ys): (Vec<f64>, Vec<f64>) = data
            .iter()
            .zip(&resid)
            .zip(bands)
            .filter(|(_, b)| *b == code)
            .map(|((s, r), _)| (s.t_p_s() + shift, *r))
            .unzip();
        series.push(
            Series::points(word.clone(), xs, ys)
                .mark(Mark::Points {
                    radius: 2,
                    opacity: 0.45,
                })
                .colour(PALETTE[*code as usize % PALETTE.len()]),
        );
    }
    let (mut m, mut lo, mut hi) = (Vec::new(), Vec::new(), Vec::new());
    for &t in &grid.periods_s {
        let mut r: Vec<f64> = data
            .iter()
            .zip(&resid)
            .filter(|(s, _)| s.t_p_s() == t)
            .map(|(_, r)| *r)
            .collect();
        r.sort_by(f64::total_cmp);
        let q = |p: f64| {
            r.get(((r.len() as f64 - 1.0) * p).round() as usize)
                .copied()
                .unwrap_or(f64::NAN)
        };
        m.push(mean(r.iter().copied()));
        lo.push(q(0.05));
        hi.push(q(0.95));
    }
    let black = RGBColor(0, 0, 0);
    series.push(
        Series::line("mean per T_p", grid.periods_s.clone(), m)
            .colour(black)
            .stroke(Stroke::Solid, 2),
    );
    series.push(
        Series::line("5th / 95th percentile per T_p", grid.periods_s.clone(), lo)
            .colour(black)
            .stroke(Stroke::Dashed, 1),
    );
    series.push(
        Series::line("5th / 95th percentile per T_p", grid.periods_s.clone(), hi)
            .colour(black)
            .stroke(Stroke::Dashed, 1),
    );
    let metrics = &ff.all_cases;
    Panel::xy(
        format!(
            "{} form{}: RMSE {:.3} s, R² {:.3}",
            ff.form.name(),
            if ff.form == z.fit().recommended {
                " (recommended)"
            } else {
                ""
            },
            metrics.rmse,
            metrics.r2
        ),
        Axis::new(if building { "T_1 (s)" } else { "T_p (s)" }),
        Axis::new("computed − predicted T_new (s)"),
        series,
    )
}

//! Figures (SVG, with plotters) and the HTML page of the report. Knows nothing of how the
//! numbers were computed: every function takes plain series and returns text.

use plotters::prelude::*;

/// One curve or point set of a chart.
#[derive(Debug, Clone)]
pub struct Series {
    pub label: String,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    /// Drawn as points instead of a line.
    pub points: bool,
    /// Thin grey line without a legend entry (e.g. individual motions behind their mean).
    pub faint: bool,
}

impl Series {
    pub fn line(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self {
            label: label.into(),
            x,
            y,
            points: false,
            faint: false,
        }
    }
    pub fn points(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self {
            points: true,
            ..Self::line(label, x, y)
        }
    }
    pub fn faint(x: Vec<f64>, y: Vec<f64>) -> Self {
        Self {
            faint: true,
            ..Self::line("", x, y)
        }
    }
}

const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

fn range(series: &[Series], pick: impl Fn(&Series) -> &Vec<f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in series
        .iter()
        .flat_map(|s| pick(s).iter())
        .filter(|v| v.is_finite())
    {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = 0.04 * (hi - lo).max(1e-12);
    (lo - pad, hi + pad)
}

/// A line/point chart as an SVG document.
pub fn chart(title: &str, x_label: &str, y_label: &str, series: &[Series]) -> String {
    draw_chart(title, x_label, y_label, series, false)
}

/// [`chart`] with logarithmic axes; values ≤ 0 are left out.
pub fn chart_log_log(title: &str, x_label: &str, y_label: &str, series: &[Series]) -> String {
    let log = |v: &[f64]| -> Vec<f64> {
        v.iter()
            .map(|x| if *x > 0.0 { x.log10() } else { f64::NAN })
            .collect()
    };
    let logged: Vec<Series> = series
        .iter()
        .map(|s| Series {
            x: log(&s.x),
            y: log(&s.y),
            ..s.clone()
        })
        .collect();
    draw_chart(title, x_label, y_label, &logged, true)
}

/// Tick label of a log10 axis value: `1e-3`, or the value itself near 1.
fn power_label(v: &f64) -> String {
    if (v - v.round()).abs() > 1e-9 {
        return String::new();
    }
    match v.round() as i32 {
        0 => "1".to_string(),
        1 => "10".to_string(),
        e => format!("1e{e}"),
    }
}

fn draw_chart(title: &str, x_label: &str, y_label: &str, series: &[Series], log: bool) -> String {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (640, 420)).into_drawing_area();
        let draw = || -> Result<(), Box<dyn std::error::Error + '_>> {
            root.fill(&WHITE)?;
            let (x0, x1) = range(series, |s| &s.x);
            let (y0, y1) = range(series, |s| &s.y);
            let mut c = ChartBuilder::on(&root)
                .caption(title, ("sans-serif", 18))
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(60)
                .build_cartesian_2d(x0..x1, y0..y1)?;
            let mut mesh = c.configure_mesh();
            mesh.x_desc(x_label)
                .y_desc(y_label)
                .light_line_style(RGBColor(235, 235, 235));
            if log {
                let ticks = |a: f64, b: f64| ((b.floor() - a.ceil()) as usize + 1).clamp(2, 12);
                mesh.x_labels(ticks(x0, x1) * 4)
                    .y_labels(ticks(y0, y1) * 4)
                    .x_label_formatter(&power_label)
                    .y_label_formatter(&power_label);
            }
            mesh.draw()?;
            let mut colour = 0;
            for s in series {
                let pts: Vec<(f64, f64)> =
                    s.x.iter()
                        .zip(&s.y)
                        .filter(|(x, y)| x.is_finite() && y.is_finite())
                        .map(|(x, y)| (*x, *y))
                        .collect();
                if s.faint {
                    c.draw_series(LineSeries::new(pts, RGBColor(200, 200, 200)))?;
                    continue;
                }
                let col = COLOURS[colour % COLOURS.len()];
                colour += 1;
                let drawn = if s.points {
                    c.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, col.filled())))?
                } else {
                    c.draw_series(LineSeries::new(pts, col.stroke_width(2)))?
                };
                drawn
                    .label(s.label.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], col));
            }
            if series.iter().any(|s| !s.faint && !s.label.is_empty()) {
                c.configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .draw()?;
            }
            root.present()?;
            Ok(())
        };
        if let Err(e) = draw() {
            return format!("<svg xmlns='http://www.w3.org/2000/svg'><text>{e}</text></svg>");
        }
    }
    svg
}

/// A table as HTML: header cells and rows of already formatted cells.
pub fn table(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut s = String::from("<table><tr>");
    for h in header {
        s += &format!("<th>{}</th>", escape(h));
    }
    s += "</tr>";
    for r in rows {
        s += "<tr>";
        for c in r {
            s += &format!("<td>{}</td>", escape(c));
        }
        s += "</tr>";
    }
    s + "</table>"
}

/// A number for tables: `0`, or two significant digits in scientific notation (`1.5e-13`).
pub fn sci(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else {
        format!("{x:.1e}")
    }
}

pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The page: a title, then sections of (heading, HTML body).
pub fn page(title: &str, sections: &[(String, String)]) -> String {
    let mut s = format!(
        "<!doctype html><html><head><meta charset='utf-8'><title>{t}</title><style>\
         body{{font-family:sans-serif;max-width:1000px;margin:2em auto;line-height:1.4}}\
         table{{border-collapse:collapse;margin:1em 0}}td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}}\
         img{{max-width:100%}}</style></head><body><h1>{t}</h1>",
        t = escape(title)
    );
    for (h, body) in sections {
        s += &format!("<h2>{}</h2>{body}", escape(h));
    }
    s + "</body></html>\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chart_is_an_svg_with_its_labels() {
        let svg = chart(
            "Spectra",
            "T (s)",
            "PSA (g)",
            &[
                Series::line("target", vec![0.1, 1.0], vec![0.4, 0.16]),
                Series::faint(vec![0.1, 1.0], vec![0.3, 0.2]),
            ],
        );
        assert!(svg.starts_with("<svg"));
        assert!(svg.contains("Spectra") && svg.contains("target") && svg.contains("PSA (g)"));
        let t = table(&["a", "b"], &[vec!["1".into(), "<2>".into()]]);
        assert_eq!(
            t,
            "<table><tr><th>a</th><th>b</th></tr><tr><td>1</td><td>&lt;2&gt;</td></tr></table>"
        );
    }
}

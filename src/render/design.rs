//! The design page of a report (`design.html`): a form asking for one structure (zone, `T_p`,
//! the stack's mass ratios and friction coefficients), the answers `slidestack design` gives,
//! computed in the page by its script (`design.js`) from the study's data embedded as JSON, the
//! case drawn on the `T_new`–`T_p` figure and on the spectrum, and an explorer of the grid's
//! figures. Self-contained: no request leaves the page, so it works from `file://` and from any
//! static host.

use super::page::escape;

const SCRIPT: &str = include_str!("design.js");

const STYLE: &str = "body{font-family:sans-serif;max-width:1100px;margin:1em auto;padding:0 1em;\
line-height:1.4}fieldset{border:1px solid #ccc;margin:0 0 1em;padding:.5em 1em}\
.inputs{display:grid;grid-template-columns:repeat(auto-fill,minmax(11em,1fr));gap:.6em 1em}\
label{display:block;font-weight:bold;font-size:95%}input,select{font-size:1rem;padding:.3em;\
width:100%;box-sizing:border-box}input[type=checkbox]{width:auto;margin-right:.4em}\
.check label{display:inline;font-weight:normal}table{border-collapse:collapse;margin:1em 0}\
td,th{border:1px solid #ccc;padding:4px 10px;text-align:right}th{background:#f4f4f4}\
td:first-child,th:first-child{text-align:left}output{font-variant-numeric:tabular-nums}\
#error{color:#a00;font-weight:bold}.figs{display:grid;grid-template-columns:repeat(auto-fit,\
minmax(300px,1fr));gap:1em}figure{margin:0}svg{width:100%;height:auto;font-size:15px}\
svg .grid{stroke:#e4e4e4}svg .frame{fill:none;stroke:#888}svg .title{font-weight:bold}\
ul.legend{list-style:none;padding:0;margin:.3em 0;font-size:90%}ul.legend li{display:inline-block;\
margin-right:1.2em}.key{display:inline-block;width:2em;border-top-width:3px;vertical-align:middle;\
margin-right:.4em}.key.dot{width:.7em;height:.7em;border-width:3px;border-radius:50%}\
#fig-explorer{max-width:800px}a:focus,input:focus,select:focus{outline:3px solid #f90}code{overflow-wrap:anywhere}\
@media(max-width:600px){td,th{padding:3px 5px}}";

/// One row of the answers' table: a label, the `id` of its output (the JSON key of
/// `slidestack design --json`) and its unit.
type Row = (&'static str, &'static str, &'static str);

const OUTPUT_ROWS: [Row; 6] = [
    ("T_rigid: stack rigidly attached", "t_rigid_s", "s"),
    (
        "T_new: the study's grid (interpolated)",
        "t_new_grid_s",
        "s",
    ),
    ("T_new: the fitted design equation", "t_new_fit_s", "s"),
    ("T_new: the paper's Eqs. 16–17", "t_new_paper_s", "s"),
    ("Design Sa at T_p", "sa_tp_g", "g"),
    ("Design Sa at T_new (grid, else fit)", "sa_new_g", "g"),
];

/// A building study's rows: `T_1`, `T_1,rigid` and the fraction `λ`.
const BUILDING_ROWS: [Row; 9] = [
    (
        "T_1,rigid: stack rigidly attached to its floor(s)",
        "t_rigid_s",
        "s",
    ),
    (
        "T_new: the frame's cases (interpolated)",
        "t_new_grid_s",
        "s",
    ),
    ("T_new: the fitted building equation", "t_new_fit_s", "s"),
    (
        "T_new: the paper's Eqs. 16–17 (one storey, at T_1)",
        "t_new_paper_s",
        "s",
    ),
    ("Design Sa at T_1", "sa_tp_g", "g"),
    ("Design Sa at T_new (grid, else fit)", "sa_new_g", "g"),
    (
        "λ, effective live-load fraction: the frame's cases (interpolated)",
        "lambda_grid",
        "",
    ),
    ("λ: the fitted fraction equation", "lambda_fit", ""),
    (
        "λ_code, the fraction to count as seismic weight: the frame's cases",
        "lambda_code_grid",
        "",
    ),
];

/// The row of a study that checks whether its stacks rock (`grid.aspect`).
const ROCKS_ROW: Row = (
    "Share of the motions under which the stack would rock (interpolated; where above 0 the \
     sliding-only model's answers are outside their model)",
    "rocks_share",
    "",
);

/// The answers' rows of a study's page (`building`: a building study's; `rocking`: a study that
/// checks whether its stacks rock).
fn output_rows(building: bool, rocking: bool) -> Vec<Row> {
    let mut rows = if building {
        BUILDING_ROWS.to_vec()
    } else {
        OUTPUT_ROWS.to_vec()
    };
    if rocking {
        rows.push(ROCKS_ROW);
    }
    rows
}

/// The ids of the page's numeric outputs, each the JSON key of `slidestack design --json` that
/// it shows (`building`, `rocking`: as [`PageForm`]); the page's script finds them by their
/// class.
pub fn output_ids(building: bool, rocking: bool) -> Vec<&'static str> {
    output_rows(building, rocking).iter().map(|r| r.1).collect()
}

/// What a study's page asks and answers: its zones, its stacks' `blocks` blocks, the input
/// hints (`ranges`: `T_p`, then each `α`, then each `μ`), a building study's storey and floor
/// inputs, and whether the study checks that its stacks rock (the `rocks_share` row).
pub struct PageForm<'a> {
    pub zones: &'a [String],
    pub blocks: usize,
    pub ranges: &'a [String],
    pub building: Option<&'a FrameInputs>,
    pub rocking: bool,
}

/// A building study's inputs: the storey counts and floors its selects offer, and its
/// distinct frames (`3 storeys, stack on the roof`) for the explorer, in stored order.
pub struct FrameInputs {
    pub storeys: Vec<usize>,
    /// `1` … `N_max`, `roof`, `mid`, `all`.
    pub floors: Vec<String>,
    pub frames: Vec<String>,
}

fn select(id: &str, label: &str, options: &[String]) -> String {
    let options: String = options
        .iter()
        .map(|o| format!("<option value='{0}'>{0}</option>", escape(o)))
        .collect();
    format!(
        "<div><label for='{id}'>{}</label><select id='{id}' name='{id}'>{options}</select></div>",
        escape(label)
    )
}

fn input(id: &str, label: &str, hint: &str) -> String {
    format!(
        "<div><label for='{id}'>{}</label><input id='{id}' name='{id}' type='number' step='any' \
         min='0' inputmode='decimal' aria-describedby='{id}-hint' required='required'/>\
         <small id='{id}-hint'>{}</small></div>",
        escape(label),
        escape(hint)
    )
}

/// The page of a study asking and answering as `form` says: `title`, an introduction (HTML)
/// and `data`, the JSON the script reads (`zones`: each zone's `design::ZoneDesign`, in a
/// building study each zone and frame's; `drr`: `DRR_1`, `DRR_2` per case of each;
/// `damping_depth`; a building study's `frames`).
pub fn design_page(title: &str, intro: &str, form: &PageForm, data: &str) -> String {
    let PageForm {
        zones,
        blocks,
        ranges,
        building,
        rocking,
    } = *form;
    let zone_options: String = zones
        .iter()
        .map(|z| format!("<option value='{0}'>{0}</option>", escape(z)))
        .collect();
    let hint = |i: usize| ranges.get(i).map_or("", String::as_str);
    let period = match building {
        None => "T_p: period of the bare structure (s)",
        Some(_) => "T_1: first-mode period of the bare building (s)",
    };
    let mut inputs = format!(
        "<div><label for='zone'>Zone</label><select id='zone' name='zone'>{zone_options}</select>\
         </div>{}",
        input("period", period, hint(0))
    );
    if let Some(b) = building {
        let storeys: Vec<String> = b.storeys.iter().map(usize::to_string).collect();
        inputs += &select("storeys", "N: storeys of the building", &storeys);
        inputs += &select(
            "floor",
            "Floor carrying the stack (N is the roof)",
            &b.floors,
        );
    }
    for i in 1..=blocks {
        inputs += &input(
            &format!("alpha_{i}"),
            &format!("α_{i}: mass ratio of block {i} (m_{i}/m_p)"),
            hint(i),
        );
    }
    for i in 1..=blocks {
        let below = if i == 1 {
            "the structure".to_string()
        } else {
            format!("block {}", i - 1)
        };
        inputs += &input(
            &format!("mu_{i}"),
            &format!("μ_{i}: friction, block {i} on {below}"),
            hint(blocks + i),
        );
    }
    let rows: String = output_rows(building.is_some(), rocking)
        .iter()
        .map(|(label, id, unit)| {
            format!(
                "<tr><th scope='row'>{}</th><td><output id='{id}' class='number'>–</output> \
                 {unit}</td></tr>",
                escape(label)
            )
        })
        .collect();
    let (frame_row, frame_select) = match building {
        None => (String::new(), String::new()),
        Some(b) => {
            let options: String = (b.frames.iter().enumerate())
                .map(|(k, f)| format!("<option value='{k}'>{}</option>", escape(f)))
                .collect();
            (
                "<tr><th scope='row'>Building</th><td><output id='building'>–</output></td></tr>"
                    .to_string(),
                format!(
                    "<div><label for='x-frame'>Building</label><select id='x-frame'>{options}\
                     </select></div>"
                ),
            )
        }
    };
    let alpha_selects: String = (1..=blocks)
        .map(|i| {
            format!(
                "<div><label for='x-alpha_{i}'>α_{i}</label><select id='x-alpha_{i}'>\
                 </select></div>"
            )
        })
        .collect();
    // `</` cannot end the data's script element early (JSON allows `<\/` for `</`).
    let data = data.replace("</", "<\\/");
    format!(
        "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'/>\
         <meta name='viewport' content='width=device-width, initial-scale=1'/>\
         <title>{t}</title><style>{STYLE}</style></head><body>\
         <p><a href='index.html'>← the full report</a></p><h1>{t}</h1>{intro}\
         <main><form id='design' action='#' novalidate='novalidate'><fieldset>\
         <legend>Your structure</legend><div class='inputs'>{inputs}</div>\
         <p class='check'><input id='extrapolate' name='extrapolate' type='checkbox'/>\
         <label for='extrapolate'>Extrapolate outside the study's grid (answers from the fitted \
         form)</label></p></fieldset></form>\
         <p id='error' role='alert' hidden='hidden'></p>\
         <table id='answers' aria-live='polite'><caption>The answers (as <code>slidestack design \
         --json</code> gives them)</caption>{frame_row}{rows}<tr><th scope='row'>Fitted form</th>\
         <td><output id='fit_form'>–</output></td></tr></table><ul id='notes'></ul>\
         <p>A link to this answer: <a id='permalink' href='design.html'>design.html</a></p>\
         <div class='figs'><figure id='fig-case'></figure><figure id='fig-spectrum'></figure>\
         </div>\
         <section aria-labelledby='explorer-h'><h2 id='explorer-h'>Explore the grid (Figs 10–11 \
         and 16–17)</h2><p>Any mass ratios and any friction pairs of the study's grid: the mean \
         over the motions of DRR_1 = u_stack/u_rigid, DRR_2 = u_single/u_rigid, or T_new, \
         against T_p. Select several friction pairs with Ctrl or Shift (or Space on the list).\
         </p><form id='explorer' action='#'><div class='inputs'>\
         <div><label for='x-zone'>Zone</label><select id='x-zone'>{zone_options}</select></div>\
         {frame_select}\
         <div><label for='x-quantity'>Quantity</label><select id='x-quantity'>\
         <option value='T_new'>T_new (Figs 16–17)</option>\
         <option value='DRR_1'>DRR_1, the stack (Figs 10–11)</option>\
         <option value='DRR_2'>DRR_2, a single block (Figs 10–11)</option></select></div>\
         {alpha_selects}<div><label for='x-mu'>Friction pairs</label>\
         <select id='x-mu' multiple='multiple'></select></div></div></form>\
         <figure id='fig-explorer'></figure></section></main>\
         <script type='application/json' id='study-data'>{data}</script>\
         <script>{SCRIPT}</script></body></html>\n",
        t = escape(title),
    )
}

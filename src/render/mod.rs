//! Rendering: figures (SVG, with plotters) and HTML pages from plain series, tables and text,
//! returned as text. Knows nothing of how the numbers were computed (but for the design page's
//! script, which repeats `slidestack design`'s arithmetic in the browser), nor of the report
//! stage (`pipeline::report`) or its files (`store::report`), which use it.
//!
//! * [`mod@chart`]: panels, series, legends outside the plot areas; [`chart::render`] a figure.
//! * [`mod@page`]: tables, figures and sections of an HTML page.
//! * [`mod@design`]: the design page, answering for one structure in the browser.

pub mod chart;
pub mod design;
pub mod page;

pub use chart::{Series, chart, chart_log_log};
pub use page::{escape, page, sci, table};

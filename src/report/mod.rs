//! Figures (SVG, with plotters) and HTML pages of reports. Knows nothing of how the numbers were
//! computed: every function takes plain series, tables and text, and returns text.
//!
//! * [`mod@chart`]: panels, series, legends outside the plot areas; [`chart::render`] a figure.
//! * [`mod@page`]: tables, figures and sections of an HTML page.

pub mod chart;
pub mod page;

pub use chart::{Series, chart, chart_log_log};
pub use page::{escape, page, sci, table};

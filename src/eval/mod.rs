//! Held-out evaluation (`skytie eval`): run a matrix of presets × error profiles × held-out seeds through a
//! workflow, grade every run against the campaign's truth, print one table (mean and worst case per preset and
//! profile) and compare it with a committed baseline, failing when a number got worse beyond its noise band.
//! See docs/evaluation.md.

pub mod baseline;
pub mod grade;
pub mod matrix;
pub mod run_cell;
pub mod table;

pub use baseline::{compare, Baseline, Finding};
pub use grade::{grade_cell, CellMetrics, METRICS};
pub use matrix::{Cell, Matrix};
pub use run_cell::{run_cell, CellRun};
pub use table::{build_table, render_markdown, Table};

//! Plots to SVG, PNG or a self-contained HTML page, chosen by the file extension.
//!
//! A [`Figure`] is a stack of [`Panel`]s sharing the x axis (usually time); each panel holds
//! [`Series`]. Callers describe what to show; this module decides how it looks.

use std::path::Path;

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// A line through the points.
    Line,
    /// Small dots (for dense measured data).
    Points,
}

/// One named data series.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend label.
    pub name: String,
    /// X values.
    pub x: Vec<f64>,
    /// Y values (same length as `x`; NaN points are skipped).
    pub y: Vec<f64>,
    /// Line or points.
    pub style: Style,
}

/// One panel of a figure: a y axis and its series.
#[derive(Clone, Debug)]
pub struct Panel {
    /// Panel title.
    pub title: String,
    /// Y axis label with unit.
    pub y_label: String,
    /// The series drawn in this panel.
    pub series: Vec<Series>,
}

/// A figure: panels stacked vertically sharing one x axis.
#[derive(Clone, Debug)]
pub struct Figure {
    /// Figure title.
    pub title: String,
    /// X axis label with unit.
    pub x_label: String,
    /// The panels, top to bottom.
    pub panels: Vec<Panel>,
}

/// Writes `figure` to `path`; the format follows the extension (`.svg`, `.png`, `.html`).
pub fn write(path: &Path, figure: &Figure) -> anyhow::Result<()> {
    let _ = (path, figure);
    anyhow::bail!("plotting is not implemented yet")
}

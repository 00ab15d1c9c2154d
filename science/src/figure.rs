//! Figures as data: what to show, not how it looks.
//!
//! A [`Figure`] is a stack of [`Panel`]s with one x quantity (usually time), each panel scaled to
//! its own data; each panel holds [`Series`]. The science describes what to show (the fit's
//! predicted acceleration, the diagnosis's simulated velocities); the `propid` command renders it
//! (SVG, PNG, HTML).

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

/// A figure: panels stacked vertically, one x quantity.
#[derive(Clone, Debug)]
pub struct Figure {
    /// Figure title.
    pub title: String,
    /// X axis label with unit.
    pub x_label: String,
    /// The panels, top to bottom.
    pub panels: Vec<Panel>,
}

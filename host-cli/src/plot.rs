//! Plots to SVG, PNG or a self-contained interactive HTML page, chosen by the file extension.
//!
//! A [`Figure`] is a stack of [`Panel`]s with one x quantity (usually time), each panel scaled to
//! its own data; each panel holds [`Series`]. Callers describe what to show; this module decides
//! how it looks.

use std::path::Path;

use anyhow::Context;
use plotters::coord::Shift;
use plotters::prelude::*;

pub use propid_science::figure::{Figure, Panel, Series, Style};

/// Pixel size of one panel.
const PANEL_HEIGHT: u32 = 300;
/// Figure width in pixels.
const WIDTH: u32 = 1200;
/// Largest number of points drawn per series (longer series are decimated by stride).
const MAX_POINTS: usize = 5000;

/// Writes `figure` to `path`; the format follows the extension (`.svg`, `.png`, `.html`).
pub fn write(path: &Path, figure: &Figure) -> anyhow::Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let height = PANEL_HEIGHT * figure.panels.len().max(1) as u32 + 40;
    match ext.as_str() {
        "svg" => {
            let backend = SVGBackend::new(path, (WIDTH, height));
            draw(backend.into_drawing_area(), figure)?;
        }
        "png" => {
            let backend = BitMapBackend::new(path, (WIDTH, height));
            draw(backend.into_drawing_area(), figure)?;
        }
        "html" => {
            let page = crate::html::page(
                &figure.title,
                &[crate::html::figure_section(figure, "figure")],
            );
            std::fs::write(path, page)
                .with_context(|| format!("cannot write {}", path.display()))?;
        }
        other => anyhow::bail!(
            "{}: unknown plot format `{other}` (use .svg, .png or .html)",
            path.display()
        ),
    }
    Ok(())
}

fn range_of<'a>(values: impl Iterator<Item = &'a f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &v in values {
        if v.is_finite() {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        lo.abs().max(1.0) * 0.05
    };
    (lo - pad, hi + pad)
}

const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, figure: &Figure) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow::anyhow!("plot: {e:?}");
    root.fill(&WHITE).map_err(err)?;
    let root = root
        .titled(&figure.title, ("sans-serif", 24))
        .map_err(err)?;
    let panels = root.split_evenly((figure.panels.len().max(1), 1));
    for (area, panel) in panels.iter().zip(&figure.panels) {
        // Each panel spans its own data: a held-out window is not squeezed into the whole run.
        let (x0, x1) = range_of(panel.series.iter().flat_map(|s| s.x.iter()));
        let (y0, y1) = range_of(panel.series.iter().flat_map(|s| s.y.iter()));
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, ("sans-serif", 16))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(figure.x_label.as_str())
            .y_desc(panel.y_label.as_str())
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(err)?;
        for (k, series) in panel.series.iter().enumerate() {
            let color = PALETTE[k % PALETTE.len()];
            let stride = series.x.len().div_ceil(MAX_POINTS).max(1);
            let points = series
                .x
                .iter()
                .zip(&series.y)
                .step_by(stride)
                .filter(|(x, y)| x.is_finite() && y.is_finite())
                .map(|(x, y)| (*x, *y));
            match series.style {
                Style::Line => chart
                    .draw_series(LineSeries::new(points, color.stroke_width(1)))
                    .map_err(err)?
                    .label(series.name.as_str())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color)),
                Style::Points => chart
                    .draw_series(points.map(|p| Circle::new(p, 1, color.filled())))
                    .map_err(err)?
                    .label(series.name.as_str())
                    .legend(move |(x, y)| Circle::new((x + 8, y), 3, color.filled())),
            };
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn figure() -> Figure {
        let x: Vec<f64> = (0..200).map(|i| i as f64 * 0.01).collect();
        Figure {
            title: "test <figure>".into(),
            x_label: "t [s]".into(),
            panels: vec![Panel {
                title: "sine".into(),
                y_label: "y".into(),
                series: vec![
                    Series {
                        name: "sin".into(),
                        y: x.iter().map(|t| t.sin()).collect(),
                        x: x.clone(),
                        style: Style::Line,
                    },
                    Series {
                        name: "pts".into(),
                        y: x.iter().map(|t| t.cos()).collect(),
                        x,
                        style: Style::Points,
                    },
                ],
            }],
        }
    }

    #[test]
    fn writes_svg_png_and_html() {
        let dir = tempfile::tempdir().unwrap();
        for ext in ["svg", "png", "html"] {
            let p = dir.path().join(format!("f.{ext}"));
            write(&p, &figure()).unwrap();
            let bytes = std::fs::read(&p).unwrap();
            assert!(bytes.len() > 1000, "{ext} too small");
            if ext != "png" {
                let text = String::from_utf8(bytes).unwrap();
                let drawn = if ext == "svg" { "<svg" } else { "uPlot" };
                assert!(text.contains(drawn) && text.contains("sin"), "{ext}");
            } else {
                assert_eq!(&bytes[1..4], b"PNG");
            }
        }
        let err = write(&dir.path().join("f.jpg"), &figure()).unwrap_err();
        assert!(err.to_string().contains("unknown plot format"));
    }
}

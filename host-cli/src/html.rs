//! Self-contained HTML: interactive, zoomable plots (uPlot, embedded) and report pages that open
//! offline from a single file.
//!
//! ```text
//!  science::figure::Figure ─► figure_section(): one uPlot chart per panel, data as inline JSON
//!  sections (tables, text, charts) ─► page(): one HTML file with uPlot's JS and CSS embedded
//! ```
//! uPlot draws series that share an x axis; the panels of a [`Figure`] may hold series sampled at
//! different x (a held-out window beside the whole run), so each panel's x values are merged and
//! a series is `null` where it has no point (drawn as a gap).

use std::fmt::Write as _;

use propid_science::figure::{Figure, Series, Style};

/// uPlot's minified script (MIT, see `assets/uplot/LICENSE`).
const UPLOT_JS: &str = include_str!("../assets/uplot/uPlot.iife.min.js");
/// uPlot's stylesheet.
const UPLOT_CSS: &str = include_str!("../assets/uplot/uPlot.min.css");
/// The pages' own style.
const PAGE_CSS: &str = include_str!("../assets/page/page.css");
/// The helper that draws one chart of a page.
const CHART_JS: &str = include_str!("../assets/page/chart.js");

/// Largest number of points kept per series (longer series are decimated by stride).
const MAX_POINTS: usize = 4000;

/// Colours by series index within a panel (the same model gets the same colour in every panel
/// because figures list their series in the same order).
const COLOURS: [&str; 6] = [
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b",
];

/// Escapes text for HTML element content and attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A JSON number, or `null` for NaN and infinities (JSON has neither).
fn json_number(v: f64) -> String {
    if v.is_finite() {
        // Shortest representation that reads back to the same f64.
        format!("{v}")
    } else {
        "null".into()
    }
}

/// JSON for a string inside a `<script>` element: `</` cannot close the element early.
pub fn json_string(s: &str) -> String {
    serde_json::to_string(s)
        .unwrap_or_else(|_| "\"\"".into())
        .replace("</", "<\\/")
}

/// One panel's data in uPlot's column layout: `[[x…], [y1…], [y2…]]`, x merged and sorted.
fn panel_columns(series: &[Series]) -> Vec<Vec<Option<f64>>> {
    let decimated: Vec<Vec<(f64, f64)>> = series
        .iter()
        .map(|s| {
            let n = s.x.len().min(s.y.len());
            let stride = n.div_ceil(MAX_POINTS).max(1);
            (0..n)
                .step_by(stride)
                .map(|i| (s.x[i], s.y[i]))
                .filter(|(x, _)| x.is_finite())
                .collect()
        })
        .collect();
    let mut xs: Vec<f64> = decimated.iter().flatten().map(|(x, _)| *x).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let mut columns = vec![xs.iter().map(|x| Some(*x)).collect::<Vec<_>>()];
    for d in &decimated {
        let mut col = vec![None; xs.len()];
        for (x, y) in d {
            if let Ok(i) = xs.binary_search_by(|v| v.total_cmp(x)) {
                col[i] = y.is_finite().then_some(*y);
            }
        }
        columns.push(col);
    }
    columns
}

/// A section with one interactive chart per panel of `figure`. `id` must be unique in the page.
pub fn figure_section(figure: &Figure, id: &str) -> String {
    let mut html = format!(
        "<section class=\"figure\"><h2>{}</h2>\n",
        escape(&figure.title)
    );
    for (p, panel) in figure.panels.iter().enumerate() {
        let columns = panel_columns(&panel.series);
        let mut data = String::from("[");
        for (c, col) in columns.iter().enumerate() {
            if c > 0 {
                data.push(',');
            }
            data.push('[');
            for (i, v) in col.iter().enumerate() {
                if i > 0 {
                    data.push(',');
                }
                data.push_str(&v.map_or("null".into(), json_number));
            }
            data.push(']');
        }
        data.push(']');
        let mut series = format!("[{{label:{}}}", json_string(&figure.x_label));
        for (k, s) in panel.series.iter().enumerate() {
            let colour = COLOURS[k % COLOURS.len()];
            let style = match s.style {
                Style::Line => format!("stroke:\"{colour}\",width:1.5,spanGaps:false"),
                Style::Points => format!(
                    "stroke:\"{colour}\",width:0,paths:()=>null,points:{{show:true,size:3,fill:\"{colour}\"}}"
                ),
            };
            let _ = write!(series, ",{{label:{},{style}}}", json_string(&s.name));
        }
        series.push(']');
        let chart = format!("{id}-{p}");
        let _ = write!(
            html,
            "<h3>{title}</h3><div class=\"chart\" id=\"{chart}\"></div>\n<script>propidChart({chart_js},{title_js},{y_js},{series},{data});</script>\n",
            title = escape(&panel.title),
            chart_js = json_string(&chart),
            title_js = json_string(&panel.title),
            y_js = json_string(&panel.y_label),
        );
    }
    html.push_str("</section>\n");
    html
}

/// A whole page: `title`, then the sections (already HTML), with uPlot, the chart helper and
/// the style embedded (nothing is fetched: the file opens offline).
pub fn page(title: &str, sections: &[String]) -> String {
    let t = escape(title);
    let mut html = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n\
<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
<title>{t}</title>\n<style>{UPLOT_CSS}\n{PAGE_CSS}</style>\n\
<script>{UPLOT_JS}</script>\n<script>\n{CHART_JS}</script>\n\
</head><body>\n<h1>{t}</h1>\n"
    );
    for s in sections {
        html.push_str(s);
    }
    html.push_str("</body></html>\n");
    html
}

/// An HTML table: a header row and rows of cells (already escaped where needed; numbers are
/// right-aligned when a cell starts with a digit, a sign or a dot).
pub fn table(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut html = String::from("<table><tr>");
    for h in header {
        let _ = write!(html, "<th>{}</th>", escape(h));
    }
    html.push_str("</tr>\n");
    for row in rows {
        html.push_str("<tr>");
        for cell in row {
            let numeric = cell
                .chars()
                .next()
                .is_some_and(|c| c.is_ascii_digit() || c == '-' || c == '+' || c == '.');
            let class = if numeric { " class=\"num\"" } else { "" };
            let _ = write!(html, "<td{class}>{cell}</td>");
        }
        html.push_str("</tr>\n");
    }
    html.push_str("</table>\n");
    html
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_science::figure::Panel;

    #[test]
    fn panels_merge_x_and_mark_gaps() {
        let series = vec![
            Series {
                name: "a".into(),
                x: vec![0.0, 1.0, 2.0],
                y: vec![1.0, f64::NAN, 3.0],
                style: Style::Line,
            },
            Series {
                name: "b".into(),
                x: vec![1.5, 2.0],
                y: vec![5.0, 6.0],
                style: Style::Points,
            },
        ];
        let c = panel_columns(&series);
        assert_eq!(c[0], vec![Some(0.0), Some(1.0), Some(1.5), Some(2.0)]);
        assert_eq!(c[1], vec![Some(1.0), None, None, Some(3.0)]);
        assert_eq!(c[2], vec![None, None, Some(5.0), Some(6.0)]);
    }

    #[test]
    fn page_embeds_uplot_and_escapes_text() {
        let fig = Figure {
            title: "t <x> & \"y\"".into(),
            x_label: "t [s]".into(),
            panels: vec![Panel {
                title: "</script><b>".into(),
                y_label: "y".into(),
                series: vec![Series {
                    name: "s".into(),
                    x: vec![0.0, 1.0],
                    y: vec![2.0, f64::INFINITY],
                    style: Style::Line,
                }],
            }],
        };
        let html = page("report", &[figure_section(&fig, "f")]);
        assert!(html.contains("uPlot"));
        assert!(html.contains("t &lt;x&gt; &amp; &quot;y&quot;"));
        // The panel title reaches the script as a JSON string that cannot close the element.
        assert!(!html.contains("</script><b>"));
        assert!(html.contains("[[0,1],[2,null]]"));
        // Nothing is fetched: no external script or stylesheet.
        assert!(!html.contains("<script src") && !html.contains("<link"));
    }
}

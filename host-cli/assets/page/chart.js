// Draws one chart of a report page with uPlot (embedded before this script): drag to zoom,
// double-click to reset. Each chart's data sits inline in the page as uPlot's columns.
function propidChart(id, title, yLabel, series, data) {
  const el = document.getElementById(id);
  const width = Math.max(400, Math.min(1200, (el.parentElement || document.body).clientWidth || 1000));
  const opts = { width, height: 280, series, scales: { x: { time: false } },
    axes: [{}, { label: yLabel, size: 70 }], cursor: { drag: { x: true, y: false } } };
  el.propidPlot = new uPlot(opts, data, el);
}

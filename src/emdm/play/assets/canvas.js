// Bokeh 3.9 reads every visual property of every glyph from the CSS cascade (a --bk-* variable
// through getComputedStyle) at each paint, though no page defines one, and that read is a third
// of a plot's paint (bokeh/bokeh#15286, open). This page defines no --bk-* variable, so the read
// always falls back to the property itself; it is skipped. If Bokeh changes, nothing is patched.
(function () {
  const visual = window.Bokeh && Bokeh.require && Bokeh.require("core/visuals/visual")
  const base = visual && visual.VisualProperties && visual.VisualProperties.prototype
  if (base && typeof base._get_css_value === "function" && base._get_css_value.length === 1) {
    base._get_css_value = function (_name) { return "" }
  }
})();
// Bokeh 3.9 rewrites the style sheet that places each annotation, axis and title at every
// paint, mostly with the same text; each write made the browser restyle the page at the next
// getComputedStyle (Bokeh reads a plot's font size for every text it measures), which was the
// largest single cost of a plot's paint. A sheet whose text is unchanged is left alone.
(function () {
  const dom = window.Bokeh && Bokeh.require && Bokeh.require("core/dom")
  const sheet = dom && dom.InlineStyleSheet && dom.InlineStyleSheet.prototype
  if (sheet && typeof sheet._update === "function" && sheet._update.length === 1) {
    const update = sheet._update
    sheet._update = function (css) {
      if (this.el.textContent !== css) {
        update.call(this, css)
      }
    }
  }
})();
// When an axis of a plot needs more or less room (its tick labels changed, as the Pareto
// front's do at most changes), Bokeh 3.9 lays out the whole page again (15-25 ms: every widget
// measured, every plot's style rewritten and repainted). A plot of fixed width and height
// cannot move anything around it, so only that plot is laid out again, after the page was laid
// out once.
(function () {
  const canvas = window.Bokeh && Bokeh.require && Bokeh.require("models/plots/plot_canvas")
  const plot = canvas && canvas.PlotView && canvas.PlotView.prototype
  if (!plot || typeof plot._invalidate_layout_if_needed !== "function") {
    return
  }
  const fixed = (view) => {
    const {width_policy, height_policy, width, height} = view.box_sizing()
    return view.root._layout_computed && width != null && height != null &&
      ["auto", "fixed"].includes(width_policy) && ["auto", "fixed"].includes(height_policy)
  }
  function own_layout() {
    this.measure_layout()
    this.update_bbox()
    this._compute_layout()
    this.after_layout()
  }
  const invalidate = plot._invalidate_layout_if_needed
  plot._invalidate_layout_if_needed = function () {
    if (!fixed(this)) {
      return invalidate.call(this)
    }
    this.compute_layout = own_layout
    try {
      return invalidate.call(this)
    } finally {
      delete this.compute_layout
    }
  }
})();

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
})()

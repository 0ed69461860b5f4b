// Show the status the server wrote (source: its html column) in the status box (status, a Div of
// fixed size), in place: a Div's new text re-lays out the whole page (10 ms), and the status
// changes several times a second while the motion plays.
const view = Bokeh.index.find_one(status)
if (view != null && view.markup_el != null) {
  view.markup_el.innerHTML = source.data.html[0]
}

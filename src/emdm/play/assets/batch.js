// Paint a change once. The server opens a batch before the first message of a change and closes
// it after the last; in between the plots wait, so that the first run, the second run and the
// status are not each painted on their own. A batch of a drag in progress (live) that closes after
// the drag was released is not painted either: the release's own batch follows (live.js sets
// emdm_release_due), and painting both cost a paint of every plot. A batch left open is closed
// after 0.5 s.
// args: figures (the page's plots), hold (true: open the batch, false: close it), batch (the
// marker's data source: its live column says whether the change is a drag in progress).
const views = figures.map((figure) => Bokeh.index.find_one(figure)).filter((v) => v != null)
const release = () => {
  clearTimeout(window.emdm_batch)
  window.emdm_batch = null
  window.emdm_release_due = false
  for (const view of views) {
    view.unpause()
  }
  window.dispatchEvent(new Event("emdm-batch-closed"))  // the latency benchmark waits for it
}
if (hold && window.emdm_batch == null) {
  for (const view of views) {
    view.pause()
  }
  window.emdm_batch = setTimeout(release, 500)
} else if (!hold && window.emdm_batch != null && !(batch.data.live[0] && window.emdm_release_due)) {
  release()
}

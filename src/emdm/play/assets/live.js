// Follow a drag: while the goal moves under the hand, send where it is to the server every
// `interval` ms, from `delay` ms after the drag began, so both runs are recomputed and drawn as
// the hand moves (a quick flick is only its release: a change computed for its middle would
// delay the release's). The drag tool itself sends the release, which replays the motion from
// the start.
// args: goal (the dragged data source), live (where the position goes), interval, delay (ms).
if (window.emdm_live == null) {
  window.emdm_live = {sent: -Infinity, began: 0, timer: null}
  const state = window.emdm_live
  const watch = (source, what) => {
    const where = () => [Array.from(source.data.x ?? []), Array.from(source.data.y ?? [])]
    let known = JSON.stringify(where())  // the position the server set or was last sent
    let dragging = false
    // a whole new value (the server's, or the drag tool's release) is not a drag step
    source.properties.data.change.connect(() => {
      known = JSON.stringify(where())
      // the drag tool's release after a position was sent: the release's change follows the
      // drag's (batch.js paints only the release's); the server never sets the goal mid-drag
      window.emdm_release_due = dragging && state.sent > state.began + delay - interval
      dragging = false
      clearTimeout(state.timer)
      state.timer = null
    })
    source.change.connect(() => {  // a drag step: the tool moved the point in place
      if (JSON.stringify(where()) === known) {
        return
      }
      if (!dragging) {  // the drag's first step: its first position goes `delay` ms later
        dragging = true
        state.began = performance.now()
        state.sent = state.began + delay - interval
      }
      const send = () => {
        state.timer = null
        const [x, y] = where()
        const now = JSON.stringify([x, y])
        if (now === known) {
          return
        }
        known = now
        state.sent = performance.now()
        live.data = {what: x.map(() => what), x, y}
      }
      const wait = interval - (performance.now() - state.sent)
      if (wait <= 0) {
        send()
      } else if (state.timer == null) {
        state.timer = setTimeout(send, wait)
      }
    })
  }
  watch(goal, "goal")
}

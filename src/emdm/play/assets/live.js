// Follow a drag: while the goal moves under the hand, send where it is to the server every
// `interval` ms at most, from `delay` ms after the drag began, so both runs are recomputed and
// drawn as the hand moves (a quick flick is only its release: a change computed for its middle
// would delay the release's). One position is in flight at a time: the next goes when the page
// has applied the last (apply.js calls emdm_live.next) or after 0.5 s, so a slow change never
// queues others behind it, and the newest position is the one sent. The drag tool itself sends
// the release, which replays the motion from the start.
// args: goal (the dragged data source), live (where the position goes), interval, delay (ms).
if (window.emdm_live == null) {
  window.emdm_live = {sent: -Infinity, began: 0, timer: null, inflight: false, next: () => {}}
  const state = window.emdm_live
  const where = () => [Array.from(goal.data.x ?? []), Array.from(goal.data.y ?? [])]
  let known = JSON.stringify(where())  // the position the server set or was last sent
  let dragging = false
  const send = () => {
    clearTimeout(state.timer)
    state.timer = null
    if (!dragging) {
      return
    }
    const now = performance.now()
    const wait = Math.max(
      interval - (now - state.sent),
      state.inflight ? 500 - (now - state.sent) : 0,
    )
    if (wait > 0) {  // too soon, or the last position not yet applied: try again then
      state.timer = setTimeout(send, wait)
      return
    }
    const [x, y] = where()
    const position = JSON.stringify([x, y])
    if (position === known) {
      return
    }
    known = position
    state.sent = now
    state.inflight = true
    live.data = {what: x.map(() => "goal"), x, y}
  }
  state.next = () => {  // the page applied a change of the drag (or skipped it)
    state.inflight = false
    if (state.timer != null) {
      send()
    }
  }
  // a whole new value (the server's, or the drag tool's release) is not a drag step
  goal.properties.data.change.connect(() => {
    known = JSON.stringify(where())
    // the drag tool's release after a position was sent: the release's change follows the
    // drag's (apply.js skips the drag's); the server never sets the goal mid-drag
    window.emdm_release_due = dragging && state.sent > state.began + delay - interval
    dragging = false
    state.inflight = false
    clearTimeout(state.timer)
    state.timer = null
  })
  goal.change.connect(() => {  // a drag step: the tool moved the point in place
    if (JSON.stringify(where()) === known) {
      return
    }
    if (!dragging) {  // the drag's first step: its first position goes `delay` ms later
      dragging = true
      state.began = performance.now()
      state.sent = state.began + delay - interval
      state.inflight = false
    }
    if (state.timer == null) {
      send()
    }
  })
}

// Follow a drag: while the goal moves under the hand, send where it is to the server at most
// every `interval` ms, so both runs are recomputed and drawn as the hand moves. The drag tool
// itself sends the release, which replays the motion from the start.
// args: goal (the dragged data source), live (where the position goes), interval (ms).
if (window.emdm_live == null) {
  window.emdm_live = {sent: -Infinity, timer: null}
  const state = window.emdm_live
  const watch = (source, what) => {
    const where = () => [Array.from(source.data.x ?? []), Array.from(source.data.y ?? [])]
    let known = JSON.stringify(where())  // the position the server set or was last sent
    // a whole new value (the server's, or the drag tool's release) is not a drag step
    source.properties.data.change.connect(() => { known = JSON.stringify(where()) })
    source.change.connect(() => {  // a drag step: the tool moved the point in place
      if (JSON.stringify(where()) === known) {
        return
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

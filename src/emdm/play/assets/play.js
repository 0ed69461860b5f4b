// Play the motion in real time: advance the scrub bar by the elapsed time times the speed.
// args: toggle (Toggle), scrub (Slider), speed (RadioButtonGroup), speeds (its factors),
// interval (ms): the scrubbed time goes to the server (for the status and the Pareto front) at
// most this often and at the last frame; every frame is drawn here without a round trip.
const key = "emdm_play_" + toggle.id
if (window[key] != null) {
  cancelAnimationFrame(window[key])
  window[key] = null
}
if (toggle.active) {
  const dt = scrub.step
  if (scrub.value >= scrub.end - dt / 2) {
    scrub.value = scrub.start
  }
  let t = scrub.value
  let last = performance.now()
  let sent = last
  const tick = (now) => {
    if (!toggle.active) {
      return
    }
    if (Math.abs(scrub.value - t) > dt) {
      t = scrub.value // moved by the user or the server: continue from there
    }
    t = Math.min(scrub.end, t + (now - last) / 1000 * speeds[speed.active])
    last = now
    const shown = Math.min(scrub.end, t)  // between states: frame.js draws in between
    if (shown != scrub.value) {
      const sync = t >= scrub.end || now - sent >= interval
      sent = sync ? now : sent
      scrub.setv({value: shown}, {sync})
    }
    if (t >= scrub.end) {
      toggle.active = false
      return
    }
    window[key] = requestAnimationFrame(tick)
  }
  window[key] = requestAnimationFrame(tick)
}

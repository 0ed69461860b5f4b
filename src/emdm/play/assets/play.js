// Play the motion in real time: advance the scrub bar by the elapsed time times the speed.
// args: toggle (Toggle), scrub (Slider), speed (RadioButtonGroup), speeds (its factors),
// interval (ms): the scrubbed time goes to the server (for the status and the Pareto front) at
// most this often and at the last frame; every frame is drawn here without a round trip, at
// most 30 a second (frame.js draws between states: smooth at any speed, and a page that paints
// its scene at 60 a second while playing answered a drag or a slider 20-40 ms later).
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
  let mine = t  // the last time set here
  let last = performance.now()
  let sent = last
  let drawn = -Infinity
  const tick = (now) => {
    if (!toggle.active) {
      return
    }
    if (scrub.value !== mine) {
      t = mine = scrub.value // moved by the user or the server: continue from there
    }
    t = Math.min(scrub.end, t + (now - last) / 1000 * speeds[speed.active])
    last = now
    const shown = Math.min(scrub.end, t)  // between states: frame.js draws in between
    if (shown != scrub.value && (t >= scrub.end || now - drawn >= 1000 / 30 - 1)) {
      drawn = now
      mine = shown
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

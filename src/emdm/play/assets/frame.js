// Show the state under the scrub bar. Between two states k and k + 1 (t = (k + f) dt) the arm,
// its end-effector ellipse's centre and size are drawn in between (linear in the joint
// positions: at 1 rad/s and dt = 0.05 s a link's length is off by under 0.04 %), so any
// playback speed is smooth; the joint states, the ellipse's angle and the step's program are
// those of the nearest state.
// args: scrub (Slider, value = t in s, step = dt), runs ([{points, steps, arm, ell}]),
// cursors (Spans of the time plots), clock (Label of the scene), velocity ({all, now, want,
// got, steps}: the first run's tip velocity set at every state, the one drawn, the P velocity
// and the tip velocity, read from its steps).
// Every change here is drawn but not sent to the server (sync: false): the view of a frame is
// the browser's alone, and sending it cost the server one patch per source per frame.
const show = (model, attrs) => model.setv(attrs, {sync: false})
const t = scrub.value
const dt = scrub.step
for (const run of runs) {
  const steps = run.steps.data
  const K = steps.t.length - 1
  if (K < 0) {
    show(run.arm, {data: {x: [], y: [], s: []}})
    show(run.ell, {data: {x: [], y: [], w: [], h: [], a: []}})
    continue
  }
  const u = Math.min(K, Math.max(0, t / dt))
  const k0 = Math.min(K, Math.floor(u + 1e-9))
  const k1 = Math.min(K, k0 + 1)
  const f = k1 > k0 ? u - k0 : 0
  const k = f < 0.5 ? k0 : k1  // the nearest state
  const pts = run.points.data
  const per = pts.x.length / (K + 1)
  const between = (a) => Array.from({length: per},
    (_, i) => a[k0 * per + i] + f * (a[k1 * per + i] - a[k0 * per + i]))
  const mix = (a) => a[k0] + f * (a[k1] - a[k0])
  show(run.arm, {data: {x: between(pts.x), y: between(pts.y),
                        s: Array.from(pts.s.slice(k * per, (k + 1) * per))}})
  show(run.ell, {data: {x: [mix(steps.ex)], y: [mix(steps.ey)], w: [mix(steps.ew)],
                        h: [mix(steps.eh)], a: [steps.ea[k]]}})
}
{
  const steps = velocity.steps.data
  const K = steps.t.length - 1
  const none = {x0: [], y0: [], x1: [], y1: []}
  if (K < 0 || steps.vx === undefined) {
    show(velocity.now, {data: {x: [], y: []}})
    show(velocity.want, {data: none})
    show(velocity.got, {data: none})
  } else {
    const k = Math.min(K, Math.max(0, Math.round(t / dt)))
    const all = velocity.all.data
    const per = all.px.length / (K + 1)
    const rows = (a) => Array.from(a.slice(k * per, (k + 1) * per))
    show(velocity.now, {data: {x: rows(all.px), y: rows(all.py)}})
    const arrow = (x, y) => (Number.isFinite(x[k]) ?
      {x0: [steps.ex[k]], y0: [steps.ey[k]], x1: [x[k]], y1: [y[k]]} : none)
    show(velocity.want, {data: arrow(steps.vx, steps.vy)})
    show(velocity.got, {data: arrow(steps.ax, steps.ay)})
  }
}
for (const cursor of cursors) {
  show(cursor, {location: t})
}
show(clock, {text: `t = ${t.toFixed(2)} s`})

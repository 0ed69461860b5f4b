// Show the state under the scrub bar: copy row k of each run into the drawn sources.
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
  const k = Math.min(K, Math.max(0, Math.round(t / dt)))
  const pts = run.points.data
  const per = pts.x.length / (K + 1)
  const rows = (a) => Array.from(a.slice(k * per, (k + 1) * per))
  show(run.arm, {data: {x: rows(pts.x), y: rows(pts.y), s: rows(pts.s)}})
  show(run.ell, {data: {x: [steps.ex[k]], y: [steps.ey[k]], w: [steps.ew[k]], h: [steps.eh[k]],
                        a: [steps.ea[k]]}})
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

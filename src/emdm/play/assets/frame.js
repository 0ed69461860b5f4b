// Show the state under the scrub bar: copy row k of each run into the drawn sources.
// args: scrub (Slider, value = t in s, step = dt), runs ([{points, steps, arm, ell}]),
// cursors (Spans of the time plots), clock (Label of the scene).
const t = scrub.value
const dt = scrub.step
for (const run of runs) {
  const steps = run.steps.data
  const K = steps.t.length - 1
  if (K < 0) {
    run.arm.data = {x: [], y: [], s: []}
    run.ell.data = {x: [], y: [], w: [], h: [], a: []}
    continue
  }
  const k = Math.min(K, Math.max(0, Math.round(t / dt)))
  const pts = run.points.data
  const per = pts.x.length / (K + 1)
  const rows = (a) => Array.from(a.slice(k * per, (k + 1) * per))
  run.arm.data = {x: rows(pts.x), y: rows(pts.y), s: rows(pts.s)}
  run.ell.data = {x: [steps.ex[k]], y: [steps.ey[k]], w: [steps.ew[k]], h: [steps.eh[k]],
                  a: [steps.ea[k]]}
}
for (const cursor of cursors) {
  cursor.location = t
}
clock.text = `t = ${t.toFixed(2)} s`

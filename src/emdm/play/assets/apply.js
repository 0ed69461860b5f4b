// Apply a change the server sent as one message: every numeric column of the drawn sources end
// to end in one float64 array (change.data.values[0]), the rest as JSON (change.data.meta[0]:
// sources {name: {column: {f: [offset, length]} | {fs: [[offset, length], ...]} | {v: values}}},
// props {name: {attribute: value}}, restart, live). Nothing here is sent back to the server
// (sync: false). A change of a drag in progress that arrives after the drag was released is
// skipped: the release's own change follows (live.js sets emdm_release_due).
// args: change (data source), models ({name: model}), toggle (the Play button).
const meta = JSON.parse(change.data.meta[0])
if (!(meta.live && window.emdm_release_due)) {
  const packed = change.data.values[0]
  const values = new Float64Array(packed.buffer, packed.byteOffset, packed.length)
  const column = (spec) => {
    if (spec.f != null) {
      return values.subarray(spec.f[0], spec.f[0] + spec.f[1])
    }
    if (spec.fs != null) {
      return spec.fs.map(([offset, length]) => values.subarray(offset, offset + length))
    }
    return spec.v
  }
  for (const [name, columns] of Object.entries(meta.sources ?? {})) {
    const data = {}
    for (const [key, spec] of Object.entries(columns)) {
      data[key] = column(spec)
    }
    models[name].setv({data}, {sync: false})
  }
  for (const [name, attributes] of Object.entries(meta.props ?? {})) {
    models[name].setv(attributes, {sync: false})
  }
  if (!meta.live) {
    window.emdm_release_due = false
  }
  if (meta.restart) {  // a new run plays from its start; a playing motion goes on from there
    const scrub = models.scrub
    scrub.value = scrub.start
    if (!toggle.active) {
      toggle.active = true
    }
  }
}
if (meta.live && window.emdm_live != null) {  // the drag's next position may go (live.js)
  window.emdm_live.next()
}

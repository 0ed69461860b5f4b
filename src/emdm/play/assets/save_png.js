// Download the view (the scene and the plots, side by side) as one PNG.
// args: button (its tags: [file name, caption]), scene (figure), plots (grid of figures).
const [name, caption] = button.tags
const parts = [scene, plots].map((model) => Bokeh.index.find_one(model).export("png").canvas)
const ratio = window.devicePixelRatio || 1
const pad = Math.round(36 * ratio)
const canvas = document.createElement("canvas")
canvas.width = parts.reduce((w, c) => w + c.width, 0)
canvas.height = Math.max(...parts.map((c) => c.height)) + pad
const ctx = canvas.getContext("2d")
ctx.fillStyle = "white"
ctx.fillRect(0, 0, canvas.width, canvas.height)
ctx.fillStyle = "#222"
ctx.font = `${Math.round(15 * ratio)}px sans-serif`
ctx.fillText(caption, Math.round(10 * ratio), Math.round(24 * ratio))
let x = 0
for (const part of parts) {
  ctx.drawImage(part, x, pad)
  x += part.width
}
canvas.toBlob((blob) => download(blob, name), "image/png")

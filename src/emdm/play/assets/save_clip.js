// Download the clip the server wrote (a GIF of the runs shown). args: clip (data source: its
// columns gif, the file's bytes in base64, and name); empty columns are no clip.
const data = clip.data.gif ?? []
if (data.length && data[0]) {
  const bytes = Uint8Array.from(atob(data[0]), (c) => c.charCodeAt(0))
  download(new Blob([bytes], {type: "image/gif"}), clip.data.name[0])
}

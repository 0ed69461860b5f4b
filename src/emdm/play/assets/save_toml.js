// Download the current scenario as TOML. args: button (its tags: [toml text, file name]).
const [text, name] = button.tags
const link = document.createElement("a")
link.href = URL.createObjectURL(new Blob([text], {type: "application/toml"}))
link.download = name
document.body.appendChild(link)
link.click()
link.remove()

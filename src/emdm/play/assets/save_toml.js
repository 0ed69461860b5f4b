// Download the current scenario as TOML. args: button (its tags: [toml text, file name]).
const [text, name] = button.tags
download(new Blob([text], {type: "application/toml"}), name)

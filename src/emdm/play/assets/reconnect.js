// The server went away (stopped, restarted): say so on the page, then knock every second and
// reload the page once the server answers at all (any status: a path without a page is enough,
// and opens no session). The address holds the settings, so the reloaded page shows the same
// run. args: banner (Div).
if (window.emdm_reconnect == null) {
  banner.text = '<div class="error">Connection to emdm play lost: waiting for the server ' +
    "(start it again with the same command); the page reloads with its settings when it answers.</div>"
  window.emdm_reconnect = setInterval(() => {
    fetch(window.location.origin + "/emdm-alive", {method: "HEAD", cache: "no-store"})
      .then(() => {
        clearInterval(window.emdm_reconnect)
        window.location.reload()
      })
      .catch(() => {})
  }, 1000)
}

// Keep the page address equal to the settings in force, so that a reload, a bookmark or a link
// restores them. args: address (data source whose column query holds the query string the server wrote).
const query = address.data.query[0]
if (query && window.location.search !== "?" + query) {
  window.history.replaceState(null, "", window.location.pathname + "?" + query)
}

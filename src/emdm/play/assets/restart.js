// Play a new run from its start. args: toggle (Toggle), scrub (Slider). A playing motion
// continues from the start (play.js follows a scrub bar moved under it); a paused one starts.
scrub.value = scrub.start
if (!toggle.active) {
  toggle.active = true
}

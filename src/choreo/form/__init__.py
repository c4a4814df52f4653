"""Choreography with a form: when a song's section returns, its dance returns (choreo.form.returns),
as the song's form says (choreo.music.form: analysed, or given with --form)."""

"""The command-line faces below :mod:`snoworm.cli`: what every command shares (:mod:`.common`:
exit statuses, error handling, common options, progress, logging) and the study commands
(:mod:`.studies`).  Thin: every command calls the Python API."""

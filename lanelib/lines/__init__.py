"""Every visible lane line, for the benchmarks that label all of them: traced by windows
(``trace``) or found by a vote over straight lines (``vote``), in ``perspective.LinesView``."""

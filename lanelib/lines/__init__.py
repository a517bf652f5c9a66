"""Every visible lane line, for the benchmarks that label all of them: in the lines view
(``view.LinesView``), traced by windows (``trace``) or found by a vote over straight lines
(``vote``), masked, searched and mapped back to the raw frame by ``detect``."""

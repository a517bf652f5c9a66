"""Hard-road parts: double lines (``stripes``) and the asphalt edge and the road seen ahead
(``edge``). The core's search uses ``stripes`` when ``SearchConfig.double_line_px`` is set; the
pipeline and the tracker use ``edge``."""

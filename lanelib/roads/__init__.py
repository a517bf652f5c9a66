"""Hard-road parts, each off by default and switched on by the ``hard-roads`` and ``country``
presets (or alone): double lines (``stripes``), the asphalt edge and the road seen ahead
(``edge``), the proposers that look again on hard roads (``fallbacks``: no track needed;
``proposers``: the road view, re-acquisition, the asphalt edge, a faded line's shoulder), the
checks of a tracked frame (``checks``: near gap, grade pair, stripe spread, restart from one
line) and the lane trend (``trend``). The core calls them where ``CORE_CALLS`` of
``tests/test_imports.py`` allows: the search (``stripes``), the pipeline and the tracker (the
proposers' chains, ``checks``, ``trend``)."""

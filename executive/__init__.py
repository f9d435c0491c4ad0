"""Running trees: the ``bearchair`` CLI and its commands, the tick loop (``runner``),
run configuration, run records, recordings and their replay (``inspect``, ``view``).

May import every package but ``evaluation`` (which sits on top of it).
"""

"""The evaluation harness: ``bearchair trials``, the paper's protocol over a set of chairs,
each trial a mission in a subprocess of its own, with SQLite records and a report.

It sits on top of the layering and may import every package below it, ``executive``
included; nothing imports it (``bearchair.executive.cli`` finds its command by entry point).

Modules:
    cli             the ``bearchair trials`` subcommand (entry point ``bearchair.commands``).
    protocol        the chairs of a folder and the trials of a protocol (seeds included).
    worker          one trial's process: ``python -m bearchair.evaluation.worker '<json>'``.
    worker_process  running that worker in a subprocess: crash and timeout become errors.
    forked_workers  workers forked from a trial server preloaded by ``server_preload``.
    backends        where the subprocesses run: locally, a few at once, or as Ray tasks.
    store           the SQLite records, one committed row per finished trial.
    campaign        run what the records do not hold yet (resume, Ctrl-C).
    report          the paper's Table 1, stage medians and failure causes from the records.
    pictures        imagined pose per chair, final scene per trial.
    progress        the progress bar with an ETA.
"""

"""Trials: the paper's evaluation protocol over a set of chairs, with records and a report.

Modules:
    protocol        the chairs of a folder and the trials of a protocol (seeds included).
    worker_process  one trial in its own subprocess: crash and timeout become errors.
    backends        where the subprocesses run: locally, a few at once, or as Ray tasks.
    store           the SQLite records, one committed row per finished trial.
    campaign        run what the records do not hold yet (resume, Ctrl-C).
    report          the paper's Table 1, stage medians and failure causes from the records.
    pictures        imagined pose per chair, final scene per trial.
    progress        the progress bar with an ETA.
"""

"""The run's records: ``ticks.jsonl``, ``tree.json`` and ``summary.json``, written while a
mission runs (:mod:`.run_record`), typed (:mod:`.run_summary`), and read back offline
(:mod:`.replay`). Plain JSON files, readable without bearchair."""

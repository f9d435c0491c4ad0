"""What more than one test module uses: each helper module named after what it holds.

No ``tests/test_*.py`` imports another test module (tests/test_architecture.py checks
it); a helper two test files share lives here, or in conftest.py when it is a fixture.

- ``cli_calls``: calling the CLI in this process (``refused``).
- ``campaigns``: the fake trial worker, box chairs, a Ray stand-in, tables to compare.
- ``missions``: missions on fakes (``FakeMission``, ``run_scripted_mission``) and a run record.
- ``cells``: cell files (``GOOD_CELL``, ``cell_file``).
- ``silent_peers``: TCP peers that accept and never answer.
- ``scans``: synthetic scans of a chair (``frames_of``).
- ``process_tree``: which processes a command left behind.
- ``groot2_client``: a client of Groot2's protocol.
- ``forked_fakes``: trial-worker entries the trial server imports by name.
"""

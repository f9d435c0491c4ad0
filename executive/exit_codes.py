"""The exit statuses of every ``bearchair`` command (docs/exit-status.md); a stop signal N
ends a command with 128 + N (:func:`bearchair.executive.interrupts.exit_status`)."""

EXIT_SUCCESS = 0
EXIT_MISSION_FAILED = 1
EXIT_BAD_INPUT = 2
EXIT_INTERNAL_ERROR = 3

"""What the trial server holds before it forks the first trial (imported only there).

Importing this module is the preloading: the libraries and the project's modules a
mission imports (about 1.9 s on the 2-core machine), and the whole-body planner's casadi
problems with their fine trajectory NLP (about 1.2 s), which every mission builds the
same way. Nothing here depends on a trial: every fork starts from the same state, so a
trial's outcome is what it would be in a fresh interpreter.

A failure here is printed and swallowed: the trials then import and build on first use,
as a fresh interpreter would.
"""

from __future__ import annotations

import importlib
import sys
import time

PRELOADED_MODULES = (
    "bearchair.executive.run",
    "bearchair.evaluation.worker",
    "bearchair.trees.mission",
    "bearchair.skills.default_skills",  # every skill
)


def _preload() -> float:
    """Imports every module a mission binds and builds the planner's problems; returns
    the seconds it took."""
    started = time.perf_counter()
    for module_name in PRELOADED_MODULES:
        importlib.import_module(module_name)
    from bearchair.skills.planning.wholebody.optimisation import seating_problems

    problems = seating_problems()
    problems.trajectory_solver(problems.n_knots)
    return time.perf_counter() - started


try:
    PRELOAD_S: float | None = _preload()
except Exception as error:  # the server must start all the same
    PRELOAD_S = None
    print(f"trial server: preloading failed ({type(error).__name__}: {error})", file=sys.stderr)

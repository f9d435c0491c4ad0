"""The mission's inputs on the blackboard: what any host writes before the first tick.

The leaves read two keys nobody in the tree writes (:data:`bearchair.behaviours.keys.SET_BY_EXECUTIVE`):
the run's seed and the arena. ``bearchair``'s executive writes them with
:func:`set_mission_inputs`; so does any other host, before its first tick::

    import py_trees

    from bearchair.behaviours.mission_inputs import set_mission_inputs
    from bearchair.trees.mission import create_tree

    tree = py_trees.trees.BehaviourTree(create_tree())
    set_mission_inputs(seed=0)            # the arena: DEFAULT_ARENA
    tree.setup(skills=my_skills, robot=my_robot)
    tree.tick()

(py_trees_ros's ``BehaviourTree`` is the same: call it before ``setup``/``tick_tock``.)
"""

from __future__ import annotations

import numbers

import py_trees

from bearchair.behaviours import keys
from bearchair.core.arena import DEFAULT_ARENA, Arena

WRITER_NAME = "executive"
"""The blackboard client that writes the inputs (``bearchair tree --blackboard`` shows it)."""


def set_mission_inputs(*, seed: int, arena: Arena = DEFAULT_ARENA) -> py_trees.blackboard.Client:
    """Writes :data:`keys.SEED` and :data:`keys.ARENA`, the keys of ``keys.SET_BY_EXECUTIVE``.

    Args:
        seed: seeds every skill that draws random numbers; the same seed, the same run.
        arena: the workspace the planner and the assistance keep to.

    Returns:
        The writing client (keep it to change an input between runs).

    Raises:
        TypeError: ``seed`` is not a whole number (a mistake the leaves would only meet
            ticks later, in a skill's random generator).
    """
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral):
        raise TypeError(f"seed: a whole number is needed, got {seed!r}")
    writer = py_trees.blackboard.Client(name=WRITER_NAME)
    for key, value in zip(keys.SET_BY_EXECUTIVE, (seed, arena), strict=True):
        writer.register_key(key=key, access=py_trees.common.Access.WRITE)
        writer.set(key, value, overwrite=True)
    return writer

"""The mission's algorithms as plain functions and small classes on typed inputs.

Nothing in here imports py_trees: the behaviours in ``behaviours/`` call these through
``skills.toolbox.MissionSkills``.
"""

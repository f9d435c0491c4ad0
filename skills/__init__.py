"""The mission's algorithms as plain functions and small classes on typed inputs:
perception, imagination, planning, control, assistance (no py_trees in here).

May import ``core`` and ``hardware`` (its interfaces, to drive a robot through them).
The behaviours call these through ``bearchair.skills.mission_skills.MissionSkills``.
"""

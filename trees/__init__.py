"""Composition only: the mission tree built from the leaves (``bearchair.trees.mission.create_tree``).

May import ``behaviours`` (and ``core``, ``hardware``, ``skills`` for types); no logic.
"""

"""The mission tree's leaves: thin py_trees behaviours, one skill call each, run in a
worker thread (``update()`` polls, ``terminate()`` cancels); ``keys`` names the blackboard.

May import ``core``, ``hardware`` and ``skills`` (their protocols and result types: the
skills themselves arrive as a ``bearchair.skills.mission_skills.MissionSkills`` object at setup).
"""

"""The Rerun recording of a mission (``mission.rrd``, or a live viewer): the tree and the
3D scene on one timeline (:mod:`.mission_recording`), the skills' results drawn
(:mod:`.scene_loggers`), the robots from their URDFs (:mod:`.urdf_robots`), the layout the
viewer opens with (:mod:`.layout`) and reading a recording back (:mod:`.read_back`).
Needs rerun-sdk; the run records in :mod:`bearchair.executive.records` do not."""

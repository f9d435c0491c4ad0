"""Motion planning: the humanoid's SE(2) path (``se2``) and its whole-body seating motion
(``wholebody``)."""

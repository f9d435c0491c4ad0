"""Hardware interfaces (``hardware.interfaces``) and their backends: ``hardware.sim``
(pybullet, the default) and ``hardware.real`` (the robots' SDKs)."""

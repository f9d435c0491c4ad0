"""Hardware interfaces (``bearchair.hardware.interfaces``, typing.Protocols), their backends:
``bearchair.hardware.sim`` (pybullet, the default) and ``bearchair.hardware.real`` (the robots' SDKs), and
fakes of them for tests (``bearchair.hardware.fakes``).

May import ``core`` only.
"""

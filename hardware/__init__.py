"""Hardware interfaces (``hardware.interfaces``, typing.Protocols), their backends:
``hardware.sim`` (pybullet, the default) and ``hardware.real`` (the robots' SDKs), and
fakes of them for tests (``hardware.fakes``).

May import ``core`` only.
"""

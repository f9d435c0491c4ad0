"""bearchair: a behaviour-tree robot task executive that seats a teddy bear on a chair.

Everything importable lives under this one name. The card's top-level folders
(``core/``, ``hardware/``, ``skills/``, ``behaviours/``, ``trees/``, ``executive/``,
``evaluation/``, the testing kit ``testing/``) are its subpackages: in a checkout
``bearchair/<room>`` is a symbolic link to ``../<room>``, and a built wheel holds them as ``bearchair/<room>/``.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("bearchair")
except PackageNotFoundError:  # a checkout on sys.path that was never installed
    __version__ = "0+unknown"

__all__ = ["__version__"]

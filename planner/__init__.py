"""minkplan: translational motion planning on Minkowski-sum C-obstacles."""
from . import _minkowski_core  # noqa: F401

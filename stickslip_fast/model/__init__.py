"""The physical model: parameters and presets, packed parameter slots, the friction law, f(y), its
Jacobian and the bordered linear algebra.
"""

from ..base.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__)  # submodules as attributes on first use

"""The compiled integration core: tableaus, problem records, steppers, the one adaptive driver,
the Poincare section, trajectory and tangent kernels, and the validated settings.
"""

from ..base.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__)  # submodules as attributes on first use

"""Where the chunks of a sweep or census run: this machine's cores (local), a Dask cluster, or a
CUDA GPU.
"""

from ..base.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__)  # submodules as attributes on first use

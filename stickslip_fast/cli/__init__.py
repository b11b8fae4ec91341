"""The command line (``stickslip-fast``) and the TOML configuration files it reads."""

from .commands import build_parser, main

__all__ = ["build_parser", "main"]

from ..base.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__)  # submodules as attributes on first use

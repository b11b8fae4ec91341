"""The command line (``stickslip-fast``) and the TOML configuration files it reads."""

from .commands import build_parser, main

__all__ = ["build_parser", "main"]

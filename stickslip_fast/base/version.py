"""The installed package's version, for result files (a layer below everything that writes one)."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version


def package_version() -> str:
    """The version of the installed ``stickslip_fast`` distribution (a source tree: ``0.0.0+unknown``)."""
    try:
        return version("stickslip_fast")
    except PackageNotFoundError:  # running from a source tree
        return "0.0.0+unknown"

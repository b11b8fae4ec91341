"""Sphinx configuration for the stickslip_fast documentation.

Build (from the repository root, with ``pip install ".[docs]"``)::

    python3 -m sphinx -W -b html docs docs/_build/html

The build documents the source tree it sits in (the repository root is put first
on ``sys.path``), runs every example of ``examples/`` (sphinx-gallery; their
figures are made here), renders the benchmark summary from
``benchmarks/results/results.json`` and checks that every name of
``stickslip_fast.__all__`` appears in the API reference.

Intersphinx (links to the NumPy, SciPy, h5py, xarray, Dask, Matplotlib and
Python docs) needs those sites' inventories, which are downloaded at build time.
CI builds offline, so intersphinx is off unless ``SSF_DOCS_INTERSPHINX=1``;
the pages read the same either way (types render as text without it).
"""

from __future__ import annotations

import json
import os
import re
import sys
import warnings
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))  # the tree being documented, not an installed copy

import stickslip_fast  # noqa: E402

# -- Project ------------------------------------------------------------------

project = "stickslip_fast"
author = "the stickslip_fast developers"
copyright = "the stickslip_fast developers"  # noqa: A001
release = stickslip_fast.__version__
version = ".".join(release.split(".")[:2])

# -- Extensions ---------------------------------------------------------------

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.doctest",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]

INTERSPHINX = os.environ.get("SSF_DOCS_INTERSPHINX", "") not in ("", "0")
if INTERSPHINX:
    extensions.append("sphinx.ext.intersphinx")
    intersphinx_mapping = {
        "python": ("https://docs.python.org/3", None),
        "numpy": ("https://numpy.org/doc/stable", None),
        "scipy": ("https://docs.scipy.org/doc/scipy", None),
        "h5py": ("https://docs.h5py.org/en/stable", None),
        "xarray": ("https://docs.xarray.dev/en/stable", None),
        "dask": ("https://docs.dask.org/en/stable", None),
        "distributed": ("https://distributed.dask.org/en/stable", None),
        "matplotlib": ("https://matplotlib.org/stable", None),
    }

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = [
    "_build",
    "Thumbs.db",
    ".DS_Store",
    "auto_examples/*.ipynb",
    "auto_examples/*.py",
    "auto_examples/*.zip",
    "auto_examples/*.md5",
    "auto_examples/*.codeobj.json",
    "_generated/*.md",  # included into performance.md, not pages of their own
]
templates_path = ["_templates"]

# MyST: the pages are plain GitHub Markdown; `$...$` is not math there.
myst_enable_extensions = ["colon_fence", "deflist"]
myst_heading_anchors = 3

# autodoc / autosummary / numpydoc
autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": True, "inherited-members": False}
autodoc_typehints = "none"  # numpydoc's Parameters sections say the types
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = INTERSPHINX
numpydoc_validation_checks = set()
if INTERSPHINX:
    numpydoc_xref_aliases = {"ndarray": "numpy.ndarray", "Path": "pathlib.Path"}
    numpydoc_xref_ignore = {"optional", "default", "of", "or", "shape", "array", "int", "float"}

# sphinx-gallery: examples/ -> docs/auto_examples/, run at build time
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "matplotlib_animations": False,
    "show_memory": False,
    "abort_on_example_error": True,
    "reset_modules": ("matplotlib",),
    "line_numbers": False,
    "min_reported_time": 0,
    "write_computation_times": False,
}

# -- HTML ---------------------------------------------------------------------

html_theme = "pydata_sphinx_theme"
html_title = f"stickslip_fast {release}"
html_static_path: list[str] = []
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "header_links_before_dropdown": 8,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version", "theme-version"],
}
html_show_sourcelink = False

# Agg: the gallery and any plot draw without a display
os.environ.setdefault("MPLBACKEND", "Agg")
warnings.filterwarnings("ignore", message="Matplotlib is currently using agg")


# -- Generated pages ----------------------------------------------------------


def _write_if_changed(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def _results_images(text: str) -> str:
    """Images beside the results (``![x](name.png)``) as seen from performance.md, which includes them."""
    return re.sub(r"\]\(([\w.-]+\.png)\)", r"](../benchmarks/results/\1)", text)


def render_benchmarks(app) -> None:
    """benchmarks/results/results.json -> docs/_generated/benchmark-summary.md.

    The same renderer ``benchmarks/run.py`` uses for ``benchmarks/results/summary.md``,
    so the Performance page shows the recorded run, regenerated at every build.
    """
    from benchmarks.summary import write_summary

    results = json.loads((ROOT / "benchmarks" / "results" / "results.json").read_text())
    text = write_summary(results)
    # the summary's own title becomes a section of performance.md
    text = re.sub(r"\A# .*\n", "", text)
    text = _results_images(text)
    _write_if_changed(DOCS / "_generated" / "benchmark-summary.md", text)
    for name in ("gpu.md", "dask_overhead.md", "profile.md"):
        src = (ROOT / "benchmarks" / "results" / name).read_text()
        text = _results_images(re.sub(r"\A# .*\n", "", src))
        _write_if_changed(DOCS / "_generated" / name, text)


def check_api_complete(app) -> None:
    """Every public name is in the API reference (a missing one fails the -W build)."""
    api = (DOCS / "api.rst").read_text()
    missing = [n for n in stickslip_fast.__all__ if not re.search(rf"\b{re.escape(n)}\b", api)]
    if missing:
        from sphinx.util import logging

        logging.getLogger(__name__).warning(
            "public names missing from docs/api.rst: %s", ", ".join(missing)
        )


def setup(app):
    app.connect("builder-inited", render_benchmarks)
    app.connect("builder-inited", check_api_complete)

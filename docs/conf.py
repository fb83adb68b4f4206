"""Sphinx configuration of the simlunar documentation site (``make docs``).

The guides are the Markdown files of this folder (MyST); the API reference is generated from
the numpydoc docstrings by autosummary; the configuration reference, the experiment table and
the figure gallery are generated from the code and the result folders by the ``simlunar_docs``
extension (``docs/_ext``) each time the site is built, so they cannot go stale.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")

import simlunar  # noqa: E402

project = "simlunar"
author = "the simlunar authors"
copyright = "the simlunar authors (Apache-2.0)"
version = release = simlunar.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "simlunar_docs",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "figures/README.md"]
templates_path = ["_templates"]

# MyST: $...$ maths in the guides, heading anchors for the guides' in-page links
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# API reference: one page per module (written by simlunar_docs), members documented from
# their numpydoc docstrings
autodoc_default_options = {"members": True, "member-order": "bysource"}
autodoc_typehints = "none"  # the numpydoc Parameters sections carry the types and units
autodoc_mock_imports: list[str] = []
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks: set[str] = set()
numpydoc_xref_param_type = False

html_theme = "pydata_sphinx_theme"
html_title = f"simlunar {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "navbar_align": "left",
}
html_static_path: list[str] = []
html_show_sourcelink = False
html_copy_source = False

"""Sphinx configuration: the documentation site of handover-sandbox.

Build it strictly (every warning an error, every cross-reference checked)::

    pip install -e ".[docs]"
    sphinx-build -W --keep-going -n -b html docs docs/_build/html

The pages under ``docs/_generated`` are written at build time, never by hand:
the API reference (one page per public module, from the docstrings), the CLI
reference (from the argument parsers), one page per environment id (from the
registered environments) and the results (from ``python -m sandbox results``'s
output in ``notebooks/figures``). See ``docs/_ext/generate.py``.
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
REPO = DOCS.parent
sys.path.insert(0, str(DOCS / "_ext"))

import sandbox  # noqa: E402

project = "handover-sandbox"
author = "handover-sandbox developers"
copyright = "2026, handover-sandbox developers"  # noqa: A001
release = version = sandbox.__version__  # the one version source: sandbox/__init__.py

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax shipped with the site: the pages render offline
    "myst_parser",
    "generate",   # docs/_ext/generate.py: the generated pages
    "docscheck",  # docs/_ext/docscheck.py: a public name without a docstring is a warning
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
# Included by results.md and method.md, not pages of their own:
exclude_patterns = ["_build", "_generated/results.md", "_generated/equations.md"]
root_doc = "index"

# Strict: -n (nitpicky) reports every reference that does not resolve. References to this
# project must resolve; those to other projects (numpy, gymnasium, the standard library)
# cannot offline (no intersphinx inventories are fetched), so they are ignored by name.
nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", r"(?!sandbox\b).*"),
    (r"py:class", r"sandbox\..*\._\w+"),  # a private base class (show-inheritance): not documented
]

# ignore-module-all: a package documents what it defines; what it re-exports is documented
# where it is defined, and references to the re-exported name resolve there (generate.py).
autodoc_default_options = {"members": True, "undoc-members": True, "show-inheritance": True,
                           "ignore-module-all": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_format = "short"
autodoc_inherit_docstrings = True
napoleon_google_docstring = True  # for docstrings inherited from Gymnasium (reset, step)
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_use_ivar = True  # Attributes as fields: a dataclass field is described once, by autodoc

myst_enable_extensions = ["dollarmath", "amsmath", "deflist"]
myst_heading_anchors = 3

html_theme = "furo"
html_title = f"handover-sandbox {release}"
html_static_path: list[str] = []
# The environment's Gymnasium-style "Arguments" section is prose, not a parameter list.
napoleon_custom_sections = [("Arguments", "Notes")]

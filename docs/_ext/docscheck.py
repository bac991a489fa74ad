"""A public name without a docstring is a warning, so the strict build fails on it.

Public: a module, class, function, method or property whose own name and whose
module's dotted name have no part starting with ``_``. Data and attributes are
not held to it (their ``#:`` comments are optional). A method that overrides a
documented one inherits its docstring (``autodoc_inherit_docstrings``).
"""

from __future__ import annotations

from sphinx.util import logging

logger = logging.getLogger(__name__)
CHECKED = {"module", "class", "exception", "function", "method", "property"}


def check(app, what, name, obj, options, lines) -> None:
    if what not in CHECKED or any(part.startswith("_") for part in name.split(".")):
        return
    if not any(line.strip() for line in lines):
        logger.warning("public %s %s has no docstring", what, name, type="docscheck",
                       subtype="missing")


def setup(app):
    app.connect("autodoc-process-docstring", check)
    return {"parallel_read_safe": True, "version": "1"}

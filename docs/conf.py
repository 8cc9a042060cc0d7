"""Sphinx configuration of pkdyn's documentation (``make docs``).

The user guide (``guide/``, MyST Markdown) is written by hand, except its command-line
reference, generated from the parsers at every build (``_ext/cli_reference.py``). The API
reference is generated from the docstrings (autodoc + napoleon, Google style) of every
public module of ``pkdyn`` and ``solvers`` (autosummary, recursive; each module's ``__all__``
selects what is shown). The notebooks of ``notebooks/`` are copied here and executed when the
documentation is built (myst-nb), so their plots are those of the current code.
"""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS / "_ext"))

project = "pkdyn"
author = "pkdyn developers"
copyright = "pkdyn developers"  # noqa: A001 - Sphinx's name

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.viewcode",
    "myst_nb",
    "cli_reference",
]

# MyST: anchors for the headings of the guide (links such as `loading.md#tolerance-and-home`)
myst_heading_anchors = 3
# no typographic quotes and dashes: "--pose" must stay two hyphens (copied into a shell)
smartquotes = False

# API reference: one page per public module, members from __all__, Google docstrings
autosummary_generate = True
autosummary_ignore_module_all = False
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_preserve_defaults = True
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_attr_annotations = True
templates_path = ["_templates"]
# attribute types such as ``nv`` or ``codes`` name attributes of several classes: Sphinx picks one
suppress_warnings = ["ref.python"]

# notebooks: copied from notebooks/ and executed at every build
NOTEBOOKS = DOCS / "notebooks"
shutil.rmtree(NOTEBOOKS, ignore_errors=True)
NOTEBOOKS.mkdir()
for nb in sorted((ROOT / "notebooks").glob("*.ipynb")):
    shutil.copy2(nb, NOTEBOOKS / nb.name)
nb_execution_mode = os.environ.get("PKDYN_DOCS_EXECUTE", "force")  # "off": skip (drafts)
nb_execution_timeout = 900
nb_execution_raise_on_error = True
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}

_documenting: list[str] = [""]


def _module_docstring(app, what, name, obj, options, lines):  # noqa: ANN001, ARG001
    """Remember the module whose page autodoc is writing."""
    if what == "module":
        _documenting[0] = name


def _skip_reexports(app, what, name, obj, skip, options):  # noqa: ANN001, ARG001
    """A function or class re-exported by a package is documented in its own module only."""
    module = getattr(obj, "__module__", None)
    if what == "module" and callable(obj) and module and module != _documenting[0]:
        return True
    return None


def setup(app):  # noqa: ANN001
    """Connect the re-export filter."""
    app.connect("autodoc-process-docstring", _module_docstring)
    app.connect("autodoc-skip-member", _skip_reexports)


# _generated/: pages included by others (the command-line reference), not documents of their own
exclude_patterns = ["_build", "_generated", "Thumbs.db", ".DS_Store"]
html_theme = "furo"
html_title = "pkdyn"

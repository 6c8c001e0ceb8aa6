"""Sphinx configuration of the kvrod documentation.

Sphinx + MyST-NB: the pages are Markdown (as the notes and the README are), the tutorials
are MyST Markdown notebooks executed at every build, and the API reference comes from the
docstrings (autodoc + napoleon, numpydoc style). The pages that must not drift (the
derivation, every problem-file key, every command-line flag, the notes and benchmark
tables) are rendered at build time by ``_ext/kvrod_docs.py`` from the code itself.

Build: ``.venv/bin/sphinx-build -W -n -b html docs docs/_build/html`` (see the README).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent / "_ext"))

project = "kvrod"
author = "the kvrod developers"
copyright = "2026, the kvrod developers"

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "kvrod_docs",
]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence"]
myst_heading_anchors = 3
source_suffix = {".md": "myst-nb", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "design.md", "**/.ipynb_checkpoints"]
# the generated notes start sections at any level; :ivar: fields of different classes
# share names (t, y), which Sphinx reports as ambiguous (not missing) references
suppress_warnings = ["myst.header", "ref.python"]

# every tutorial runs at every build; an error in a cell fails the build
nb_execution_mode = "force"
nb_execution_raise_on_error = True
nb_execution_timeout = 300
nb_merge_streams = True

autodoc_typehints = "none"            # signatures stay readable; types are in the text
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "undoc-members": False}
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_ivar = True              # Attributes sections as fields (no duplicate objects)

# nitpicky: every cross-reference must resolve; the ones into other projects (no network
# for intersphinx on the build machines) are named here
nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", r"(numpy|np|scipy|sp|casadi|matplotlib|pathlib|collections|typing|sympy)\..*"),
    (r"py:.*", r"(Path|Any|Callable|Mapping|Sequence|Iterator|Iterable|Expr|ndarray)"),
    # numpydoc type words and types documented in prose (napoleon makes them references)
    (r"py:class", r"(optional|callable|callables|sequence|mapping|array_like|"
                  r"ResidualProblem|BDFSolution|RodModel|.* of .*|str to .*|"
                  r"\{?\"[a-z]+\"\}?)"),
]

html_theme = "furo"
html_title = "kvrod"

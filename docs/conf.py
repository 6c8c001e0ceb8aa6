"""Sphinx configuration of the kvrod documentation.

Sphinx + MyST-NB: the pages are Markdown (as the notes and the README are), the tutorials
are MyST Markdown notebooks executed through a cache (see below), and the API reference
comes from the docstrings (autodoc + napoleon, numpydoc style). The pages that must not
drift (the derivation, every problem-file key, every command-line flag, the output of the
getting-started commands, the validation tables and figures from the notes, the benchmark
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
    "sphinx-mathjax-offline",   # MathJax served from _static/mathjax: math renders offline
    "kvrod_docs",
]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence"]
myst_heading_anchors = 3
source_suffix = {".md": "myst-nb", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "design.md", "**/.ipynb_checkpoints"]
# the generated notes start sections at any level
suppress_warnings = ["myst.header"]

# The tutorials are executed through jupyter-cache: a notebook runs again only when its
# code cells change or when kvrod's own code does. kvrod_docs points
# nb_execution_cache_path at <build folder>/.jupyter_cache/<key>, the key hashing the
# sources of derive/, generated/, runtime/, kvrod/, references/, examples/ and the
# versions of Python and the numerical libraries (a stale output can never hide a break:
# the test suite builds with an empty cache). An error in a cell fails the build and is
# not cached.
nb_execution_mode = "cache"
nb_execution_raise_on_error = True
nb_execution_timeout = 300
nb_merge_streams = True

autodoc_typehints = "none"            # signatures stay readable; types are in the text
autodoc_member_order = "bysource"
# No default options: Sphinx 9 lets a default "members" override a directive's explicit
# member list and reads "undoc-members": False as given. Every API page names its
# objects, each documented once at its defining module (re-exports are not documented);
# attributes appear only where they have a docstring or a #: comment.
autodoc_default_options: dict = {}
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_ivar = True              # Attributes sections as fields (no duplicate objects)

# nitpicky: every cross-reference must resolve; the ones into other projects (no network
# for intersphinx on the build machines) are named here
nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", r"(numpy|np|scipy|sp|casadi|matplotlib|pathlib|collections|typing|sympy)\..*"),
    (r"py:.*", r"(Path|Any|Callable|Mapping|Sequence|Iterator|Iterable|Expr|ndarray)"),
    # internal modules that docstrings mention but the API reference does not cover
    (r"py:.*", r"runtime\.(model\.(rigid|statics)|solvers\.(schedule|statics))(\..*)?"),
    # numpydoc type words and types documented in prose (napoleon makes them references)
    (r"py:class", r"(optional|callable|callables|sequence|mapping|array_like|"
                  r"ResidualProblem|BDFSolution|RodModel|.* of .*|str to .*|"
                  r"\{?\"[a-z]+\"\}?)"),
]

html_theme = "furo"
html_title = "kvrod"
html_static_path = ["_static"]
html_css_files = ["kvrod.css"]

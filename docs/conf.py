"""Sphinx configuration of ssw's documentation (``make docs``; MyST pages, numpydoc API).

The configuration, command-line and API references are generated when the pages are built
(``docs/_ext/ssw_docs.py``); nothing generated is committed.
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))
sys.path.insert(0, str(HERE.parent))

import ssw  # noqa: E402

project = "ssw"
author = "the ssw developers"
copyright = "the ssw developers"
release = version = ssw.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "numpydoc",
    "ssw_docs",
    "ssw_figures",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store"]
suppress_warnings: list[str] = []

# ------------------------------------------------------------------ MyST
myst_enable_extensions = ["colon_fence"]
myst_heading_anchors = 3

# ------------------------------------------------------------------ API (autodoc + numpydoc)
autodoc_default_options = {"members": True, "member-order": "bysource"}
autodoc_typehints = "signature"
autodoc_preserve_defaults = True
autodoc_inherit_docstrings = False
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_attributes_as_param_list = False
# What the build checks in every docstring it renders (docs/CONTRACTS.md, "Docstrings"):
# every public function, class and method has one (GL08); it documents every parameter of
# the signature (PR01; a dataclass's fields are its constructor's), names none the
# signature lacks (PR02), in the signature's order (PR03), each entry with a type (PR04)
# and a description (PR07); what it returns (RT01); one parameter per entry (ssw_docs).
numpydoc_validation_checks = {"GL08", "PR01", "PR02", "PR03", "PR04", "PR07", "RT01"}
# Private names and what Python writes (dataclass and namedtuple methods) are not checked;
# nor type aliases, whose documentation is their ``#:`` comment (an alias of a typing
# construct or of another package's class has no docstring of its own).
numpydoc_validation_exclude = {
    r"\._[^.]*$",
    r"\.__\w+__$",
    r"^ssw\.yamlio\.SAFE_LOADER$",
    r"^ssw\.daq\.model\.Force$",
    r"^ssw\.calibration\.lm\.Evaluate$",
    r"^ssw\.calibration\.residuals\.Derivatives$",
}

# ------------------------------------------------------------------ cross-references
nitpicky = True
# Names of other packages cannot resolve without their inventories (the build runs
# offline); names of ssw must.
nitpick_ignore_regex = [
    (r"py:.*", r"(np|numpy|scipy|h5py|matplotlib|gmsh|petsc4py|mpi4py|jsonschema|yaml"
               r"|snakemake|nidaqmx|nptdms|argparse|collections|typing|types|pathlib|os"
               r"|io|concurrent|threading|subprocess|dataclasses|enum|abc|contextlib"
               r"|functools|itertools|datetime|logging|json|re|builtins|ctypes|hashlib"
               r"|importlib)(\..*)?"),
    (r"py:class", r"(Path|ndarray|NDArray|Any|Callable|Iterator|Iterable|Sequence|Mapping"
                  r"|MutableMapping|Generator|Literal|Self|TypeVar|ArrayLike|Figure|Axes"
                  r"|PETSc\..*|MPI\..*)"),
    # type variables of generic signatures
    (r"py:class", r"ssw(\.\w+)*\.[A-Z]"),
    (r"py:(class|obj)", r"(int|float|str|bool|bytes|dict|list|tuple|set|frozenset|object"
                        r"|complex|None|type|slice|range|callable|optional|default)"),
]

# ------------------------------------------------------------------ HTML
html_theme = "furo"
html_title = f"ssw {release}"
html_static_path: list[str] = []
html_show_sourcelink = False
# Keep "--flag" and quotes as typed (docutils would turn -- into an en dash).
smartquotes = False

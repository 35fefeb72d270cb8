"""Sphinx configuration for the vistrack documentation (`make docs`)."""

from sphinx.util.inspect import TypeAliasForwardRef

import vistrack

project = "vistrack"
author = "vistrack developers"
copyright = "vistrack developers"
release = vistrack.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
templates_path = ["_templates"]
exclude_patterns = ["_build"]

# -- API reference -------------------------------------------------------------------------
# One page per public object, listed from each module's __all__ (the names it re-exports from
# its submodules included).
autosummary_generate = True
autosummary_ignore_module_all = False
autodoc_member_order = "bysource"
# The signatures carry the annotations; the numpydoc Parameters sections already say the types
# in words, so the annotations are not repeated in the descriptions.
autodoc_typehints = "signature"
# numpy.typing.ArrayLike by its name, not the union of protocols it stands for. The others
# are names that modules import for their annotations only (under TYPE_CHECKING): given here,
# the signatures that use them resolve, and Frame and Tracks (re-exported by vistrack.io and
# vistrack.tracking too) link to their one page.
autodoc_type_aliases = {  # see the hooks below
    "ArrayLike": "numpy.typing.ArrayLike",
    "Frame": "~vistrack.types.Frame",
    "Tracks": "~vistrack.types.Tracks",
    "TextIO": "typing.TextIO",
    "Detector": "~vistrack.frontends.Detector",
    "ConfidenceMap": "~vistrack.frontends.ConfidenceMap",
}

# numpydoc would add a table of members to every class, beside the members autodoc already
# documents, and document each attribute twice.
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# -- Markdown guides -----------------------------------------------------------------------
# Anchors like GitHub's for `#` to `###` headings, so that the guides' links such as
# `mot.md#frame-rate` work both here and on GitHub.
myst_heading_anchors = 3

# -- HTML ----------------------------------------------------------------------------------
html_theme = "furo"
html_title = f"vistrack {release}"


# -- Hooks ----------------------------------------------------------------------------------
# Sphinx writes an alias inside another type (``ArrayLike | None``, ``Callable[[ndarray],
# ConfidenceMap]``, in a signature or a property's type) as its placeholder's repr,
# ``TypeAliasForwardRef('numpy.typing.ArrayLike')``: make that repr the alias's name.
TypeAliasForwardRef.__repr__ = lambda self: self.name

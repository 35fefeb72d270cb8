"""Sphinx configuration for the vistrack documentation (`make docs`)."""

import re

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
# numpy.typing.ArrayLike by its name, not the union of protocols it stands for.
autodoc_type_aliases = {"ArrayLike": "numpy.typing.ArrayLike"}  # see _alias_names

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
def _alias_names(app, what, name, obj, options, signature, return_annotation):
    """Sphinx writes an alias in a union (``ArrayLike | None``) as its placeholder's repr,
    ``TypeAliasForwardRef('numpy.typing.ArrayLike')``: write the alias's name instead."""

    def fix(text):
        return re.sub(r"TypeAliasForwardRef\('([\w.]+)'\)", r"\1", text) if text else text

    return fix(signature), fix(return_annotation)


def setup(app):
    app.connect("autodoc-process-signature", _alias_names)

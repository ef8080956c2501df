"""Sphinx configuration of the contactqp documentation (``make docs``).

The build is offline: no intersphinx, no remote images or fonts (the furo theme ships its own).
Warnings are errors (``-W --keep-going``) and every cross-reference must resolve (``-n``);
objects of other projects (numpy, scipy, ...) are not linked, since nothing is fetched to
resolve them.
"""

from __future__ import annotations

import inspect
import sys
from pathlib import Path

import jinja2
import jinja2.sandbox
import numpydoc.docscrape
import numpydoc.docscrape_sphinx
import numpydoc.numpydoc
import sphinx.jinja2glue

import contactqp

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))

project = "contactqp"
author = "the contactqp developers"
copyright = "the contactqp developers"
release = version = contactqp.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "api_pages",
    "registry_page",
    "resolve_names",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "**.ipynb_checkpoints", "auto_examples/*.ipynb"]
html_theme = "furo"
html_title = f"contactqp {release}"
html_static_path: list[str] = []

# API reference: one page per package, written at build time into api/generated/ (api_pages)
autosummary_generate = False
autodoc_typehints = "none"  # numpydoc's Parameters sections give the types
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# every reference must resolve; other projects' objects are not linked (no intersphinx)
nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", r"(numpy|np|scipy|sp|h5py|meshio|skfem|matplotlib|dask|distributed|ansys)\..*"),
    (r"py:.*", r"(qpsolvers|rich\..*|enum\.IntEnum|abc\.ABC)"),
]

myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]

# the gallery: every example is run at build time (all three take seconds); an example that
# is not run here must be run by a test (tests/test_docs.py checks that)
GALLERY_EXECUTED = ("hertz", "cattaneo_mindlin", "cyclic_shear")
sphinx_gallery_conf = {
    "examples_dirs": str(DOCS.parent / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": "/(" + "|".join(GALLERY_EXECUTED) + r")\.py$",
    "download_all_examples": False,
    "remove_config_comments": True,
    "plot_gallery": "True",
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
    "show_signature": False,
    "image_scrapers": ("matplotlib",),
}


def skip_member(app, what, name, obj, skip, options):
    """Leave out the classes and functions a module imports from other packages."""
    module = getattr(obj, "__module__", None)
    if (inspect.isclass(obj) or inspect.isroutine(obj)) and isinstance(module, str):
        if not module.startswith("contactqp"):
            return True
    return None


def _numpydoc_template_once() -> None:
    """numpydoc compiles its Jinja template anew for every docstring (a third of the build
    here): compile it once per builder and hand it to numpydoc's own docstring reader."""
    templates: dict = {}
    folder = Path(numpydoc.docscrape_sphinx.__file__).parent / "templates"

    def get_doc_object(obj, what=None, doc=None, config=None, builder=None):
        if id(builder) not in templates:  # builder None: numpydoc's signature pass
            if builder is None:
                loader = jinja2.FileSystemLoader([str(folder)])
            else:
                loader = sphinx.jinja2glue.BuiltinTemplateLoader()
                loader.init(builder, dirs=[str(folder)])
            environment = jinja2.sandbox.SandboxedEnvironment(loader=loader)
            templates[id(builder)] = environment.get_template("numpydoc_docstring.rst")
        config = {} if config is None else config
        config["template"] = templates[id(builder)]
        return numpydoc.docscrape.get_doc_object(
            obj,
            what=what,
            doc=doc,
            config=config,
            class_doc=numpydoc.docscrape_sphinx.SphinxClassDoc,
            func_doc=numpydoc.docscrape_sphinx.SphinxFunctionDoc,
            obj_doc=numpydoc.docscrape_sphinx.SphinxObjDoc,
        )

    numpydoc.docscrape_sphinx.get_doc_object = get_doc_object
    numpydoc.numpydoc.get_doc_object = get_doc_object


def setup(app):
    app.connect("autodoc-skip-member", skip_member)
    _numpydoc_template_once()

"""Sphinx configuration of the chuteflow documentation.

Build (from the repository root)::

    pip install ".[docs]" && python -m sphinx -W -b html docs docs/_build/html

The API reference is generated from the docstrings (autosummary, recursive over the
``chuteflow`` package, so new modules appear without editing these files); the tutorial and
the gallery are Python scripts in ``examples/`` executed at build time by sphinx-gallery.
"""

from __future__ import annotations

import importlib
import inspect
import os
import pkgutil
import re
import subprocess
import sys
from datetime import date
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
# The checkout's sources win over an installed copy only when no chuteflow is installed.
try:
    import chuteflow
except ImportError:  # building from a checkout without `pip install .`
    sys.path.insert(0, str(ROOT / "src"))
    import chuteflow

sys.path.insert(0, str(DOCS / "_ext"))

# Executed examples: one BLAS thread, no display.
os.environ.setdefault("MPLBACKEND", "Agg")
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

project = "chuteflow"
author = "chuteflow developers"
copyright = f"{date.today().year}, {author}"
release = chuteflow.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "sphinx.ext.mathjax",
    "sphinx.ext.intersphinx",
    "sphinx.ext.viewcode",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = [
    "_build",
    "Thumbs.db",
    ".DS_Store",
    "**.ipynb_checkpoints",
    "tools",
    # included by reproducing.md (a snapshot, not a page of its own)
    "reproduce-snapshot.md",
]
templates_path = ["_templates"]
# Pages listed in index.md's toctrees that may be absent (docs/dns.md, a design note written
# on another branch): dropped from the toctree when the file does not exist.
OPTIONAL_PAGES = ("dns",)

# ------------------------------------------------------------------ Markdown (MyST)
myst_enable_extensions = ["dollarmath", "amsmath", "deflist", "colon_fence"]
myst_heading_anchors = 3

# ------------------------------------------------------------------ API reference
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {
    "members": True,
    # document each object once, where it is defined; package pages list their re-exports
    "ignore-module-all": True,
    "show-inheritance": True,
    "member-order": "bysource",
}
autodoc_typehints = "signature"
autodoc_preserve_defaults = False
autodoc_inherit_docstrings = False
# numpydoc: Attributes are rendered like Parameters (no second description of a dataclass
# field); the members are documented by autodoc, not by numpydoc's tables.
numpydoc_show_class_members = False
numpydoc_attributes_as_param_list = True
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()
# The numpy/scipy/xarray/matplotlib inventories need the network: off by default
# (CHUTEFLOW_DOCS_INTERSPHINX=1 turns them on).
intersphinx_mapping = (
    {
        "python": ("https://docs.python.org/3", None),
        "numpy": ("https://numpy.org/doc/stable", None),
        "xarray": ("https://docs.xarray.dev/en/stable", None),
    }
    if os.environ.get("CHUTEFLOW_DOCS_INTERSPHINX")
    else {}
)

# ------------------------------------------------------------------ executed examples
sphinx_gallery_conf = {
    "examples_dirs": ["../examples/tutorial", "../examples/gallery"],
    "gallery_dirs": ["tutorial", "gallery"],
    "filename_pattern": r"/(plot|run)_",
    "within_subsection_order": "gallery_order.GalleryOrder",  # docs/_ext/gallery_order.py
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "abort_on_example_error": True,
    "show_memory": False,
    "plot_gallery": "True",
    # no reprs of the last expression of a cell (Text(...), <Figure ...>): the scripts print
    "capture_repr": (),
}

# ------------------------------------------------------------------ HTML
html_theme = "pydata_sphinx_theme"
html_title = f"chuteflow {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
}
html_show_sourcelink = False
# MathJax is loaded from its CDN (the Sphinx default). For reading the built pages offline,
# point CHUTEFLOW_DOCS_MATHJAX at a local copy of MathJax 3 (tex-mml-chtml.js).
if os.environ.get("CHUTEFLOW_DOCS_MATHJAX"):
    mathjax_path = os.environ["CHUTEFLOW_DOCS_MATHJAX"]


# ------------------------------------------------------------------ package pages
def _canonical(obj, name: str, package: str) -> str | None:
    """Full dotted name under which ``obj`` (re-exported by ``package``) is documented."""
    module = getattr(obj, "__module__", None)
    if (inspect.isclass(obj) or inspect.isfunction(obj)) and module:
        if module.split(".")[-1].startswith("_") or not module.startswith("chuteflow"):
            return None
        return f"{module}.{getattr(obj, '__qualname__', name)}"
    # data: the public submodule that lists it in its own __all__
    pkg = importlib.import_module(package)
    for info in pkgutil.walk_packages(getattr(pkg, "__path__", []), prefix=package + "."):
        if any(part.startswith("_") for part in info.name.split(".")):
            continue
        mod = sys.modules.get(info.name) or importlib.import_module(info.name)
        if name in getattr(mod, "__all__", ()) and getattr(mod, name, None) is obj and not info.ispkg:
            return f"{info.name}.{name}"
    return None


def _list_reexports(app, what, name, obj, options, lines):
    """On a package's page, a table of the public names it re-exports from its modules."""
    if what != "module" or not hasattr(obj, "__path__"):
        return
    entries = []
    for public in getattr(obj, "__all__", ()):
        if public.startswith("__"):
            continue
        try:
            value = getattr(obj, public)
        except AttributeError:
            continue
        target = _canonical(value, public, name)
        if target and target.rsplit(".", 1)[0] != name:
            entries.append(target)
    if entries:
        lines.extend(["", ".. rubric:: Public names", "", ".. autosummary::", ""])
        # relative to the package (autosummary resolves them against the current module)
        lines.extend(f"   ~{target.removeprefix(name + '.')}" for target in entries)
        lines.append("")


_LITERAL = re.compile(r"(``.*?``|:math:`[^`]*`)")


def _plain_bars(app, what, name, obj, options, lines):
    """Docstrings write |k|, |α(N) − α(N')| as plain text: a bar is not a substitution.

    Bars are escaped outside inline literals, literal blocks and doctest lines, so that the
    docstrings read the same in ``help()`` and on these pages.
    """
    block_indent = None
    for i, line in enumerate(lines):
        stripped = line.lstrip()
        indent = len(line) - len(stripped)
        if block_indent is not None:
            if stripped and indent <= block_indent:
                block_indent = None
            else:
                continue
        if stripped.startswith((">>>", "...")):
            continue
        if "|" in line:
            parts = _LITERAL.split(line)
            lines[i] = "".join(p if j % 2 else p.replace("|", "\\|") for j, p in enumerate(parts))
        if (stripped.endswith("::") and not stripped.startswith("..")) or stripped.startswith(
            (".. math::", ".. code", ".. literal")
        ):
            block_indent = indent


def _optional_pages(app, docname, source):
    """Drop toctree entries of :data:`OPTIONAL_PAGES` whose file does not exist."""
    if docname != root_doc:
        return
    missing = {p for p in OPTIONAL_PAGES if not any((DOCS / f"{p}{ext}").exists() for ext in (".md", ".rst"))}
    if missing:
        source[0] = "\n".join(line for line in source[0].split("\n") if line.strip() not in missing)


def _cli_signature(app, what, name, obj, options, signature, return_annotation):
    """Command functions (typer): show each option's default, not typer's OptionInfo object."""
    if what != "function" or not name.startswith("chuteflow.cli."):
        return None
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return None
    params = []
    for p in sig.parameters.values():
        default = p.default
        if type(default).__name__ in ("OptionInfo", "ArgumentInfo"):
            value = getattr(default, "default", inspect.Parameter.empty)
            default = inspect.Parameter.empty if value is ... else value
        # options are named on the command line: keyword-only, so a required option may follow
        # one with a default
        kind = inspect.Parameter.KEYWORD_ONLY
        params.append(p.replace(default=default, annotation=inspect.Parameter.empty, kind=kind))
    return str(sig.replace(parameters=params, return_annotation=inspect.Signature.empty)), None


def _reread_root(app, env, added, changed, removed):
    """Re-read the entry page on every build: whether an optional page exists may change."""
    return [root_doc]


def setup(app):
    app.connect("env-get-outdated", _reread_root)
    app.connect("autodoc-process-signature", _cli_signature)
    app.connect("source-read", _optional_pages)
    app.connect("autodoc-process-docstring", _plain_bars)
    app.connect("autodoc-process-docstring", _list_reexports)


# ------------------------------------------------------------------ build provenance
try:
    commit = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=True
    ).stdout.strip()
except (OSError, subprocess.CalledProcessError):
    commit = "unknown"
html_context = {"chuteflow_commit": commit}

"""Sphinx configuration of mt-widgets' documentation site.

Built by ``./scripts/build-docs.sh`` (Sphinx with warnings as errors) into docs/_build/html.
At each build this file writes what is generated from the code and the data (never committed):

- the API reference's package pages, docs/api/<package>.md, from every package's ``__all__``
  (docs/_ext/api_names.py); autosummary then writes one page per name into docs/api/generated/;
- the tutorials and the apps' notebooks, copied from tutorials/ and notebooks/ into docs/ (Sphinx
  reads only files under docs/);
- the benchmark figures, docs/benchmarks/_figures/*.png, plotted from docs/benchmarks/*.json;
- the list of the user guide's pages, docs/guide/*.md, whichever exist (docs/guide.md).
"""

from __future__ import annotations

import shutil
import sys
from importlib.metadata import version as installed_version
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path[:0] = [str(ROOT), str(DOCS / "_ext")]

import api_names  # noqa: E402
import benchmark_figures  # noqa: E402
import mathjax  # noqa: E402 (the docs extra's django-static-mathjax: MathJax's files, below)

project = "mt-widgets"
author = "mt-widgets developers"
copyright = "mt-widgets developers"   # noqa: A001 (Sphinx's name)
release = installed_version("mt-widgets")
version = release

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
]

# MyST: the markdown of the README's and the guides' pages, `$...$` maths as in the tutorials,
# and heading anchors so that `[text](page.md#a-heading)` links resolve.
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# The tutorials and the apps' notebooks are executed at every build, shortened by the test suite's
# one switch (their `parameters` cells, tests/notebook_parameters.py), so the site shows the outputs
# of today's code; a notebook that fails fails the build. About 100 s of the build (docs/tutorials.md);
# MT_WIDGETS_DOCS_EXECUTE=0 renders them as committed, without outputs, for a quick draft.
import os  # noqa: E402

EXECUTE = os.environ.get("MT_WIDGETS_DOCS_EXECUTE", "1") != "0"
nb_execution_mode = "force" if EXECUTE else "off"
nb_execution_timeout = 600
nb_execution_cache_path = str(DOCS / "_build" / ".jupyter_cache")
nb_execution_raise_on_error = True
nb_merge_streams = True

exclude_patterns = ["_build", "**/.ipynb_checkpoints", "jupyter_execute", "_ext", "_vendor", "README.md",
                    "benchmarks/_generated"]
templates_path = ["_templates"]
html_static_path = ["_static"]

# MathJax from the site itself, not a CDN: a classroom without internet reads the maths too. The
# files come from the docs extra's django-static-mathjax (MathJax 3, its static files only, no
# Django): the combined TeX component, its fonts and the parts it loads on demand (TeX extensions,
# the menu, the accessibility helpers), copied at each build into _build and served as
# _static/mathjax/ (the speech engine, 15 MB, is left out: the menu's speech options stay off).
MATHJAX_FILES = ("tex-chtml.js", "input", "output/chtml", "ui", "a11y")
mathjax_path = "mathjax/tex-chtml.js"


def _ship_mathjax() -> Path:
    """The folder whose mathjax/ holds the MathJax files the site serves (a static path)."""
    source = Path(mathjax.__file__).parent / "static" / "mathjax" / "es5"
    folder = DOCS / "_build" / "mathjax-static"
    shutil.rmtree(folder, ignore_errors=True)
    for name in MATHJAX_FILES:
        if (source / name).is_dir():
            shutil.copytree(source / name, folder / "mathjax" / name)
        else:
            (folder / "mathjax").mkdir(parents=True, exist_ok=True)
            shutil.copy2(source / name, folder / "mathjax" / name)
    return folder


html_static_path.append(str(_ship_mathjax()))

# The tutorials' widgets from their saved state (nbclient stores it when it executes a notebook),
# drawn without a kernel and without the internet: myst-nb's default loads RequireJS and the widget
# manager (@jupyter-widgets/html-manager) from CDNs, and the manager loads ipycanvas and anywidget
# from another. Here all of them come from the site: the manager is vendored (docs/_vendor/html-manager,
# its SOURCE.txt says what and why), RequireJS is the copy Voila ships (the lab extra), and ipycanvas
# and anywidget are the AMD builds their pip packages install for the classic notebook
# (share/jupyter/nbextensions); docs/_static/widgets/local-modules.js points RequireJS at them.
HTML_MANAGER_VERSION = "1.0.15"


def _ship_widgets() -> Path:
    """The folder whose widgets/ holds what the executed notebooks' widgets need (a static path)."""
    from jupyter_core.paths import jupyter_path

    def installed(*parts: str) -> Path:
        for root in jupyter_path():
            if Path(root, *parts).is_file():
                return Path(root, *parts)
        raise FileNotFoundError(f"{'/'.join(parts)}: not in the Jupyter data folders {jupyter_path()}; "
                                f"the docs extra installs it (pip install -e '.[docs]')")

    folder = DOCS / "_build" / "widgets-static"
    shutil.rmtree(folder, ignore_errors=True)
    target = folder / "widgets"
    shutil.copytree(DOCS / "_vendor" / "html-manager", target, ignore=shutil.ignore_patterns("SOURCE.txt"))
    shutil.copy2(installed("voila", "templates", "base", "static", "require.min.js"), target / "require.min.js")
    for module in ("ipycanvas", "anywidget"):
        (target / module).mkdir()
        shutil.copy2(installed("nbextensions", module, "index.js"), target / module / "index.js")
    return folder


html_static_path.append(str(_ship_widgets()))
nb_ipywidgets_js = {
    "widgets/require.min.js": {},
    "widgets/local-modules.js": {},
    # The CDN attribute names no CDN: a module not on the site fails to load instead of being fetched.
    "widgets/embed-amd.js": {"data-jupyter-widgets-cdn": "./"},
}

html_theme = "pydata_sphinx_theme"
html_title = f"mt-widgets {release}"
html_logo = None
html_theme_options = {
    "navigation_depth": 2,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_sidebars = {"changelog": [], "index": []}

# The API reference: one page per public name, its docstring and its members'.
autosummary_generate = True
autosummary_generate_overwrite = True
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_class_signature = "mixed"
# traitlets' widgets would list every trait of ipywidgets.DOMWidget: members inherited from
# outside mt-widgets are left out (autodoc's default), and so is their long docstring.
autodoc_inherit_docstrings = False
# The docstrings are Google style (Args:, Returns:, Raises:, Attributes:); attributes as a field
# list, since autodoc documents a dataclass's fields as members too (two descriptions would clash).
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_ivar = True
# A docstring's prose types ("(episodes, demonstrations)", "episode, n_episodes") may name an
# attribute that several classes have; Sphinx then warns that the link is ambiguous. Only that
# warning is silenced: a missing page, a broken link or a docstring error still fails the build.
suppress_warnings = ["ref.python"]


def _write_api_pages() -> None:
    """docs/api/<package>.md for every package: its docstring's first paragraph, an autosummary
    table of its own names (one generated page each) and links to the names it re-exports."""
    names = api_names.public_names()
    folder = DOCS / "api"
    for old in folder.glob("mt_widgets*.md"):
        old.unlink()
    for package in api_names.packages():
        own = [n for n in names if n.package == package and not n.is_reexport]
        again = [n for n in names if n.package == package and n.is_reexport]
        # The module's docstring, then its names relative to it (autosummary warns of names that
        # repeat the current module).
        # (In reStructuredText: autosummary finds what to generate only in its own syntax.)
        lines = [f"# `{package}`", "", "```{eval-rst}", f".. automodule:: {package}", "   :no-members:",
                 "   :no-index:", "", f".. currentmodule:: {package}", ""]
        if own:
            lines += [".. autosummary::", "   :toctree: generated", "   :nosignatures:", ""]
            lines += [f"   {n.name}" for n in own]
        lines += ["```", ""]
        if again:
            lines += ["Also exported here, documented where they are defined:", ""]
            lines += [f"- `{n.full_name}`: {{py:obj}}`{n.documented_as}`" for n in again] + [""]
        (folder / f"{package}.md").write_text("\n".join(lines))


def _copy_notebooks() -> None:
    """tutorials/ and notebooks/ (the apps' notebooks, which the start-here tutorial links) into
    docs/tutorials/ and docs/notebooks/, where Sphinx reads them: the committed notebooks, and the
    files next to them that they read (the capstone's and the online pilot's protocols)."""
    for folder in ("tutorials", "notebooks"):
        target = DOCS / folder
        shutil.rmtree(target, ignore_errors=True)
        target.mkdir()
        for path in sorted((ROOT / folder).glob("*.ipynb")) + sorted((ROOT / folder).glob("*.toml")):
            shutil.copy2(path, target / path.name)
            if path.suffix == ".ipynb":
                _titled(target / path.name, f"{folder}/{path.name}")
            if EXECUTE and path.suffix == ".ipynb":
                _shorten(path, target / path.name)


def _titled(copy: Path, name: str) -> None:
    """An app's notebook (a page served by Voila) starts with code, not a heading: the copy gets its
    file's name as its title, as Sphinx needs one for the contents."""
    import json

    content = json.loads(copy.read_text())
    first = next((cell for cell in content["cells"] if cell["cell_type"] == "markdown"), None)
    if first is not None and "".join(first["source"]).lstrip().startswith("# "):
        return
    content["cells"].insert(0, {"cell_type": "markdown", "metadata": {}, "source": [f"# `{name}`"]})
    copy.write_text(json.dumps(content, indent=1))


def _shorten(source: Path, copy: Path) -> None:
    """The test run's one switch (tests/notebook_parameters.py) on a copy to execute: its cell tagged
    ``parameters`` gets the test run's values (fewer simulated studies, the simulated arm at 50x,
    a synthetic novice in the capstone, scratch folders instead of ~/mt-widgets-lessons)."""
    import json

    from tests.notebook_parameters import NOTEBOOK_PARAMETERS, TAG, Scratch, injected_source, scratch_root

    notebook = source.relative_to(ROOT).as_posix()
    values = NOTEBOOK_PARAMETERS.get(notebook)
    if values is None:
        return
    root = scratch_root(ROOT) / "docs"
    for value in values.values():
        if isinstance(value, Scratch):
            shutil.rmtree(root / value.name, ignore_errors=True)
            (root / value.name).mkdir(parents=True)
    content = json.loads(copy.read_text())
    [cell] = [cell for cell in content["cells"] if TAG in cell.get("metadata", {}).get("tags", [])]
    cell["source"] = injected_source("".join(cell["source"]), values, root, notebook)
    copy.write_text(json.dumps(content, indent=1))


def _guide_pages(app, docname, source) -> None:
    """docs/guide.md lists the guide's pages that exist (docs/guide/*.md, written by whoever builds
    the feature): a toctree glob that matched nothing would be a warning, so the list is written here."""
    if docname != "guide":
        return
    pages = sorted(path.stem for path in (DOCS / "guide").glob("*.md"))
    if pages:
        toctree = "\n".join(["```{toctree}", ":maxdepth: 1", ""] + [f"guide/{page}" for page in pages] + ["```"])
    else:
        toctree = "No guide pages have been written yet."
    source[0] = source[0].replace("<!-- guide pages -->", toctree)


def _plural_literals(app, what, name, obj, options, lines) -> None:
    """The docstrings write a plural as ````Phase``s``; reStructuredText wants a literal to end
    before a space or punctuation, so an escaped space (nothing in the output) goes between."""
    import re

    def escape(line: str) -> str:
        # Literals paired from the left, as reStructuredText reads them; only one followed by a
        # letter or digit gets the escaped space.
        return re.sub(r"``[^`]+``(?=([A-Za-z0-9])?)",
                      lambda match: match.group(0) + ("\\ " if match.group(1) else ""), line)

    lines[:] = [escape(line) for line in lines]


def _constant_docs(app, what, name, obj, options, lines) -> None:
    """A constant's documentation is the ``#:`` comment above its assignment in the module that
    defines it; autodoc, reading the package that re-exports it, would show its type's docstring
    instead (``dict() -> new empty dictionary``). So it is looked up in the package's modules."""
    if what not in ("data", "attribute") or not isinstance(obj, (dict, tuple, list, str, int, float, frozenset, set)):
        return
    if lines and "\n".join(lines).strip() != (type(obj).__doc__ or "").strip():
        return
    import importlib
    import pkgutil

    from sphinx.pycode import ModuleAnalyzer

    package, _, short = name.rpartition(".")
    try:
        module = importlib.import_module(package)
    except ImportError:
        return
    candidates = [package] + [info.name for info in pkgutil.walk_packages(getattr(module, "__path__", []),
                                                                           prefix=f"{package}.")]
    for candidate in candidates:
        try:
            docs = ModuleAnalyzer.for_module(candidate).find_attr_docs()
        except Exception:   # a module the analyzer cannot read (compiled, missing source)
            continue
        if ("", short) in docs:
            lines[:] = [line for line in docs[("", short)]]
            return
    lines[:] = []


_write_api_pages()
_copy_notebooks()
benchmark_figures.plot_all(DOCS / "benchmarks", DOCS / "benchmarks" / "_generated")


def setup(app):
    app.connect("source-read", _guide_pages)
    app.connect("autodoc-process-docstring", _constant_docs)
    app.connect("autodoc-process-docstring", _plural_literals)
    return {"parallel_read_safe": True}

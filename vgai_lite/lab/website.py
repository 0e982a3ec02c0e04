"""The book as a static website: ``python -m vgai_lite site --out site/``.

Built with Sphinx and MyST-NB from the committed, executed notebooks, which are **not** executed
again (``nb_execution_mode = "off"``): the site shows exactly the outputs a reader of the repository
sees. Why Sphinx + MyST-NB rather than Jupyter Book: Jupyter Book 1 is a thin layer over exactly
these packages (its configuration would only be translated into the ``conf.py`` written here), and
Jupyter Book 2 builds with a Node.js toolchain that this Python-only book would then need. Sphinx
gives the rest for free: navigation between chapters (the book theme's sidebar and next/previous
links), full-text search that runs in the browser, and MathJax for the equations.

Offline: everything the pages load is in the built folder. MathJax comes from the
``sphinx-mathjax-offline`` package instead of a CDN, widget JavaScript (ipywidgets, from a CDN by
default) is left out because no committed output needs it, and the theme's fonts and icons are
bundled by the theme. The site's packages are an optional group (``requirements-site.txt``); the
book itself never imports them.

Pages: the README is the landing page, then notebooks 00-08 in order. Each notebook page starts
with links to download the notebook (with its outputs) and its student copy (exercises stubbed,
``course.make_student_copies``).
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Optional, Union

import nbformat

from ..book import ROOT
from .course import make_student_copies

INSTALL = "pip install -r requirements-site.txt"
SITE_PACKAGES = ("sphinx", "myst_nb", "sphinx_book_theme")


def check_installed() -> None:
    """Raise a clear error unless the site's optional packages are importable."""
    import importlib.util

    missing = [p for p in SITE_PACKAGES if importlib.util.find_spec(p) is None]
    if importlib.util.find_spec("sphinx-mathjax-offline") is None:
        missing.append("sphinx-mathjax-offline")
    if missing:
        raise SystemExit(f"building the site needs {', '.join(missing)}: {INSTALL} (an optional group; "
                         "the book itself does not need it)")


CONF = '''# Written by vgai_lite.lab.website: the Sphinx configuration of the book's static site.
project = "vgai-lite"
author = "the vgai-lite authors"
copyright = "the vgai-lite authors"
extensions = ["myst_nb", "sphinx-mathjax-offline"]
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3
nb_execution_mode = "off"          # the committed outputs, never re-executed
nb_ipywidgets_js = {}              # no widget JavaScript from a CDN: no committed output needs it
nb_merge_streams = True
nb_render_markdown_format = "myst"  # Markdown outputs (the tables and prose cells display) parsed as MyST: tables, maths
html_theme = "sphinx_book_theme"
html_title = "vgai-lite: learning VGAI, notebook by notebook"
html_theme_options = {"use_download_button": False, "show_toc_level": 2,
                      "home_page_in_toc": True, "navigation_with_keys": False}
html_context = {"default_mode": "light"}   # the theme otherwise logs an error on a first visit
html_favicon = "favicon.png"
html_show_sourcelink = False
html_copy_source = False           # each page links its own downloads instead (see website.py)
suppress_warnings = ["myst.header", "myst.xref_missing", "misc.highlighting_failure", "mystnb.unknown_mime_type"]
exclude_patterns = ["_build", "downloads"]
'''


def _index(readme: str, pages: list[str]) -> str:
    """The landing page: the README, with the chapters' table of contents (hidden: the sidebar shows it)."""
    toc = "\n".join(["", "```{toctree}", ":hidden:", ":maxdepth: 1", ""] + pages + ["```", ""])
    return readme + "\n" + toc


def _with_downloads(nb: nbformat.NotebookNode, name: str) -> nbformat.NotebookNode:
    """The notebook with a first cell linking its two downloads (the notebook, its student copy)."""
    links = (f"*Download:* {{download}}`this notebook <downloads/{name}.ipynb>` (with its outputs) · "
             f"{{download}}`its student copy <downloads/student/{name}.ipynb>` (exercises to fill in) · "
             "run it with `python -m vgai_lite lab` after the README's set-up.")
    cell = nbformat.v4.new_markdown_cell(links)
    nb = nbformat.from_dict(json.loads(json.dumps(nb)))
    title = next((i for i, c in enumerate(nb.cells) if c.cell_type == "markdown"), 0)
    src = nb.cells[title].source
    if src.lstrip().startswith("# "):  # keep the title first: split it from the rest of its cell
        head, _, rest = src.lstrip().partition("\n")
        nb.cells[title].source = head
        nb.cells.insert(title + 1, cell)
        if rest.strip():
            nb.cells.insert(title + 2, nbformat.v4.new_markdown_cell(rest.strip("\n")))
    else:
        nb.cells.insert(0, cell)
    return nb


def _favicon(path: Path) -> None:
    """The site's icon: five drones in the book's VGAI orange (drawn here, so no file to ship)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(0.32, 0.32), dpi=100)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.scatter([0.2, 0.5, 0.8, 0.35, 0.65], [0.3, 0.2, 0.35, 0.7, 0.75], s=18, color="tab:orange")
    ax.set_xlim(0, 1), ax.set_ylim(0, 1), ax.axis("off")
    fig.savefig(path, transparent=True)
    plt.close(fig)


def prepare(src: Path, notebooks: Optional[Path] = None) -> list[str]:
    """Write the Sphinx source folder ``src``: conf.py, index.md (the README), the notebooks with
    their download links, and the downloads. Returns the page names in order."""
    notebooks = Path(notebooks or ROOT / "notebooks")
    paths = sorted(notebooks.glob("[0-9][0-9]_*.ipynb"))
    if not paths:
        raise FileNotFoundError(f"no notebooks NN_*.ipynb in {notebooks}")
    if src.exists():
        shutil.rmtree(src)
    (src / "downloads" / "student").mkdir(parents=True)
    (src / "conf.py").write_text(CONF)
    _favicon(src / "favicon.png")
    make_student_copies(src / "downloads" / "student", source=notebooks)
    pages = []
    for p in paths:
        nb = nbformat.read(p, as_version=4)
        shutil.copy2(p, src / "downloads" / p.name)
        nbformat.write(_with_downloads(nb, p.stem), src / p.name)
        pages.append(p.stem)
    readme = (ROOT / "README.md").read_text()
    readme = readme.replace("](notebooks/", "](")  # the README's links into notebooks/ point at the pages
    (src / "index.md").write_text(_index(readme, pages))
    return pages


MATHJAX_KEEP = ("tex-chtml.js", "output/chtml", "input/tex", "a11y", "ui")
"""What the pages load of the offline MathJax (sphinx-mathjax-offline copies all 24 MB of it):
the TeX-to-HTML bundle it points ``mathjax_path`` at, its fonts, the TeX extensions it loads on
demand, and the menu with its accessibility parts."""


def prune_mathjax(out: Path) -> None:
    root = out / "_static" / "mathjax"
    if not root.is_dir():
        raise FileNotFoundError(f"no offline MathJax in {root}: is sphinx-mathjax-offline installed? {INSTALL}")
    for p in sorted(root.rglob("*"), reverse=True):
        rel = p.relative_to(root).as_posix()
        keep = any(rel == k or rel.startswith(k + "/") or k.startswith(rel + "/") for k in MATHJAX_KEEP)
        if not keep:
            shutil.rmtree(p) if p.is_dir() else p.unlink()


def build(out: Union[str, Path] = "site", notebooks: Optional[Union[str, Path]] = None,
          quiet: bool = True) -> dict:
    """Build the site into ``out`` (its pages at out/index.html). Returns the build's figures:
    seconds, pages, size in MB."""
    check_installed()
    out = Path(out).resolve()
    src = out.parent / f".{out.name}-source"
    start = time.perf_counter()
    pages = prepare(src, notebooks and Path(notebooks))
    if out.exists():
        shutil.rmtree(out)
    cmd = [sys.executable, "-m", "sphinx", "-b", "html", "-d", str(src / ".doctrees"), str(src), str(out)]
    cmd += ["-q"] if quiet else []
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"sphinx failed ({done.returncode}):\n{done.stderr[-4000:]}")
    prune_mathjax(out)
    size = sum(f.stat().st_size for f in out.rglob("*") if f.is_file()) / 2 ** 20
    shutil.rmtree(src)
    return {"out": str(out), "pages": pages, "seconds": round(time.perf_counter() - start, 1),
            "megabytes": round(size, 1), "warnings": [w for w in done.stderr.splitlines() if "WARNING" in w]}

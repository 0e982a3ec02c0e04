"""The book as a website (``python -m vgai_lite site``), opened in a real headless Chromium.

The site is built from the committed notebooks into a temporary folder and served over HTTP on
localhost. On the landing page and every chapter: the equations are typeset by MathJax (no raw TeX,
no MathJax error), every image has loaded, the browser logs no error (no failed load either: the site
needs no network), the chapter links lead to the next chapter, search finds pages, and each chapter's
two downloads (the notebook, its student copy) are there. Needs the site's optional packages
(requirements-site.txt) and Chromium: skipped without them, except under ``.ci/run``
(``VGAI_LITE_REQUIRE_SITE=1``), which installs both.
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest
from devtools import CHROMIUM, DevTools, free_port, start_chromium, stop, wait_http

pytestmark = pytest.mark.slow  # `pytest -m "not slow"` skips this file

ROOT = Path(__file__).resolve().parent.parent
CHAPTERS = sorted(p.stem for p in (ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))
LOAD_SECONDS = 60


def _need(ok: bool, what: str) -> None:
    if not ok:
        if os.environ.get("VGAI_LITE_REQUIRE_SITE") == "1":
            pytest.fail(f"the site test must run here: {what} (.ci/run installs it)")
        pytest.skip(what)


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    _need(importlib.util.find_spec("sphinx") is not None and importlib.util.find_spec("myst_nb") is not None,
          "the site's packages are not installed: pip install -r requirements-site.txt")
    _need(CHROMIUM is not None, "no Chromium on this machine (apt-get install chromium)")
    from vgai_lite.lab import website

    tmp = tmp_path_factory.mktemp("site")
    info = website.build(tmp / "site")
    port, cdp = free_port(), free_port()
    server = subprocess.Popen([sys.executable, "-m", "http.server", str(port), "--bind", "127.0.0.1",
                               "--directory", info["out"]], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    chrome = start_chromium(cdp, tmp / "chromium")
    try:
        base = f"http://127.0.0.1:{port}"
        wait_http(base + "/index.html", 30, server, "the site's HTTP server")
        targets = json.loads(wait_http(f"http://127.0.0.1:{cdp}/json", 30, chrome, "Chromium"))
        tools = DevTools(next(t for t in targets if t.get("type") == "page")["webSocketDebuggerUrl"])
        for domain in ("Page", "Runtime", "Log"):
            tools.call(f"{domain}.enable")
        yield tools, base, info
        tools.close()
    finally:
        stop(chrome, server)


PAGE_STATE = """(async () => {
  if (document.readyState !== 'complete') return {ready: false};
  if (window.MathJax && MathJax.startup && MathJax.startup.promise) await MathJax.startup.promise;
  const maths = [...document.querySelectorAll('.math')];
  const imgs = [...document.querySelectorAll('article img, main img')];
  const next = document.querySelector('a.right-next');
  return {ready: true, title: document.title,
          maths: maths.length, typeset: maths.filter(m => m.querySelector('mjx-container')).length,
          mathErrors: document.querySelectorAll('mjx-merror, .MathJax_Error').length,
          rawTables: [...document.querySelectorAll('.cell_output')].filter(o => o.innerText.includes('|---|')).length,
          images: imgs.length, loaded: imgs.filter(i => i.complete && i.naturalWidth > 0).length,
          next: next ? next.getAttribute('href') : null,
          downloads: [...document.querySelectorAll('a.download, a.reference.download')].map(a => a.getAttribute('href')),
          nav: [...document.querySelectorAll('nav.bd-links a.reference')].map(a => a.getAttribute('href'))};
})()"""


def _open(tools, url: str) -> dict:
    tools.call("Page.navigate", url=url)
    end, state = time.time() + LOAD_SECONDS, {}
    while time.time() < end:
        state = tools.js(PAGE_STATE) or {}
        if state.get("ready") and state["typeset"] == state["maths"] and state["loaded"] == state["images"]:
            break
        time.sleep(0.3)
    return state


def test_the_site_is_small_and_every_chapter_is_a_page(site):
    tools, base, info = site
    assert info["pages"] == CHAPTERS
    assert info["megabytes"] <= 50, f"the site is {info['megabytes']} MB (target: at most 50 MB)"
    state = _open(tools, base + "/index.html")
    assert "vgai-lite" in state["title"]
    chapters = [h.split("#")[0] for h in state["nav"] if h.split("#")[0]]  # "#": the landing page itself
    assert chapters == [f"{c}.html" for c in CHAPTERS], state["nav"]
    assert not tools.errors()


@pytest.mark.parametrize("chapter", CHAPTERS)
def test_a_reader_sees_equations_figures_and_the_way_on(site, chapter):
    tools, base, _ = site
    tools.errors()
    state = _open(tools, f"{base}/{chapter}.html")
    assert state.get("ready"), f"{chapter}: the page did not load within {LOAD_SECONDS} s"
    assert state["typeset"] == state["maths"], f"{chapter}: {state['maths'] - state['typeset']} equations not typeset"
    assert state["mathErrors"] == 0, f"{chapter}: MathJax reports an error in an equation"
    assert state["rawTables"] == 0, f"{chapter}: {state['rawTables']} outputs show a Markdown table as raw text"
    if chapter[:2] in ("01", "02", "03", "05", "06"):
        assert state["maths"] > 0, f"{chapter}: no equation found on a chapter that has them"
    if chapter[:2] not in ("09", "10"):  # the closing chapter and the appendix are tables and prose only
        assert state["images"] > 0, f"{chapter}: no figure found on a chapter that has them"
    assert state["loaded"] == state["images"], \
        f"{chapter}: {state['loaded']} of {state['images']} images loaded"
    errors = tools.errors()
    assert not errors, f"{chapter}: the browser logged errors: {errors[:5]}"
    i = CHAPTERS.index(chapter)
    if i + 1 < len(CHAPTERS):
        assert state["next"] == f"{CHAPTERS[i + 1]}.html", f"{chapter}: the next link is {state['next']}"
    names = sorted(h.rsplit("/", 1)[-1] for h in state["downloads"])
    assert names == [f"{chapter}.ipynb"] * 2, f"{chapter}: downloads {state['downloads']}"
    outputs = []
    for href in state["downloads"]:
        with urllib.request.urlopen(f"{base}/{href}") as r:
            nb = json.loads(r.read())
        assert nb["nbformat"] == 4 and nb["cells"]
        outputs.append(sum(len(c.get("outputs", [])) for c in nb["cells"] if c["cell_type"] == "code"))
    assert min(outputs) == 0 < max(outputs), f"{chapter}: expected the executed notebook and its cleared student copy"


def test_search_finds_the_chapters(site):
    tools, base, _ = site
    tools.call("Page.navigate", url=f"{base}/search.html?q=flocking")
    end, hits = time.time() + LOAD_SECONDS, []
    while time.time() < end and len(hits) < 3:  # Sphinx's search lists its hits one by one as it finds them
        time.sleep(0.5)
        hits = tools.js("[...document.querySelectorAll('#search-results li a')].map(a => a.getAttribute('href'))") or []
    assert len(hits) >= 3, f"search for 'flocking' found {hits}"
    assert not tools.errors()


def test_without_the_site_packages_the_command_says_how_to_install_them(monkeypatch):
    import importlib.util as iu

    from vgai_lite.lab import website

    monkeypatch.setattr(iu, "find_spec", lambda name, *a: None)
    with pytest.raises(SystemExit, match="requirements-site.txt"):
        website.check_installed()


RAW_LATEX = ("$$", "\\mathbf", "\\frac", "\\tag{", "\\begin{", "\\sum", "\\mathcal", "\\big")
"""What a page would show if MathJax had not typeset an equation."""


def _plain(text: str) -> str:
    """Whitespace collapsed and typographic ligatures undone (a PDF's text layer writes "ﬂ" for "fl")."""
    import re
    import unicodedata

    return re.sub(r"\s+", " ", unicodedata.normalize("NFKC", text)).strip()


def test_the_book_prints_as_one_pdf_with_every_chapter_where_its_contents_say(site, tmp_path):
    """``python -m vgai_lite pdf``: the site printed by Chromium. Each chapter's title is on the page
    the contents give for it, no page shows raw TeX, the outline lists the chapters, figures are there."""
    import nbformat
    from pypdf import PdfReader

    from vgai_lite.lab import pdf

    _, _, built = site
    info = pdf.build(tmp_path / "book.pdf", site=built["out"])
    reader = PdfReader(info["out"])
    assert len(reader.pages) == info["pages"]
    assert 12 + 2 <= info["pages"] <= 600, f"{info['pages']} pages: expected the landing page and 11 chapters"
    titles = [nbformat.read(ROOT / "notebooks" / f"{c}.ipynb", as_version=4).cells[0].source.splitlines()[0]
              .lstrip("# ").strip() for c in CHAPTERS]
    assert [t.replace("’", "'") for t, _ in info["chapters"]][1:] == titles, info["chapters"]  # Sphinx's smart quotes
    texts = [_plain(p.extract_text() or "") for p in reader.pages]
    contents = texts[1]
    for title, page in info["chapters"]:
        assert _plain(title) in contents and str(page) in contents
        assert _plain(title) in texts[page - 1], f"{title!r} is not on page {page}, where the contents put it"
    raw = [(i + 1, s) for i, t in enumerate(texts) for s in RAW_LATEX if s in t]
    assert not raw, f"raw TeX on pages {raw[:8]}"
    assert [o.title for o in reader.outline] == [t for t, _ in info["chapters"]]
    images = sum(len(p.images) for p in reader.pages)  # image objects, counted without decoding them
    figures = sum(1 for c in CHAPTERS for cell in nbformat.read(ROOT / "notebooks" / f"{c}.ipynb", as_version=4).cells
                  if cell.cell_type == "code" for o in cell.get("outputs", [])
                  if any(k.startswith("image/") for k in o.get("data", {})))
    assert images >= figures, f"{images} images in the PDF, {figures} figures and animations in the notebooks"
    assert info["animations"] >= 3, "the book's animations (01, 04, 06, ...) are printed as their first frame"

"""The whole book as one offline PDF: ``python -m vgai_lite pdf --out book.pdf``.

How it is made: the book's website (``website.build``: Sphinx + MyST-NB from the committed, executed
notebooks, MathJax bundled, nothing executed again) is served on localhost, and headless Chromium
prints each page (the DevTools protocol's ``Page.printToPDF``) once MathJax has typeset every
equation and every image has loaded. Each animation (a GIF) is printed as its first frame. pypdf
joins the pages behind a title page and a table of contents that gives each chapter's first page,
and the PDF's outline (its bookmarks) lists the chapters.

Why Chromium and not Sphinx's LaTeX builder: LaTeX needs a TeX distribution of several hundred MB
and would typeset the notebooks' outputs (tables drawn as HTML, prose rendered by code) its own way;
Chromium is the browser the book's tests already drive, and it prints exactly what a reader of the
website sees. Needs the site's optional packages (requirements-site.txt, pypdf among them) and a
Chromium (``apt-get install chromium``).
"""

from __future__ import annotations

import base64
import html
import io
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Optional, Union

from . import website
from .chromium import CHROMIUM, DevTools, free_port, start_chromium, stop, wait_http

LOAD_SECONDS = 90
"""How long a page may take to load and typeset before printing gives up with an error."""

PRINT = dict(printBackground=True, paperWidth=8.27, paperHeight=11.69,  # A4, in inches
             marginTop=0.6, marginBottom=0.6, marginLeft=0.55, marginRight=0.55, preferCSSPageSize=False)

PRINT_CSS = """
.bd-header, .bd-sidebar-primary, .bd-sidebar-secondary, .header-article, .bd-footer, .bd-footer-article,
.prev-next-area, .bd-header-announcement, .skip-link, .headerlink, #pst-back-to-top, .search-button,
.article-header-buttons { display: none !important; }
.bd-main, .bd-content, .bd-article-container, .bd-page-width { max-width: 100% !important; width: 100% !important;
  margin: 0 !important; padding: 0 !important; }
div, pre, table { break-inside: auto !important; }
img { max-width: 100% !important; break-inside: avoid; }
pre, .highlight pre, div.output pre { white-space: pre-wrap !important; overflow-wrap: anywhere; overflow: visible !important; }
.highlight, div.cell_input, div.cell_output, div.output, .table-wrapper, .pst-scrollable-table-container {
  overflow: visible !important; max-height: none !important; }
table { font-size: 0.72em; }
h1, h2, h3 { break-after: avoid; }
"""
"""What printing leaves out of a web page (the navigation bars, the sidebars, the buttons) and how
figures and tables break across pages."""

READY = """(async () => {
  if (document.readyState !== 'complete') return {ready: false};
  if (window.MathJax && MathJax.startup && MathJax.startup.promise) await MathJax.startup.promise;
  const maths = [...document.querySelectorAll('.math')];
  const imgs = [...document.querySelectorAll('img')];
  const h1 = document.querySelector('article h1, main h1, h1');
  return {ready: true, title: h1 ? h1.textContent.replace(/[#¶]\\s*$/, '').trim() : document.title,
          maths: maths.length, typeset: maths.filter(m => m.querySelector('mjx-container')).length,
          images: imgs.length, loaded: imgs.filter(i => i.complete && i.naturalWidth > 0).length};
})()"""


def check_installed() -> None:
    """Raise a clear error unless the site's packages, pypdf and a Chromium are there."""
    import importlib.util

    website.check_installed()
    if importlib.util.find_spec("pypdf") is None:
        raise SystemExit(f"the PDF needs pypdf: {website.INSTALL} (an optional group)")
    if CHROMIUM is None:
        raise SystemExit("the PDF is printed by Chromium, which this machine lacks (apt-get install chromium)")


def first_frames(site: Path) -> int:
    """Replace every animated GIF of the built site by its first frame (a print shows one frame, and
    this one is the same on every run). Returns how many animations it froze."""
    from PIL import Image

    frozen = 0
    for path in sorted(site.rglob("*.gif")):
        with Image.open(path) as im:
            if getattr(im, "n_frames", 1) <= 1:
                continue
            im.seek(0)
            first = im.convert("RGB")
        first.save(path, format="GIF")
        frozen += 1
    return frozen


def _print_page(tools: DevTools, url: str) -> tuple[bytes, str]:
    """One page printed once it is typeset and loaded: (PDF bytes, the page's first heading)."""
    tools.call("Page.navigate", url=url)
    end, state = time.time() + LOAD_SECONDS, {}
    while time.time() < end:
        state = tools.js(READY) or {}
        if state.get("ready") and state["typeset"] == state["maths"] and state["loaded"] == state["images"]:
            break
        time.sleep(0.3)
    else:
        raise TimeoutError(f"{url} was not typeset and loaded within {LOAD_SECONDS} s: {state}")
    tools.js(f"(() => {{ const s = document.createElement('style'); s.textContent = {json.dumps(PRINT_CSS)};"
             " document.head.appendChild(s); return true; })()")
    pdf = tools.call("Page.printToPDF", **PRINT)["data"]
    return base64.b64decode(pdf), state["title"]


def _front_matter(chapters: list[tuple[str, int]], pages_before: int) -> str:
    """The title page and the table of contents as HTML: each chapter with the PDF page it starts on."""
    rows, page = [], pages_before + 1
    for title, n in chapters:
        rows.append(f"<tr><td>{html.escape(title)}</td><td class='p'>{page}</td></tr>")
        page += n
    return f"""<!doctype html><html><head><meta charset="utf-8"><style>
body {{ font-family: sans-serif; margin: 0 1em; }} h1 {{ font-size: 2.1em; margin-top: 30%; }}
.sub {{ font-size: 1.15em; color: #444; }} .toc {{ break-before: page; }} table {{ width: 100%; border-collapse: collapse; }}
td {{ padding: 0.35em 0; border-bottom: 1px dotted #bbb; }} td.p {{ text-align: right; width: 4em; }}
</style></head><body>
<h1>vgai-lite: learning VGAI, notebook by notebook</h1>
<p class="sub">A notebook book that teaches and reproduces <i>VGAI: End-to-End Learning of Vision-Based
Decentralized Controllers for Robot Swarms</i> (Hu, Gama, Chen, Wang, Ribeiro, Sadler; ICASSP 2021,
arXiv:2002.02308), printed from the committed, executed notebooks.</p>
<div class="toc"><h2>Contents</h2><table>{''.join(rows)}</table></div></body></html>"""


def _serve(folder: Path) -> tuple[subprocess.Popen, str]:
    port = free_port()
    server = subprocess.Popen([sys.executable, "-m", "http.server", str(port), "--bind", "127.0.0.1",
                               "--directory", str(folder)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    base = f"http://127.0.0.1:{port}"
    wait_http(base + "/index.html", 30, server, "the book's HTTP server")
    return server, base


def print_site(site: Union[str, Path], out: Union[str, Path], pages: list[str]) -> dict:
    """Print the built site ``site`` (its landing page, then ``pages`` in order) to one PDF ``out``.
    Returns the figures of the print: pages, chapters with their first page, animations frozen, seconds."""
    from pypdf import PdfReader, PdfWriter

    start, site, out = time.perf_counter(), Path(site), Path(out)
    frozen = first_frames(site)
    with tempfile.TemporaryDirectory() as tmp:
        (site / "_front.html").unlink(missing_ok=True)
        server, base = _serve(site)
        cdp = free_port()
        chrome = start_chromium(cdp, Path(tmp) / "profile")
        try:
            targets = json.loads(wait_http(f"http://127.0.0.1:{cdp}/json", 30, chrome, "Chromium"))
            tools = DevTools(next(t for t in targets if t.get("type") == "page")["webSocketDebuggerUrl"])
            for domain in ("Page", "Runtime"):
                tools.call(f"{domain}.enable")
            printed = [_print_page(tools, f"{base}/{name}.html") for name in ["index"] + pages]
            chapters = [(title, len(PdfReader(io.BytesIO(pdf)).pages)) for pdf, title in printed]
            front_pages = 2  # the title page and the contents (checked below)
            (site / "_front.html").write_text(_front_matter(chapters, front_pages))
            front, _ = _print_page(tools, f"{base}/_front.html")
            tools.close()
        finally:
            stop(chrome, server)
    if len(PdfReader(io.BytesIO(front)).pages) != front_pages:
        raise RuntimeError("the contents no longer fit on one page: count its pages before numbering the chapters")
    writer = PdfWriter()
    writer.append(io.BytesIO(front))
    first, starts = front_pages, []
    for (pdf, title), (_, n) in zip(printed, chapters):
        writer.append(io.BytesIO(pdf))
        writer.add_outline_item(title=title, page_number=first)
        starts.append((title, first + 1))
        first += n
    writer.add_metadata({"/Title": "vgai-lite: learning VGAI, notebook by notebook", "/Author": "the vgai-lite authors"})
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out, "wb") as f:
        writer.write(f)
    return {"out": str(out), "pages": first, "chapters": starts, "animations": frozen,
            "seconds": round(time.perf_counter() - start, 1)}


def build(out: Union[str, Path] = "book.pdf", notebooks: Optional[Union[str, Path]] = None,
          site: Optional[Union[str, Path]] = None) -> dict:
    """The book as one PDF at ``out``, from the committed notebooks (or ``notebooks``). ``site``: a
    site built before by ``website.build`` to print (a copy of it: the original is left as it was);
    by default the site is built here, in a temporary folder."""
    check_installed()
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        copy = Path(tmp) / "site"
        if site is None:
            info = website.build(copy, notebooks)
            pages = info["pages"]
        else:
            shutil.copytree(site, copy)
            pages = sorted(p.stem for p in copy.glob("[0-9][0-9]_*.html"))
        result = print_site(copy, out, pages)
    return {**result, "seconds": round(time.perf_counter() - start, 1)}

"""What a student sees: every committed notebook opened in JupyterLab, in a real headless Chromium.

The book is opened as ``python -m vgai_lite lab`` opens it (the book's notebooks trusted first), and
Chromium is driven through its DevTools protocol (a websocket; no driver). For each notebook: every
image output of the file (figures and the GIF animations) is drawn in the page and has loaded, no
error dialog shows, no traceback is shown, and in notebook 04 the meshcat 3-D view is there (its
iframe with the viewer's canvas). Needs Chromium (Debian's ``chromium``; ``.ci/run`` installs it):
without it the test is skipped, except under ``.ci/run`` (``VGAI_LITE_REQUIRE_BROWSER=1``), where it fails.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import nbformat
import pytest
from devtools import CHROMIUM, DevTools, start_chromium
from devtools import free_port as _free_port, wait_http as _wait_http

pytestmark = pytest.mark.slow  # `pytest -m "not slow"` skips this file

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))
IMAGE_MIMES = ("image/png", "image/gif", "image/jpeg", "image/svg+xml")
LOAD_SECONDS = 90
LOADS_FROM_NETWORK = re.compile(r"""(?:src|href)\s*=\s*(?:["']|&quot;|\\")\s*(?:https?:)?//""", re.I)


@pytest.fixture(scope="module")
def book_in_a_browser(tmp_path_factory):
    if CHROMIUM is None:
        if os.environ.get("VGAI_LITE_REQUIRE_BROWSER") == "1":
            pytest.fail("the browser test must run here: install Debian's chromium (.ci/run does)")
        pytest.skip("no Chromium on this machine (apt-get install chromium); CI runs this test")
    tmp = tmp_path_factory.mktemp("browser")
    env = {**os.environ, "JUPYTER_DATA_DIR": str(tmp / "data"), "JUPYTER_CONFIG_DIR": str(tmp / "config"),
           "JUPYTER_RUNTIME_DIR": str(tmp / "runtime"), "JUPYTERLAB_SETTINGS_DIR": str(tmp / "settings"),
           "JUPYTERLAB_WORKSPACES_DIR": str(tmp / "workspaces"), "VGAI_LITE_QUICK": "1"}
    # every cell in the page (no virtual scrolling), no news or update prompts
    tracker = tmp / "settings" / "@jupyterlab" / "notebook-extension" / "tracker.jupyterlab-settings"
    tracker.parent.mkdir(parents=True)
    tracker.write_text(json.dumps({"windowingMode": "none"}))
    news = tmp / "settings" / "@jupyterlab" / "apputils-extension" / "notification.jupyterlab-settings"
    news.parent.mkdir(parents=True)
    news.write_text(json.dumps({"fetchNews": "false", "checkForUpdates": False}))
    # the book's notebooks trusted, as `python -m vgai_lite lab` does before it opens them
    subprocess.run([sys.executable, "-c", "from pathlib import Path; from vgai_lite.lab.cli import trust_book; "
                    f"trust_book(Path({str(ROOT / 'notebooks')!r}))"], env=env, check=True)
    lab_port, cdp_port, token = _free_port(), _free_port(), "vgai-lite-browser-test"
    lab = subprocess.Popen([sys.executable, "-m", "jupyter", "lab", "--no-browser", f"--port={lab_port}",
                            "--ip=127.0.0.1", f"--IdentityProvider.token={token}", "--allow-root",
                            f"--notebook-dir={ROOT / 'notebooks'}", "--ServerApp.open_browser=False"],
                           env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    chrome = start_chromium(cdp_port, tmp / 'chromium')
    try:
        _wait_http(f"http://127.0.0.1:{lab_port}/api/status?token={token}", 60, lab, "JupyterLab")
        targets = json.loads(_wait_http(f"http://127.0.0.1:{cdp_port}/json", 30, chrome, "Chromium"))
        page = next(t for t in targets if t.get("type") == "page")
        tools = DevTools(page["webSocketDebuggerUrl"])
        tools.call("Page.enable")
        tools.call("Runtime.enable")
        yield tools, f"http://127.0.0.1:{lab_port}", token
        tools.close()
    finally:
        for p in (chrome, lab):
            p.terminate()
        for p in (chrome, lab):
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()


def _expected_images(nb) -> int:
    return sum(1 for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
               if o.get("output_type") in ("display_data", "execute_result")
               and any(m in o.get("data", {}) for m in IMAGE_MIMES))


PAGE_STATE = """(() => {
  const nb = document.querySelector('.jp-NotebookPanel:not(.lm-mod-hidden) .jp-Notebook');
  if (!nb) return {ready: false};
  const outputs = nb.querySelectorAll('.jp-OutputArea-output');
  const imgs = [...nb.querySelectorAll('.jp-OutputArea-output img')];
  const frames = [...nb.querySelectorAll('.jp-OutputArea-output iframe')];
  const canvas = frames.map(f => { try { return f.contentDocument.querySelectorAll('canvas').length; }
                                   catch (e) { return -1; } });
  const text = [...nb.querySelectorAll('.jp-OutputArea-output')].map(o => o.innerText).join('\\n');
  return {ready: true, cells: nb.querySelectorAll('.jp-Cell').length, outputs: outputs.length,
          images: imgs.length, loaded: imgs.filter(i => i.complete && i.naturalWidth > 0).length,
          iframes: frames.length, canvases: canvas,
          dialogs: document.querySelectorAll('.jp-Dialog').length,
          tracebacks: (text.match(/Traceback \\(most recent call last\\)/g) || []).length,
          mathErrors: nb.querySelectorAll('mjx-merror').length,
          rawTex: [...nb.querySelectorAll('.jp-MarkdownCell .jp-RenderedMarkdown')]
                  .filter(m => /\\\\(tag|frac|mathbf|begin)\\b/.test(m.innerText)).length};
})()"""


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_a_student_sees_every_figure_and_animation(book_in_a_browser, path):
    tools, base, token = book_in_a_browser
    nb = nbformat.read(path, as_version=4)
    expected = _expected_images(nb)
    tools.call("Page.navigate", url=f"{base}/lab/tree/{path.name}?token={token}&reset")
    end, state = time.time() + LOAD_SECONDS, {}
    while time.time() < end:
        state = tools.js(PAGE_STATE) or {}
        want_frame = path.stem.startswith("04")
        if (state.get("ready") and state["cells"] == len(nb.cells) and state["loaded"] >= expected
                and state["rawTex"] == 0 and (not want_frame or any(c > 0 for c in state["canvases"]))):
            break
        time.sleep(0.5)
    assert state.get("ready"), f"{path.name}: JupyterLab showed no notebook within {LOAD_SECONDS} s"
    assert state["cells"] == len(nb.cells), f"{path.name}: {state['cells']} of {len(nb.cells)} cells drawn"
    assert state["images"] >= expected and state["loaded"] >= expected, \
        f"{path.name}: {state['loaded']} of {expected} image outputs drawn and loaded ({state})"
    assert state["dialogs"] == 0, f"{path.name}: an error dialog is open"
    assert state["tracebacks"] == 0, f"{path.name}: an output shows a traceback"
    assert state["rawTex"] == 0, f"{path.name}: {state['rawTex']} markdown cells show raw TeX (not typeset)"
    assert state["mathErrors"] == 0, f"{path.name}: MathJax reports an error in an equation"
    if path.stem.startswith("04"):
        assert state["iframes"] >= 1 and any(c > 0 for c in state["canvases"]), \
            f"{path.name}: the meshcat 3-D view is not drawn (iframes {state['iframes']}, canvases {state['canvases']})"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_outputs_need_no_script_and_no_network(path):
    """Untrusted (a fresh clone), JupyterLab strips scripts from outputs: every animation is an image,
    and no output loads anything from the network (the meshcat view of 04 is inlined, offline)."""
    nb = nbformat.read(path, as_version=4)
    for i, c in enumerate(nb.cells):
        for o in c.get("outputs", []) if c.cell_type == "code" else []:
            html = o.get("data", {}).get("text/html", "")
            html = "".join(html) if isinstance(html, list) else html
            assert "new Animation(" not in html, \
                f"{path.name} cell {i}: an animation that needs JavaScript; use viz.animation_image"
            assert not LOADS_FROM_NETWORK.search(html), f"{path.name} cell {i}: an output loads from the network"
            assert o.get("output_type") != "error", f"{path.name} cell {i}: committed with an error output"

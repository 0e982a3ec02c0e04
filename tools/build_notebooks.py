"""Build the book's notebooks from their sources and execute them.

The source of each notebook is a plain Python file in ``tools/notebooks/`` written in the "percent"
format (``# %%`` starts a code cell, ``# %% [markdown]`` a markdown cell whose lines start with
``# ``). This script turns each source into ``notebooks/NAME.ipynb`` and executes it in full mode so
that the committed notebook shows its outputs:

    python tools/build_notebooks.py                 # every notebook
    python tools/build_notebooks.py 01              # the notebooks whose name starts with 01
    python tools/build_notebooks.py --no-execute    # structure only, no outputs
    python tools/build_notebooks.py 06 --markdown-only   # prose edits only: keep the executed outputs

Edit the source, not the .ipynb, then rebuild: the two stay in step.

Exercise cells carry nbgrader's cell metadata, written in the source's cell marker:

    # %% [solution ex02-1]              the student's code cell (BEGIN/END SOLUTION inside)
    # %% [check ex02-1]                 the autograded test cell of that exercise (1 point; it raises
                                        when the check does not pass)
    # %% [markdown answer ex05-2 2]     a written answer the instructor grades by hand (2 points; the
                                        model answer is the cell's text, a student copy replaces it)
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import nbformat
from nbclient import NotebookClient

ROOT = Path(__file__).resolve().parent.parent
SOURCES = ROOT / "tools" / "notebooks"
TARGET = ROOT / "notebooks"
sys.path.insert(0, str(ROOT))

from vgai_lite.lab.course import is_score_cell  # noqa: E402


def nbgrader_metadata(marker: str) -> dict:
    """nbgrader's metadata of a cell marker's role (``# %% [check ex02-1]`` -> a locked test cell
    worth 1 point, grade_id "ex02-1-check"), or {} for a plain cell."""
    words = marker.split("[", 1)[1].rstrip("]").split() if "[" in marker else []
    words = [w for w in words if w != "markdown"]
    if not words:
        return {}
    role, grade_id, *points = words
    base = {"schema_version": 3, "grade_id": f"{grade_id}-{role}", "locked": False, "task": False}
    if role == "solution":
        return {**base, "solution": True, "grade": False}
    if role == "check":
        return {**base, "solution": False, "grade": True, "locked": True, "points": 1}
    if role == "answer":
        return {**base, "solution": True, "grade": True, "points": int(points[0]) if points else 1}
    raise ValueError(f"unknown cell role {role!r} in {marker!r} (solution, check or answer)")


def parse(text: str) -> nbformat.NotebookNode:
    """Percent-format Python -> a notebook with markdown and code cells."""
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    nb.metadata["language_info"] = {"name": "python"}
    cells, kind, lines, meta = [], None, [], {}

    def flush():
        if kind is None:
            return
        body = "\n".join(lines).strip("\n")
        if kind == "markdown":
            body = "\n".join(l[2:] if l.startswith("# ") else l.lstrip("#") for l in body.splitlines())
            cells.append(nbformat.v4.new_markdown_cell(body))
        elif body.strip():
            cells.append(nbformat.v4.new_code_cell(body))
        else:
            return
        if meta:
            cells[-1].metadata["nbgrader"] = meta
        if kind == "code" and is_score_cell(body):  # nbval compares its output: full marks (conftest.py)
            cells[-1].metadata["tags"] = ["nbval-check-output"]

    for line in text.splitlines():
        if line.startswith("# %%"):
            flush()
            kind, lines = ("markdown" if "[markdown" in line else "code"), []
            meta = nbgrader_metadata(line)
        else:
            lines.append(line)
    flush()
    nb.cells = cells
    return nb


BUSY_CORES = 0.25
"""Other processes using more than this many cores (averaged over a second) make the machine busy."""


def _cpu_jiffies() -> tuple[int, int]:
    """(busy, total) CPU time of the whole machine since boot, from /proc/stat (Linux)."""
    fields = [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)  # idle + iowait
    return sum(fields) - idle, sum(fields)


def busy_cores(seconds: float = 1.0) -> float:
    """How many cores other processes keep busy, measured over ``seconds`` while this one sleeps
    (on a machine without /proc/stat: the 1-minute load average)."""
    try:
        b0, t0 = _cpu_jiffies()
        time.sleep(seconds)
        b1, t1 = _cpu_jiffies()
    except (OSError, ValueError, IndexError):
        return os.getloadavg()[0]
    return (b1 - b0) / max(t1 - t0, 1) * (os.cpu_count() or 1)


def warn_if_busy(when: str) -> bool:
    """Print a warning when other processes load the machine: the timings a notebook prints (and the
    training times it reports) would then not be those of the book's code alone."""
    load = busy_cores()
    if load > BUSY_CORES:
        print(f"WARNING ({when}): other processes keep {load:.2f} cores busy; the timings this notebook "
              "prints will be too slow. Execute it again on an idle machine before committing it.",
              file=sys.stderr, flush=True)
        return True
    return False


def build(source: Path, execute: bool) -> Path:
    nb = parse(source.read_text())
    target = TARGET / (source.stem + ".ipynb")
    if execute:
        env = {k: v for k, v in os.environ.items() if k != "VGAI_LITE_QUICK"}  # committed notebooks: full mode
        busy = warn_if_busy(f"before {source.stem}")
        start = time.time()
        NotebookClient(nb, timeout=3600, kernel_name="python3",
                       resources={"metadata": {"path": str(TARGET)}}).execute(env=env)
        print(f"executed {source.stem} in {time.time() - start:.0f} s")
        if warn_if_busy(f"after {source.stem}") or busy:
            print(f"  {source.stem} ran on a busy machine", file=sys.stderr)
    nbformat.write(nb, target)
    return target


def update_markdown(source: Path) -> Path:
    """Copy the markdown cells of ``source`` into the executed notebook, keeping its outputs; refuses
    when any code cell differs (then the notebook must be executed again)."""
    new = parse(source.read_text())
    target = TARGET / (source.stem + ".ipynb")
    old = nbformat.read(target, as_version=4)
    kinds = lambda nb: [(c.cell_type, c.source if c.cell_type == "code" else None) for c in nb.cells]
    if kinds(new) != kinds(old):
        raise SystemExit(f"{source.name}: code cells changed (or cells added/removed); rebuild without --markdown-only")
    for a, b in zip(old.cells, new.cells):
        if a.cell_type == "markdown":
            a.source = b.source
    nbformat.write(old, target)
    return target


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("prefixes", nargs="*", help="build only notebooks whose name starts with one of these")
    p.add_argument("--no-execute", action="store_true")
    p.add_argument("--markdown-only", action="store_true", help="update prose only, keep outputs")
    args = p.parse_args(argv)
    sources = sorted(SOURCES.glob("[0-9][0-9]_*.py"))
    if args.prefixes:
        sources = [s for s in sources if any(s.stem.startswith(x) for x in args.prefixes)]
    if not sources:
        print("no notebook sources match", args.prefixes, file=sys.stderr)
        return 1
    for s in sources:
        target = update_markdown(s) if args.markdown_only else build(s, execute=not args.no_execute)
        print("wrote", target.relative_to(ROOT))
    return 0


if __name__ == "__main__":
    sys.exit(main())

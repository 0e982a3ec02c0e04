"""The committed notebooks are built from tools/notebooks/*.py: their cells must match the sources
(a notebook edited without its source, or a source edited without rebuilding, fails here)."""

import sys
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from build_notebooks import parse  # noqa: E402

SOURCES = sorted((ROOT / "tools" / "notebooks").glob("[0-9][0-9]_*.py"))


def test_every_source_has_a_notebook_and_back():
    notebooks = {p.stem for p in (ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb")}
    assert notebooks == {p.stem for p in SOURCES}


@pytest.mark.parametrize("source", SOURCES, ids=lambda p: p.stem)
def test_committed_notebook_matches_its_source_and_was_executed(source):
    built = parse(source.read_text())
    committed = nbformat.read(ROOT / "notebooks" / f"{source.stem}.ipynb", as_version=4)
    assert [c.source for c in committed.cells] == [c.source for c in built.cells], \
        f"rebuild it: python tools/build_notebooks.py {source.stem[:2]}"
    code = [c for c in committed.cells if c.cell_type == "code"]
    assert all(c.get("execution_count") for c in code), "commit notebooks executed, outputs visible"


def test_readme_results_section_is_the_one_the_records_give():
    """The README's numbers are written by tools/readme_results.py from data/: none typed by hand."""
    from readme_results import BEGIN, END, README, section

    text = README.read_text()
    assert text.count(BEGIN) == 1 and text.count(END) == 1
    committed = BEGIN + text.split(BEGIN)[1].split(END)[0] + END
    assert committed == section(), "run `python tools/readme_results.py --write`"

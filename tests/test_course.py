"""Course use: solution stubs, student copies and the grader.

The grader tests execute notebooks (quick mode): one notebook's solutions get full marks (nbval's
run of each graded notebook checks its solutions, conftest.py), every untouched student copy
executes to the end and gets zero.
"""

import json

import nbformat
import pytest

from vgai_lite.book import ROOT
from vgai_lite.lab.course import (grade_notebook, is_score_cell, make_student_copies, report_name, strip_solutions,
                              student_copy)
from vgai_lite.lab.exercises import EXERCISES, exercises_of, score
from vgai_lite.lab.method_exercises import check_dagger_mix

NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))
GRADED = [p for p in NOTEBOOKS if exercises_of(p.name[:2])]


def test_every_notebook_01_to_08_has_a_graded_exercise():
    assert sorted({k[:2] for k in EXERCISES}) == ["01", "02", "03", "04", "05", "06", "07", "08"]
    assert [p.name[:2] for p in GRADED] == ["01", "02", "03", "04", "05", "06", "07", "08"]


def test_strip_solutions_keeps_indent_and_hints():
    src = ("def f(x):\n    ### BEGIN SOLUTION\n    # HINT: double it\n    y = 2 * x\n    return y\n"
           "    ### END SOLUTION\n\nprint(f)")
    out, n = strip_solutions(src, "01.1")
    assert n == 1
    assert "2 * x" not in out and "BEGIN" not in out
    assert "    # HINT: double it" in out
    assert '    raise NotImplementedError("exercise 01.1: replace this line with your code")' in out
    ns = {}
    exec(out, ns)
    with pytest.raises(NotImplementedError):
        ns["f"](1)


@pytest.mark.parametrize("src", ["### BEGIN SOLUTION\nx = 1\n", "x = 1\n### END SOLUTION\n",
                                 "### BEGIN SOLUTION\n### BEGIN SOLUTION\n### END SOLUTION\n"])
def test_unbalanced_markers_are_reported(src):
    with pytest.raises(ValueError, match="SOLUTION"):
        strip_solutions(src)


@pytest.mark.parametrize("path", GRADED, ids=lambda p: p.name[:2])
def test_student_copy_has_no_solution_and_no_output(path):
    nb = nbformat.read(path, as_version=4)
    solutions = [c.source for c in nb.cells if c.cell_type == "code" and "### BEGIN SOLUTION" in c.source]
    copy, blocks = student_copy(nb, path.name)
    assert blocks >= len(solutions) >= 1
    text = "\n".join(c.source for c in copy.cells if c.cell_type == "code")
    assert "### BEGIN SOLUTION" not in text and "NotImplementedError" in text
    for sol in solutions:  # no line of any solution survives, except hints and signatures around it
        inner = sol.split("### BEGIN SOLUTION")[1].split("### END SOLUTION")[0]
        for line in inner.splitlines():
            if line.strip() and not line.strip().startswith("# HINT:"):
                assert line not in text.splitlines(), line
    assert all(not c.get("outputs") for c in copy.cells if c.cell_type == "code")
    nbformat.validate(copy)


@pytest.mark.parametrize("path", GRADED, ids=lambda p: p.name[:2])
def test_a_student_copy_keeps_the_takeaways_and_the_way_on(path):
    """A written answer's cell is replaced in the student copy: the notebook's key takeaways and its
    "Next" must sit in cells of their own, or a student never reads them."""
    nb = nbformat.read(path, as_version=4)
    copy, _ = student_copy(nb, path.name)
    for heading in ("## Key takeaways", "## Next"):
        if any(heading in c.source for c in nb.cells):
            assert any(heading in c.source for c in copy.cells), f"{path.name}: {heading!r} is lost in the student copy"


def test_score_counts_this_sessions_checks(capsys):
    def wrong(u_l, u_e, p, g):
        return u_e

    assert not check_dagger_mix(wrong)
    assert score("06") is None  # it prints; a notebook shows the same under JupyterLab and nbval
    out = capsys.readouterr().out
    line = [l for l in out.splitlines() if l.strip().startswith("06.1")][0]  # the score's line for 06.1
    assert line.rstrip().endswith("NOT PASSED")
    assert f"/{len(exercises_of('06'))}" in out and len(exercises_of("06")) == 3
    with pytest.raises(ValueError, match="two-digit"):
        score("6")


@pytest.fixture(scope="module")
def student_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("student")
    written = make_student_copies(out)
    assert [p.name for p in written] == [p.name for p in NOTEBOOKS]
    return out


def test_student_copies_refuse_to_overwrite_the_book():
    with pytest.raises(ValueError, match="overwrite"):
        make_student_copies(ROOT / "notebooks")


@pytest.mark.slow
def test_grader_gives_full_marks_to_a_solution_notebook(tmp_path):
    """The grader's machinery on one notebook's solutions; nbval's run of every graded notebook
    compares its score cell with the committed full marks (conftest.py), so each solution is checked there."""
    path = next(p for p in GRADED if p.name.startswith("02"))
    solution = grade_notebook(path, out=tmp_path)
    assert solution["score"] == solution["max_score"] == len(exercises_of(path.name[:2])), solution
    assert solution["cell_errors"] == []
    written = json.loads((tmp_path / report_name(path)).read_text())
    assert report_name(path) == f"notebooks__{path.stem}.json"
    assert written["score"] == solution["score"]


@pytest.mark.parametrize("path", GRADED, ids=lambda p: p.name[:2])
def test_every_committed_notebook_shows_full_marks_in_its_score_cell(path):
    nb = nbformat.read(path, as_version=4)
    cells = [c for c in nb.cells if c.cell_type == "code" and is_score_cell(c.source)]
    assert len(cells) == 1 and cells[0] is [c for c in nb.cells if c.cell_type == "code"][-1]
    text = "".join(o.get("text", "") for o in cells[0].outputs)
    n = len(exercises_of(path.name[:2]))
    assert f"Score for notebook {path.name[:2]}: {n}/{n}" in text and text.count("PASSED") == n


@pytest.mark.slow
def test_nbval_compares_the_score_cell_so_a_failing_solution_fails(tmp_path):
    """Under nbval, a score cell tagged as the builder tags it (``nbval-check-output``) whose committed
    output says full marks fails when the check did not pass (here: it never ran), and passes when its
    output is what it prints. The committed notebooks' score cells carry the tag."""
    import os
    import subprocess
    import sys

    def probe(state, points):
        ids = exercises_of("02")
        nb = nbformat.v4.new_notebook()
        cell = nbformat.v4.new_code_cell('from vgai_lite.lab.exercises import score\n\nscore("02");', execution_count=1)
        cell.metadata["tags"] = ["nbval-check-output"]
        listing = "".join(f"  {k} {EXERCISES[k]:45s} {state}\n" for k in ids)
        cell.outputs = [nbformat.v4.new_output("stream", name="stdout", text=(
            f"{listing}Score for notebook 02: {points}/{len(ids)}\n"))]
        nb.cells = [cell]
        nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
        target = tmp_path / f"02_probe_{points}.ipynb"
        nbformat.write(nb, target)
        return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "conftest", "--nbval-lax",
                               "--nbval-current-env", "-p", "no:cacheprovider", str(target)],
                              cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)},
                              capture_output=True, text=True, timeout=300)

    full_marks = probe("PASSED", len(exercises_of("02")))
    assert full_marks.returncode == 1 and "1 failed" in full_marks.stdout, full_marks.stdout[-2000:]
    # nbval shows what the cell printed instead (its diff abbreviates the line's start)
    assert f"ook 02: 0/{len(exercises_of('02'))}" in full_marks.stdout, full_marks.stdout[-2000:]
    as_printed = probe("NOT RUN", 0)
    assert as_printed.returncode == 0 and "1 passed" in as_printed.stdout, as_printed.stdout[-2000:]
    for path in GRADED:
        last = [c for c in nbformat.read(path, as_version=4).cells if c.cell_type == "code"][-1]
        assert is_score_cell(last.source) and last.metadata.get("tags") == ["nbval-check-output"], path.name


@pytest.mark.slow
@pytest.mark.parametrize("path", GRADED, ids=lambda p: p.name[:2])
def test_grader_gives_zero_to_untouched_student_copies(path, student_dir):
    student = grade_notebook(student_dir / path.name)
    # only the check cells fail (they raise when a check does not pass, for nbgrader); every other cell runs
    assert all(e["error"].startswith("AssertionError") for e in student["cell_errors"]), student["cell_errors"]
    assert len(student["cell_errors"]) == student["max_score"], "one failing check cell per exercise"
    assert student["score"] == 0 and student["max_score"] == len(exercises_of(path.name[:2]))
    for e in student["exercises"].values():
        assert not e["passed"] and "not implemented" in e["message"]


@pytest.mark.slow
def test_grader_rejects_what_it_cannot_grade(tmp_path):
    with pytest.raises(FileNotFoundError):
        grade_notebook(tmp_path / "01_missing.ipynb")
    with pytest.raises(ValueError, match="no graded exercises"):
        grade_notebook(NOTEBOOKS[0])  # 00, the overview
    odd = tmp_path / "homework.ipynb"
    nbformat.write(nbformat.v4.new_notebook(), odd)
    with pytest.raises(ValueError, match="NN_"):
        grade_notebook(odd)


def test_the_books_hints_name_the_idea_or_the_mistake_never_the_code():
    """A hint survives into the student copy: one sentence, no call, no indexing, no assignment."""
    import re

    hints = [(src.name, line.strip()[len("# HINT:"):].strip())
             for src in sorted((ROOT / "tools" / "notebooks").glob("*.py"))
             for line in src.read_text().splitlines() if line.strip().startswith("# HINT:")]
    assert len(hints) >= 10
    for name, hint in hints:
        assert len(hint) <= 160 and not re.search(r"[.;] [A-Z]", hint), (name, hint)  # one sentence
        assert not re.search(r"torch\.|nn\.|\w\(|=|\[|dim|\.sum|\.mean", hint), (name, hint)

"""The book graded with nbgrader as it is: ``nbgrader generate_assignment`` makes the student
version of a notebook from its cell metadata, and ``nbgrader autograde`` gives a solution full marks
and an untouched student version zero: the same points as the book's own grader.

Skipped where nbgrader is not installed (``requirements-grading.txt``), unless
VGAI_LITE_REQUIRE_NBGRADER=1 (CI installs it), where its absence fails.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest

from vgai_lite.book import QUICK_ENV, ROOT
from vgai_lite.lab.course import grade_notebook, is_written_answer, nbgrader_course, student_copy
from vgai_lite.lab.exercises import exercises_of

pytestmark = pytest.mark.slow  # `pytest -m "not slow"` skips this file

NOTEBOOK = "02_graph_shift_operators.ipynb"

try:
    import nbgrader  # noqa: F401
    HAVE_NBGRADER = True
except ImportError:
    HAVE_NBGRADER = False
    if os.environ.get("VGAI_LITE_REQUIRE_NBGRADER") == "1":
        raise

needs_nbgrader = pytest.mark.skipif(not HAVE_NBGRADER, reason="nbgrader not installed (pip install -r requirements-grading.txt)")


def _cells(path):
    return nbformat.read(path, as_version=4).cells


@pytest.mark.parametrize("path", sorted((ROOT / "notebooks").glob("0[1-7]_*.ipynb")), ids=lambda p: p.stem[:2])
def test_every_exercise_has_a_solution_cell_and_a_check_cell_worth_one_point(path):
    ids = exercises_of(path.name[:2])
    meta = [c.metadata.get("nbgrader") for c in _cells(path) if c.metadata.get("nbgrader")]
    checks = [m for m in meta if m.get("grade") and not m.get("solution")]
    solutions = [m for m in meta if m.get("solution") and not m.get("grade")]
    assert len(checks) == len(ids) and all(m["points"] == 1 and m["locked"] for m in checks)
    assert len(solutions) == len(ids)
    assert len({m["grade_id"] for m in meta}) == len(meta), "nbgrader needs unique grade ids"


def test_open_ended_experiments_ask_for_a_written_conclusion_and_copies_hide_the_model_answer():
    for name in ("05", "06", "07"):
        path = next((ROOT / "notebooks").glob(f"{name}_*.ipynb"))
        nb = nbformat.read(path, as_version=4)
        answers = [c for c in nb.cells if is_written_answer(c)]
        assert len(answers) == 1 and "Model answer" in answers[0].source
        copy, _ = student_copy(nb, path.name)
        assert [c.source for c in copy.cells if is_written_answer(c)] == ["YOUR ANSWER HERE"]


def _nbgrader(args, cwd):
    env = {**os.environ, QUICK_ENV: "1", "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"}
    done = subprocess.run([sys.executable, "-m", "nbgrader", *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]


@needs_nbgrader
def test_nbgrader_generates_the_student_version_and_autogrades_like_the_books_grader(tmp_path):
    from nbgrader.api import Gradebook

    book = tmp_path / "book"
    book.mkdir()
    (book / NOTEBOOK).write_bytes((ROOT / "notebooks" / NOTEBOOK).read_bytes())
    course = tmp_path / "course"
    nbgrader_course(course, book)
    _nbgrader(["generate_assignment", "02"], course)
    released = course / "release" / "02" / NOTEBOOK
    assert "BEGIN SOLUTION" not in released.read_text() and "NotImplementedError" in released.read_text()
    for student, hand_in in (("solution", course / "source" / "02" / NOTEBOOK), ("untouched", released)):
        target = course / "submitted" / student / "02" / NOTEBOOK
        target.parent.mkdir(parents=True)
        target.write_bytes(hand_in.read_bytes())
    _nbgrader(["autograde", "02", "--create"], course)
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gb:
        scores = {s: gb.find_submission_notebook(NOTEBOOK[:-6], "02", s).code_score for s in ("solution", "untouched")}
    ours = {s: grade_notebook(course / "submitted" / s / "02" / NOTEBOOK)["score"] for s in ("solution", "untouched")}
    assert scores == {"solution": 2.0, "untouched": 0.0}
    assert ours == {"solution": 2, "untouched": 0}

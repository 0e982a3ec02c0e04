"""Course use: student copies of the notebooks without solutions, and an automatic grader.

Introduced in the README's section for instructors. In the committed notebooks every exercise's
solution sits between two marker lines inside a code cell::

    def my_flocking_cost(v):
        ### BEGIN SOLUTION
        # HINT: eq. 1 averages over agents, sums over time
        vbar = v.mean(dim=2, keepdim=True)
        ...
        ### END SOLUTION

``make_student_copies`` replaces each such block by its ``# HINT:`` lines (if any) and a line that
raises ``NotImplementedError`` naming the exercise, replaces each written answer (a markdown cell
the instructor grades by hand) by "YOUR ANSWER HERE", and clears every output.

The exercise cells carry nbgrader's cell metadata (``tools/build_notebooks.py``), so nbgrader works
on the book as it is: ``nbgrader_course`` lays the notebooks out as an nbgrader course (one
assignment per notebook), where ``nbgrader generate_assignment`` makes the student version and
``nbgrader autograde`` scores a hand-in with the same points as ``grade_notebook``. ``grade_notebook``
executes a notebook in quick mode, collects what each exercise check (``vgai_lite.lab.exercises``)
reported, and returns (and writes) a score per exercise as JSON.

    python -m vgai_lite student-copies --out student/
    python -m vgai_lite grade student/01_flocking_dynamics_and_expert.ipynb --out grades/
"""

from __future__ import annotations

import json
import os
import re
import tempfile
import time
from pathlib import Path
from typing import Optional, Union

import nbformat
from nbclient import NotebookClient

from ..book import QUICK_ENV, ROOT
from .exercises import EXERCISES, GRADE_FILE_ENV, exercises_of

BEGIN = "### BEGIN SOLUTION"
END = "### END SOLUTION"
HINT = "# HINT:"
_EXERCISE_ID = re.compile(r"Exercise (\d\d\.\d+)")


def notebook_number(path: Union[str, Path]) -> str:
    """The two-digit number a book notebook's file name starts with ("01_...ipynb" -> "01")."""
    name = Path(path).name
    if not (len(name) > 2 and name[:2].isdigit()):
        raise ValueError(f"cannot tell which notebook {name!r} is: book notebooks are named NN_*.ipynb; "
                         "pass the number explicitly (notebook='01')")
    return name[:2]


def _stub_block(lines: list[str], exercise: str, where: str) -> list[str]:
    """The lines between BEGIN and END (markers excluded) -> hint comments and a raise, same indent."""
    body = [l for l in lines if l.strip()]
    if not body:
        raise ValueError(f"{where}: empty solution block")
    indent = body[0][: len(body[0]) - len(body[0].lstrip())]
    hints = [indent + l.strip() for l in lines if l.strip().startswith(HINT)]
    what = f"exercise {exercise}" if exercise else "this exercise"
    return hints + [f"{indent}# YOUR CODE HERE",
                    f'{indent}raise NotImplementedError("{what}: replace this line with your code")']


def strip_solutions(source: str, exercise: str = "", where: str = "cell") -> tuple[str, int]:
    """Replace every BEGIN/END SOLUTION block of a code cell's source by a stub.
    Returns (new source, number of blocks). Unbalanced markers raise ValueError."""
    out, block, blocks = [], None, 0
    for n, line in enumerate(source.splitlines(), 1):
        mark = line.strip()
        if mark == BEGIN:
            if block is not None:
                raise ValueError(f"{where}, line {n}: {BEGIN!r} inside an open solution block")
            block = []
        elif mark == END:
            if block is None:
                raise ValueError(f"{where}, line {n}: {END!r} without a {BEGIN!r} before it")
            out += _stub_block(block, exercise, where)
            block, blocks = None, blocks + 1
        elif block is not None:
            block.append(line)
        else:
            out.append(line)
    if block is not None:
        raise ValueError(f"{where}: {BEGIN!r} without a matching {END!r}")
    return "\n".join(out), blocks


ANSWER_STUB = "YOUR ANSWER HERE"
"""What a student copy shows in place of a written answer (nbgrader's own stub)."""


def is_written_answer(cell) -> bool:
    """A markdown cell the instructor grades by hand (nbgrader: solution and grade, markdown)."""
    meta = cell.get("metadata", {}).get("nbgrader", {})
    return cell.cell_type == "markdown" and bool(meta.get("solution")) and bool(meta.get("grade"))


def student_copy(nb: nbformat.NotebookNode, name: str = "notebook") -> tuple[nbformat.NotebookNode, int]:
    """A copy of ``nb`` with every solution stubbed and every output cleared; (copy, blocks stubbed).

    The exercise id named in a stub's message is the last "Exercise NN.k" of the markdown before it."""
    nb = nbformat.from_dict(json.loads(json.dumps(nb)))  # deep copy
    exercise, total = "", 0
    for i, cell in enumerate(nb.cells):
        if is_written_answer(cell):
            cell.source = ANSWER_STUB
            continue
        if cell.cell_type == "markdown":
            found = _EXERCISE_ID.findall(cell.source)
            exercise = found[-1] if found else exercise
            continue
        if cell.cell_type != "code":
            continue
        cell.source, blocks = strip_solutions(cell.source, exercise, where=f"{name}, cell {i}")
        total += blocks
        cell.outputs, cell.execution_count = [], None
        cell.metadata.pop("execution", None)
    nb.metadata["vgai_lite"] = {"student_copy": True}
    return nb, total


def make_student_copies(out: Union[str, Path], source: Optional[Union[str, Path]] = None) -> list[Path]:
    """Write a student copy of every book notebook (``NN_*.ipynb`` in ``source``, default the
    book's notebooks/) to ``out``. Notebooks with exercises must have a solution block for each."""
    source = Path(source) if source is not None else ROOT / "notebooks"
    out = Path(out)
    paths = sorted(source.glob("[0-9][0-9]_*.ipynb"))
    if not paths:
        raise FileNotFoundError(f"no notebooks named NN_*.ipynb in {source}")
    if out.resolve() == source.resolve():
        raise ValueError("refusing to overwrite the solution notebooks: choose another --out folder")
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for path in paths:
        nb, blocks = student_copy(nbformat.read(path, as_version=4), path.name)
        if exercises_of(notebook_number(path)) and blocks == 0:
            raise ValueError(f"{path.name} has exercises but no {BEGIN!r} blocks to remove")
        target = out / path.name
        nbformat.write(nb, target)
        written.append(target)
    return written


NBGRADER_CONFIG = """# nbgrader configuration of the book's course (written by python -m vgai_lite nbgrader-course)
c = get_config()  # noqa: F821
c.CourseDirectory.course_id = "vgai-lite"
c.CourseDirectory.root = {root!r}
c.Execute.timeout = 1200            # seconds per cell: a hand-in runs the notebook's own cells
"""


def nbgrader_course(out: Union[str, Path], source: Optional[Union[str, Path]] = None) -> list[Path]:
    """Lay the book's graded notebooks out as an nbgrader course in ``out``: ``source/NN/NN_*.ipynb``
    (assignment "NN", the solution notebook as it is) and ``nbgrader_config.py``. Then, in ``out``:
    ``nbgrader generate_assignment NN`` writes the student version to ``release/NN/``, and
    ``nbgrader autograde NN`` scores hand-ins in ``submitted/STUDENT/NN/`` (set ``VGAI_LITE_QUICK=1``
    in its environment to run the book's quick mode, as ``grade`` does). Returns the notebooks written."""
    source = Path(source) if source is not None else ROOT / "notebooks"
    out = Path(out)
    written = []
    for path in sorted(source.glob("[0-9][0-9]_*.ipynb")):
        number = notebook_number(path)
        if not exercises_of(number):
            continue
        target = out / "source" / number / path.name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(path.read_bytes())
        written.append(target)
    if not written:
        raise FileNotFoundError(f"no graded notebooks (NN_*.ipynb with exercises) in {source}")
    (out / "nbgrader_config.py").write_text(NBGRADER_CONFIG.format(root=str(out.resolve())))
    return written


def is_score_cell(source: str) -> bool:
    """Whether a code cell is a graded notebook's closing cell, which imports ``score`` and prints the
    notebook's score (``from vgai_lite.lab.exercises import score`` then ``score("NN");``). The test suite
    compares its output with the committed full marks (conftest.py)."""
    lines = [l.strip() for l in source.strip().splitlines() if l.strip()]
    return (len(lines) == 2 and lines[0] == "from vgai_lite.lab.exercises import score"
            and re.fullmatch(r'score\("\d\d"\);', lines[1]) is not None)


def report_name(path: Union[str, Path]) -> str:
    """File name of a notebook's grade report in a folder: FOLDER__NAME.json, so that the same
    notebook handed in by several students (one folder each) gets one report each."""
    path = Path(path).resolve()
    return f"{path.parent.name}__{path.stem}.json"


def grade_notebook(path: Union[str, Path], out: Optional[Union[str, Path]] = None, notebook: Optional[str] = None,
                   quick: bool = True, timeout: int = 600) -> dict:
    """Execute a (student's) notebook, collect its exercise checks, return a score per exercise.

    Every cell runs even if one raises (errors are listed in the report). An exercise scores 1 when
    its check's last run in the notebook passed, 0 when it failed or never ran. ``quick`` runs the
    book in quick mode (``VGAI_LITE_QUICK=1``). Writes the report to ``out`` (a .json file, or a
    folder that gets FOLDER__NAME.json, see ``report_name``) when given.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no notebook at {path}")
    number = notebook or notebook_number(path)
    expected = exercises_of(number)
    if not expected:
        raise ValueError(f"notebook {number} has no graded exercises; the book's are in "
                         f"{sorted({k[:2] for k in EXERCISES})}")
    nb = nbformat.read(path, as_version=4)
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "checks.jsonl"
        env = {**os.environ, QUICK_ENV: "1" if quick else "0", GRADE_FILE_ENV: str(log)}  # the kernel's only
        NotebookClient(nb, timeout=timeout, kernel_name="python3", allow_errors=True,
                       resources={"metadata": {"path": str(path.parent.resolve())}}).execute(env=env)
        records = [json.loads(l) for l in log.read_text().splitlines()] if log.is_file() else []
    last = {r["exercise"]: r for r in records}
    exercises = {}
    for k in expected:
        r = last.get(k)
        exercises[k] = {"title": EXERCISES[k], "points": int(bool(r and r["passed"])), "max_points": 1,
                        "passed": bool(r and r["passed"]),
                        "message": r["message"] if r else "the check of this exercise never ran"}
    errors = [{"cell": i, "error": f"{o.get('ename')}: {o.get('evalue')}"}
              for i, c in enumerate(nb.cells) if c.cell_type == "code"
              for o in c.get("outputs", []) if o.get("output_type") == "error"]
    report = {"notebook": path.name, "number": number, "quick": quick,
              "score": sum(e["points"] for e in exercises.values()), "max_score": len(expected),
              "exercises": exercises, "cell_errors": errors,
              "seconds": round(time.perf_counter() - start, 1)}
    if out is not None:
        out = Path(out)
        target = out if out.suffix == ".json" else out / report_name(path)
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(json.dumps(report, indent=2) + "\n")
        report["written_to"] = str(target)
    return report

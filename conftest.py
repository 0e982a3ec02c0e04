"""Test-suite set-up (repository root, so it applies to tests/ and notebooks/ alike).

* Quick mode: the variable is set before any notebook kernel starts, so nbval's kernels inherit it.
* Each graded notebook's last cell, ``score("NN")``, prints which of its exercises passed. Its
  output is compared like a cell marked ``# NBVAL_CHECK_OUTPUT`` (without showing students the
  marker): the committed notebooks hold the solutions with full marks, so nbval's run of a notebook
  also checks that every solution still passes its check. The grader's own test
  (tests/test_course.py) therefore grades the solutions of one notebook only, and every student copy.
* Two at a time: with pytest-xdist (``-n 2 --dist loadfile``, as the README's test command runs),
  each worker and the notebook kernels it starts use one torch thread (``VGAI_LITE_THREADS``), so
  two workers do not oversubscribe two cores; a file (a notebook's cells, a module's fixtures) runs
  on one worker. (``loadgroup`` would split finer, but pytest 9 moved the node ids that xdist 3.8
  rewrites for it, so its groups are ignored.)
* ``quick_table_k``: one quick serial reproduction of Table 1b (1 torch thread), shared by the
  reproduction's resume/retrain test and the Ray test, which compares a Ray run with it.
"""

import os
import time

import pytest

os.environ.setdefault("VGAI_LITE_QUICK", "1")
os.environ.setdefault("MPLBACKEND", "Agg")
if os.environ.get("PYTEST_XDIST_WORKER"):  # one of several workers: one thread each (and their kernels)
    os.environ["VGAI_LITE_THREADS"] = os.environ["OMP_NUM_THREADS"] = "1"


def _as_a_notebook_shows_it(item):
    """nbval runs cells with ``store_history=False``, under which IPython does not see a cell's
    trailing semicolon and displays the value ``score(...)`` returns; JupyterLab and the book's
    builder (which store history) show no such output. Compare what a notebook shows: drop it."""
    compare = item.compare_outputs

    def compare_outputs(test, ref, skip_compare=None):
        return compare([o for o in test if o.get("output_type") != "execute_result"], ref, skip_compare)

    item.compare_outputs = compare_outputs


def pytest_configure(config):
    if os.environ.get("PYTEST_XDIST_WORKER"):  # the worker itself, like its kernels: book.threads()
        import torch

        from vgai_lite.book import threads

        torch.set_num_threads(threads())


def pytest_collection_modifyitems(session, config, items):
    from vgai_lite.lab.course import is_score_cell

    for item in items:
        if item.path.suffix == ".ipynb":  # executing the book, even in quick mode, takes minutes
            item.add_marker(pytest.mark.slow)
        cell = getattr(item, "cell", None)  # nbval's IPyNbCell
        if cell is not None and isinstance(getattr(item, "options", None), dict) and is_score_cell(cell.source):
            item.options["check"] = True
            _as_a_notebook_shows_it(item)


@pytest.fixture(scope="session")
def quick_table_k(tmp_path_factory):
    """(results, folder, wall seconds) of ``reproduce --only K --quick --seeds 1`` run serially with
    one torch thread, the threads of each task of the Ray test. Tests that change the folder copy it."""
    import torch

    from vgai_lite.lab.reproduce import ReproduceConfig, run

    out = tmp_path_factory.mktemp("quick_K") / "serial"
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        start = time.perf_counter()
        results = run(["K"], ReproduceConfig(quick=True, seeds=1), out=out, progress=False)
        seconds = time.perf_counter() - start
    finally:
        torch.set_num_threads(threads)
    return results, out, seconds

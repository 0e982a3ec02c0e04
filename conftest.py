"""Test-suite set-up (repository root, so it applies to tests/ and notebooks/ alike).

* Quick mode: the variable is set before any notebook kernel starts, so nbval's kernels inherit it.
* Each graded notebook's last cell, ``score("NN")``, prints which of its exercises passed. It carries
  nbval's ``nbval-check-output`` tag (written by tools/build_notebooks.py; students see no marker),
  so nbval compares its output: the committed notebooks hold the solutions with full marks, so
  nbval's run of a notebook also checks that every solution still passes its check. The grader's own test
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


def pytest_configure(config):
    if os.environ.get("PYTEST_XDIST_WORKER"):  # the worker itself, like its kernels: book.threads()
        import torch

        from vgai_lite.book import threads

        torch.set_num_threads(threads())


def pytest_collection_modifyitems(session, config, items):
    for item in items:
        if item.path.suffix == ".ipynb":  # executing the book, even in quick mode, takes minutes
            item.add_marker(pytest.mark.slow)


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

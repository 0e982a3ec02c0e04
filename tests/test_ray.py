"""``reproduce --ray``: the same tables as a serial run, from Ray tasks on a local instance of 2 CPUs.

Needs Ray (requirements-cluster.txt): skipped without it, except under ``.ci/run``
(``VGAI_LITE_REQUIRE_RAY=1``), which installs it.
"""

import importlib.util
import os
import sys
import time

import pytest

from vgai_lite.reproduce import ReproduceConfig, run


def _need_ray():
    if importlib.util.find_spec("ray") is None:
        if os.environ.get("VGAI_LITE_REQUIRE_RAY") == "1":
            pytest.fail("the Ray test must run here: pip install -r requirements-cluster.txt (.ci/run does)")
        pytest.skip("Ray is not installed: pip install -r requirements-cluster.txt")


def test_a_ray_run_gives_the_serial_run_s_numbers_and_resumes(quick_table_k, tmp_path):
    """Table 1b in quick form: DAGNN and VGAI trainings at K - 1 = 1, 2, 3 (the three VGAIs share their
    first stage, so their training tasks form a chain) and their cells, against the serial run of
    conftest.py (1 torch thread, as each Ray task here). The whole quick reproduction is compared by
    ``tools/experiments/ray_quick.py`` (notebook 07)."""
    _need_ray()
    rc = ReproduceConfig(quick=True, seeds=1)
    serial, _, serial_s = quick_table_k
    start = time.perf_counter()
    on_ray = run(["K"], rc, out=tmp_path / "ray", progress=False, ray={"address": None, "cpus": 2, "threads": 1})
    ray_s = time.perf_counter() - start
    print(f"quick reproduction: serial {serial_s:.1f} s (1 thread), on Ray {ray_s:.1f} s (2 CPUs, 1 thread per task)")
    assert on_ray["tables"] == serial["tables"]
    info = on_ray["provenance"]["ray"]
    assert info["cpus"] == 2 and info["threads_per_task"] == 1 and info["tasks"]["cells"] == \
        sum(len(c["cells"]) for t in serial["tables"].values() for r in t["rows"].values() for c in r.values())
    assert on_ray["provenance"]["invocations"][-1]["models_trained_now"] == \
        serial["provenance"]["invocations"][-1]["models_trained_now"] > 0
    again = run(["K"], rc, out=tmp_path / "ray", progress=False, ray={"address": None, "cpus": 2, "threads": 1})
    assert again["provenance"]["compute_seconds"]["cells_computed_now"] == 0  # an interrupted run resumes from disk
    assert again["provenance"]["ray"]["tasks"]["trainings"] == 0


def test_without_ray_the_flag_says_how_to_install_it(monkeypatch):
    from vgai_lite import ray_runner

    monkeypatch.setitem(sys.modules, "ray", None)  # import ray fails, as where it is not installed
    with pytest.raises(SystemExit, match="requirements-cluster.txt"):
        ray_runner.import_ray()

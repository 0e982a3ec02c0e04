"""``reproduce --ray``: the same tables as a serial run, from Ray tasks on a local instance of 2 CPUs.

Needs Ray (requirements-cluster.txt): skipped without it, except under ``.ci/run``
(``VGAI_LITE_REQUIRE_RAY=1``), which installs it.
"""

import importlib.util
import os
import sys
import time

import pytest

from vgai_lite.lab.reproduce import ReproduceConfig, run

pytestmark = pytest.mark.slow  # `pytest -m "not slow"` skips this file


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
    from vgai_lite.lab import ray_runner

    monkeypatch.setitem(sys.modules, "ray", None)  # import ray fails, as where it is not installed
    with pytest.raises(SystemExit, match="requirements-cluster.txt"):
        ray_runner.import_ray()


def test_the_projection_spreads_the_work_and_respects_the_chain_of_a_shared_first_stage(tmp_path):
    """projected_hours on a made-up run: two VGAIs sharing a first stage (K = 2, 3), one with another
    seed, one DAGNN; each cell's evaluation time and each model's recorded training time in hours."""
    import json

    from vgai_lite.config import FlockConfig
    from vgai_lite.lab.ray_runner import projected_hours
    from vgai_lite.vgai_config import VGAITrainConfig

    cfg = FlockConfig().to_dict()
    h = 3600.0

    def model(kind, **tc):
        return {"kind": kind, "config": cfg,
                "train_config": VGAITrainConfig(**tc).to_dict() if kind == "vgai" else None}

    cells = {"a": (model("vgai", K=2), 1 * h, 0.5 * h), "b": (model("vgai", K=3), 2 * h, 0.5 * h),
             "c": (model("vgai", K=3, seed=1), 1 * h, 0.5 * h), "d": (model("dagnn"), 0.25 * h, 0.25 * h)}
    (tmp_path / "cells").mkdir()
    for key, (m, train, ev) in cells.items():
        (tmp_path / "cells" / f"{key}.json").write_text(json.dumps(
            {"model": m, "eval_seconds": ev, "checkpoint": f"models/{key}.pt", "train_seconds_recorded": train}))
    results = {"provenance": {"reproduce_config": {"vgai_seeds": 1}},
               "tables": {"K": {"rows": {"VGAI": {str(k): {"cells": [k]} for k in "abc"}, "DAGNN": {"1": {"cells": ["d"]}}}}}}
    one = projected_hours(results, tmp_path, 1, vgai_seeds=1)
    assert one["serial_hours"] == pytest.approx(4 + 1.5 + 0.5)  # every training and every cell, one after another
    assert one["longest_chain_hours"] == pytest.approx(3 + 0.5)  # a then b (same first stage), then the slowest cell
    assert projected_hours(results, tmp_path, 2, vgai_seeds=1)["projected_hours"] == pytest.approx(3.5)  # the chain
    assert projected_hours(results, tmp_path, 1, vgai_seeds=2)["serial_hours"] == pytest.approx(0.5 + 2 * 5.5)
    with pytest.raises(ValueError, match="positive integer"):
        projected_hours(results, tmp_path, 0)

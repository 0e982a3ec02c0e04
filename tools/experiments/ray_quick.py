"""Benchmark: the quick reproduction, serial against Ray, on this machine.

    python tools/experiments/ray_quick.py        # about 5 minutes alone on two cores; needs requirements-cluster.txt

Runs ``reproduce --quick`` (every table in miniature, from scratch in a temporary folder) three
times: serially with 2 torch threads (the command's default), serially with 1 thread, and on a
local Ray instance of 2 CPUs with 1 thread per task. Writes data/experiments/ray_quick.json: the
wall times and whether the Ray run's tables equal the 1-thread serial run's (they must: same
functions, same threads per task). Run it alone: a timing taken beside other jobs is not one to report.
"""

from __future__ import annotations

import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from vgai_lite.book import DATA_DIR  # noqa: E402
from vgai_lite.lab.reproduce import ReproduceConfig, run  # noqa: E402


def timed(rc, out, threads, ray=None):
    torch.set_num_threads(threads)
    start = time.perf_counter()
    res = run(None, rc, out=out, progress=False, ray=ray)
    return res, time.perf_counter() - start


def main() -> int:
    rc = ReproduceConfig(quick=True, seeds=2)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        serial2, s2 = timed(rc, tmp / "serial2", 2)
        serial1, s1 = timed(rc, tmp / "serial1", 1)
        on_ray, r = timed(rc, tmp / "ray", 1, ray={"address": None, "cpus": 2, "threads": 1})
    record = {"command": "python tools/experiments/ray_quick.py", "reproduce_config": {"quick": True, "seeds": 2},
              "cpus": os.cpu_count(), "platform": platform.platform(),
              "serial_2_threads_seconds": round(s2, 1), "serial_1_thread_seconds": round(s1, 1),
              "ray_seconds": round(r, 1), "ray": on_ray["provenance"]["ray"],
              "ray_equals_serial_1_thread": on_ray["tables"] == serial1["tables"],
              "serial_2_threads_equals_1_thread": serial2["tables"] == serial1["tables"],
              "ray_over_serial": round(r / s2, 2)}
    (DATA_DIR / "experiments" / "ray_quick.json").write_text(json.dumps(record, indent=1) + "\n")
    print(json.dumps(record, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

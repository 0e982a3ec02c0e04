"""``reproduce --ray``: the reproduction's trainings and cells as Ray tasks, on a laptop or a cluster.

Introduced in notebook 10 (the appendix). The plan is ``reproduce.plan``'s, unchanged; only who computes it differs.

* Every model a cell needs (and that is not ready on disk) is one **training task**, every cell one
  **cell task**; each declares ``num_cpus`` = the torch threads it runs with (``--threads``).
* A cell task depends on its model's training task through the task's object reference, so Ray
  starts it when the model is ready, on whichever machine has a free CPU.
* VGAI runs that share their first stage (``stage1_cache.stage1_identity``: Table 1b's K = 2, 3, 4)
  train one after the other, each depending on the previous one's reference, so that the second finds
  the first's stage 1 in ``OUT/stage1/`` exactly as in a serial run.
* The tasks call the same functions as the serial loop (``table_cells.obtain`` and ``evaluate_cell``)
  and write the same files as they finish: ``OUT/models/``, ``OUT/stage1/``, ``OUT/cells/KEY.json``.
  With the same torch threads per task as the serial run, the numbers are the same, and an
  interrupted Ray run resumes from what is on disk. On a cluster OUT must be a folder every machine
  sees (a shared filesystem), and every machine needs this repository and its environment.

Ray is optional (``pip install -r requirements-cluster.txt``); without it ``--ray`` says how to get it.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Optional

from tqdm.auto import tqdm

from ..checkpoints import config_hash
from ..config import FlockConfig
from .table_cells import cell_path, evaluate_cell, obtain
from ..vgai_config import VGAITrainConfig
from .stage1_cache import stage1_identity

INSTALL = "pip install -r requirements-cluster.txt"


def import_ray():
    try:
        import ray
    except ImportError:
        raise SystemExit(f"--ray needs Ray, an optional dependency: {INSTALL} (then, for a cluster: "
                         "`ray start --head` on one machine, `ray start --address HEAD:6379` on the others)") from None
    return ray


def _train(spec, out: str, retrain: bool, threads: int, *after):
    """A training task: make sure ``spec`` has a finished checkpoint (``after``: tasks to wait for)."""
    import torch

    torch.set_num_threads(threads)
    return obtain(spec, Path(out), retrain=retrain)


def _cell(spec, flight, episodes: int, seed: int, out: str, fresh: bool, threads: int, obtained=None,
          wait_for=None):
    """A cell task: fly one cell. ``obtained``: its model's training task's result, for the one cell
    whose record carries that training (as in a serial run, the first cell that needs the model);
    ``wait_for``: the training it waits for, otherwise (Ray resolves it first; its value is unused)."""
    import torch

    torch.set_num_threads(threads)
    return evaluate_cell(spec, flight, episodes, seed, Path(out), fresh=fresh, obtained=obtained)


def run_jobs(jobs: list, rc, out: Path, address: Optional[str] = None, cpus: Optional[int] = None,
             threads: int = 1, progress: bool = True) -> tuple[list, dict]:
    """Compute every job of ``reproduce.plan`` (in any order) and return their records in the plan's
    order, with a description of the Ray cluster used.

    address: None for a new local Ray instance (``cpus`` CPUs, default all), or a running cluster's
    ("auto", or "HOST:6379" of ``ray start --head``)."""
    ray = import_ray()

    if not isinstance(threads, int) or threads < 1:
        raise ValueError(f"threads (torch threads and CPUs per task) must be a positive integer, got {threads!r}")
    root = str(Path(__file__).resolve().parents[2])  # the folder holding vgai_lite/
    env = {"env_vars": {"PYTHONPATH": root + os.pathsep + os.environ.get("PYTHONPATH", "")}}
    if address is None:
        ray.init(num_cpus=cpus, include_dashboard=False, log_to_driver=False, runtime_env=env)
    else:
        ray.init(address=address, log_to_driver=False, runtime_env=env)
    try:
        resources = ray.cluster_resources()
        train = ray.remote(num_cpus=threads)(_train)
        cell = ray.remote(num_cpus=threads)(_cell)
        out_s = str(out)
        # the models that some uncomputed cell needs (all of them when retraining), in plan order
        needed, order = {}, []
        for _, _, _, spec, flight, episodes in jobs:
            if spec.kind == "local" or spec.key() in needed:
                continue
            if rc.retrain or not cell_path(spec, flight, episodes, rc.seed, out).is_file():
                needed[spec.key()] = spec
                order.append(spec.key())
        trainings, last_of_stage1 = {}, {}
        for key in order:
            spec = needed[key]
            after = ()
            if spec.kind == "vgai":
                shared = config_hash(stage1_identity(spec.cfg, spec.tcfg))
                after = (last_of_stage1[shared],) if shared in last_of_stage1 else ()
            trainings[key] = train.remote(spec, out_s, rc.retrain, threads, *after)
            if spec.kind == "vgai":
                last_of_stage1[shared] = trainings[key]
        carried, refs = set(), []
        for table, row, column, spec, flight, episodes in jobs:
            kw = {}
            key = spec.key()
            if key in trainings:
                todo = rc.retrain or not cell_path(spec, flight, episodes, rc.seed, out).is_file()
                if todo and key not in carried:
                    carried.add(key)
                    kw["obtained"] = trainings[key]
                else:
                    kw["wait_for"] = trainings[key]
            refs.append(cell.options(name=f"cell {table} {row} {column:g}").remote(
                spec, flight, episodes, rc.seed, out_s, rc.retrain, threads, **kw))
        total = len(refs) + len(trainings)
        bar = tqdm(total=total, desc="reproduce on Ray", unit="task", disable=not progress)
        pending = refs + list(trainings.values())
        done_cells = 0
        cell_ids = {r.hex() for r in refs}
        while pending:
            ready, pending = ray.wait(pending, num_returns=1)
            done_cells += sum(1 for r in ready if r.hex() in cell_ids)
            bar.update(len(ready))
            bar.set_postfix_str(f"cells {done_cells}/{len(refs)}, trainings "
                                f"{len(trainings) - sum(1 for r in pending if r.hex() not in cell_ids)}/{len(trainings)}")
        bar.close()
        records = ray.get(refs)
        info = {"address": address or "local", "cpus": resources.get("CPU"), "nodes": len(ray.nodes()),
                "threads_per_task": threads, "tasks": {"trainings": len(trainings), "cells": len(refs)}}
        return records, info
    finally:
        ray.shutdown()


def projected_hours(results: dict, out: Path, machines: int, vgai_seeds: int = 3, cores: int = 2) -> dict:
    """A rough projection of a full reproduction's wall time on ``machines`` machines of ``cores``
    cores (one task of ``cores`` threads at a time on each), with ``vgai_seeds`` training seeds per VGAI
    row, from the times recorded in a run's cells (``results``: that run's results.json, ``out`` its
    folder). The VGAI trainings and cells are scaled by vgai_seeds / the run's seeds. It is the larger
    of the work spread evenly over the machines and the longest chain of tasks that must run one
    after the other (the VGAIs sharing a first stage, Table 1b's, then the slowest cell).
    Returns hours for the serial run on one machine and the projection, with the pieces."""
    if not isinstance(machines, int) or machines < 1:
        raise ValueError(f"machines must be a positive integer, got {machines!r}")
    scale = vgai_seeds / results["provenance"]["reproduce_config"]["vgai_seeds"]
    keys = {k for t in results["tables"].values() for r in t["rows"].values() for c in r.values() for k in c["cells"]}
    cells = [json.loads((Path(out) / "cells" / f"{k}.json").read_text()) for k in sorted(keys)]
    models = {c["checkpoint"]: c for c in cells if c.get("checkpoint")}
    train = {"vgai": 0.0, "dagnn": 0.0}
    for c in models.values():
        train[c["model"]["kind"]] += c.get("train_seconds_recorded", 0.0)
    evals = {"vgai": 0.0, "dagnn": 0.0, "local": 0.0}
    for c in cells:
        evals[c["model"]["kind"]] += c["eval_seconds"]
    work = train["dagnn"] + evals["dagnn"] + evals["local"] + scale * (train["vgai"] + evals["vgai"])
    chains = {}  # the VGAIs sharing a first stage train one after another (as scheduled by run_jobs)
    for c in models.values():
        if c["model"]["kind"] == "vgai":
            shared = config_hash(stage1_identity(FlockConfig(**c["model"]["config"]),
                                                 VGAITrainConfig.from_dict(c["model"]["train_config"])))
            chains[shared] = chains.get(shared, 0.0) + c.get("train_seconds_recorded", 0.0)
    chain = max(chains.values(), default=0.0) + max(c["eval_seconds"] for c in cells)
    hours = max(work / machines, chain) / 3600
    return {"machines": machines, "cores": cores, "vgai_seeds": vgai_seeds, "serial_hours": work / 3600,
            "projected_hours": hours, "longest_chain_hours": chain / 3600}

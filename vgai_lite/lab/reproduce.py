"""Reproduce the paper's section 4 tables with one command: ``python -m vgai_lite reproduce``.

Introduced in notebook 07. Five tables (relative cost, the centralized expert = 1.00):

  F       Table 1a  features per agent F = 6, 12, 24 (VGAI; the DAGNN's 6 exact features at F = 6)
  K       Table 1b  exchanges K - 1 = 1, 2, 3 (DAGNN and VGAI, each trained at that K)
  v_init  Table 2a  initial velocity 1, 2, 3 m/s (DAGNN, Local, VGAI)
  R       Table 2b  communication radius 1.0, 1.5, 2.0 m (DAGNN, Local, VGAI)
  N       Table 3   trained on N = 50, flown by N' = 50, 60, 75 agents (paper) and 100, 200 (ours)

The paper does not say whether the v_init and R tables retrain the controllers (its section is
about "robustness to different initial conditions"). Our choice: the rows DAGNN and VGAI are the
controllers trained at the defaults (v_init = 3, R = 1.5), flown in each condition; the row
"DAGNN (retrained)" is a DAGNN trained in that condition, which is cheap, to show what retraining buys;
with ``--extras``, the row "VGAI (retrained)" of Table 2b does the same for VGAI (two more trainings).
The row "DAGNN (per neighbour)" of Tables 2b and 3 (not the paper's) is one DAGNN trained at the defaults
with each feature divided by the drone's degree (``runs.PER_NEIGHBOUR``, notebook 03 section 9), flown in
every column: one controller for every team size.

Every cell of a column is evaluated on the same initial conditions, the book's test episodes (seed
``book.TEST_SEED``: nothing is chosen on them), so controllers are compared episode by episode. A cell is one
(controller, flight configuration, episodes, seed); its result is written to
``OUT/cells/KEY.json`` (KEY a hash of everything that defines it) before the next starts, so an
interrupted run resumes where it stopped and a cell shared by several tables (the default VGAI
appears in all five) is computed once. Trained models are reused: the book's shipped checkpoints
(data/dagnn/, data/vgai/) when the configuration is the same, otherwise ``OUT/models/``.
``OUT/results.json`` and ``OUT/results.csv`` gather the tables with the provenance of the run.
"""

from __future__ import annotations

import csv
import dataclasses
import importlib.metadata as md
import json
import platform
import sys
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Union

import torch
from tqdm.auto import tqdm

from ..book import DATA_DIR, QUICK_T, QUICK_TRAIN_N, TEST_SEED, shipped_file
from ..config import FlockConfig
from ..dagnn_training import DAGNNTrainConfig
from .paper import PAPER, TABLES
from .provenance import git_state
from .runs import PER_NEIGHBOUR, VGAI_RUNS, training_minutes
from .ray_runner import run_jobs
from .table_cells import ModelSpec, evaluate_cell, model_path
from ..vgai_config import VGAITrainConfig, book_recipe

@dataclass(frozen=True)
class ReproduceConfig:
    """What a reproduction run does. The committed data/results/results.json is the defaults'
    (``python -m vgai_lite reproduce``), flying the book's shipped VGAIs; its provenance lists every
    invocation that computed its cells (data/results/cells/).

    Attributes:
        episodes: held-out episodes per cell (N' <= 75); ``episodes_large`` for N' >= 100, where a
            VGAI episode renders N'^2 drone views per step.
        seed: seed of the initial conditions (the book's TEST_SEED: the tables report, they choose nothing).
        seeds: training seeds 0..seeds-1 of the DAGNN rows (spread over training seeds);
        vgai_seeds: the same for VGAI (each costs a VGAI training: ``runs.training_minutes`` of its record).
        quick: tiny trainings and short episodes, every table in small form (the tests).
        repair_from: N' from which initial conditions use the "repair" sampler (whole-swarm rejection
            accepts about 1 draw in 400,000 at N' = 75).
        retrain: from scratch: train every model the run needs anew (overwriting its checkpoint, the
            shipped ones included) and recompute every cell, ignoring what earlier runs left.
        extras: also the rows beyond the paper's that cost VGAI trainings (``extra_rows`` of
            TABLES): a VGAI retrained at R = 1.0 and 2.0 m (two more trainings).
    """

    episodes: int = 30
    episodes_large: int = 10
    seed: int = TEST_SEED
    seeds: int = 3
    vgai_seeds: int = 1
    quick: bool = False
    repair_from: int = 75
    retrain: bool = False
    extras: bool = False

    def __post_init__(self):
        for name in ("episodes", "episodes_large", "seeds", "vgai_seeds"):
            value = getattr(self, name)
            if not isinstance(value, int) or value < 1:
                raise ValueError(f"{name} must be a positive integer, got {value!r}")


def _quick_dagnn(t: DAGNNTrainConfig) -> DAGNNTrainConfig:
    return dataclasses.replace(t, rounds=2, episodes_per_round=2, epochs_per_round=1)


def _quick_vgai(t: VGAITrainConfig) -> VGAITrainConfig:
    return dataclasses.replace(t, expert_episodes=2, dagger_rounds=1, episodes_per_round=1, warm_steps=4,
                               warm_states=1, mlp_epochs=1, joint_steps=2, windows=1)


# ---------------------------------------------------------------------------------------------
# Models


def _base_cfg(rc: ReproduceConfig, **changes) -> FlockConfig:
    cfg = FlockConfig(**changes)
    return cfg.replace(T=QUICK_T) if rc.quick else cfg


def _name(stem: str, seed: int, cfg_changes: dict) -> str:
    """A model's file name: stem, the flight settings it was trained with, its seed (dagnn_K4_R2_s0)."""
    return stem + "".join(f"_{k}{v:g}" for k, v in cfg_changes.items()) + f"_s{seed}"


def _dagnn(rc, K=4, seed=0, feature_transform="none", **cfg_changes) -> ModelSpec:
    t = dataclasses.replace(DAGNNTrainConfig(K=K, feature_transform=feature_transform), seed=seed)
    stem = f"dagnn_K{K}" + ("" if feature_transform == "none" else f"_{feature_transform}")
    return ModelSpec("dagnn", _base_cfg(rc, **cfg_changes), _quick_dagnn(t) if rc.quick else t,
                     _name(stem, seed, cfg_changes))


def _book_vgai(F: int, K: int, seed: int) -> VGAITrainConfig:
    """The configuration of the VGAI the book ships with this F, K and seed (``runs.VGAI_RUNS``), so that
    a table flies the shipped model whatever recipe it was trained with (each cell's record names its
    training configuration); the book's recipe for any other."""
    shipped = [t for t in VGAI_RUNS.values() if (t.F, t.K, t.seed) == (F, K, seed)]
    return shipped[0] if shipped else book_recipe(F=F, K=K, seed=seed)


def _vgai(rc, F=24, K=4, seed=0, **cfg_changes) -> ModelSpec:
    t, cfg = book_recipe(F=F, K=K, seed=seed) if cfg_changes else _book_vgai(F, K, seed), _base_cfg(rc, **cfg_changes)
    return ModelSpec("vgai", cfg.replace(N=QUICK_TRAIN_N) if rc.quick else cfg, _quick_vgai(t) if rc.quick else t,
                     _name(f"vgai_F{F}_K{K}", seed, cfg_changes))


def rows_of(rc: ReproduceConfig, table: str) -> list[str]:
    """The rows a run computes for ``table``: the paper's, and ours beyond them if ``rc.extras``."""
    t = TABLES[table]
    return t["rows"] + (t.get("extra_rows", []) if rc.extras else [])


def models_of(rc: ReproduceConfig, table: str, row: str, column) -> list[ModelSpec]:
    """The controllers (one per training seed) behind a cell of a table."""
    if row == "Local":
        return [ModelSpec("local", _base_cfg(rc), None, "local")]
    dagnn_seeds, vgai_seeds = range(rc.seeds), range(rc.vgai_seeds)
    if row in ("DAGNN (retrained)", "VGAI (retrained)"):
        if table not in ("v_init", "R"):
            raise ValueError(f"row {row!r} exists only in the v_init and R tables, not {table!r}")
        if row.startswith("DAGNN"):
            return [_dagnn(rc, seed=s, **{table: float(column)}) for s in dagnn_seeds]
        return [_vgai(rc, seed=s, **{table: float(column)}) for s in vgai_seeds]
    if row == "DAGNN":
        K = int(column) + 1 if table == "K" else 4
        return [_dagnn(rc, K=K, seed=s) for s in dagnn_seeds]
    if row == "DAGNN (per neighbour)":
        return [_dagnn(rc, seed=s, feature_transform=PER_NEIGHBOUR) for s in dagnn_seeds]
    if row == "VGAI":
        F = int(column) if table == "F" else 24
        K = int(column) + 1 if table == "K" else 4
        return [_vgai(rc, F=F, K=K, seed=s) for s in vgai_seeds]
    raise ValueError(f"unknown row {row!r}")


def flight_config(rc: ReproduceConfig, table: str, column) -> FlockConfig:
    """The configuration a column's episodes are flown in."""
    if table in ("F", "K"):
        return _base_cfg(rc)
    if table == "v_init":
        return _base_cfg(rc, v_init=float(column))
    if table == "R":
        return _base_cfg(rc, R=float(column))
    if table == "N":
        n = int(column)
        return _base_cfg(rc, N=n, init_method="repair" if n >= rc.repair_from else "reject")
    raise ValueError(f"unknown table {table!r}; the tables are {sorted(TABLES)}")


def episodes_of(rc: ReproduceConfig, cfg: FlockConfig) -> int:
    n = rc.episodes_large if cfg.N >= 100 else rc.episodes
    return min(n, 2) if rc.quick else n


def plan(rc: ReproduceConfig, tables: list[str]) -> list[tuple]:
    """Every (table, row, column, spec, flight, episodes) of the run, in order."""
    jobs = []
    for table in tables:
        t = TABLES[table]
        for column in t["columns"]:
            flight = flight_config(rc, table, column)
            for row in rows_of(rc, table):
                if table == "F" and row == "DAGNN" and column != 6:
                    continue  # the DAGNN's features are its 6 exact ones
                for spec in models_of(rc, table, row, column):
                    jobs.append((table, row, column, spec, flight, episodes_of(rc, flight)))
    return jobs


TRAIN_SECONDS = {"local": 0.0, "dagnn": 60.0,
                 "vgai": 60.0 * training_minutes(json.loads(shipped_file("vgai/vgai_F24.json").read_text()))}
EPISODE_SECONDS = {"local": 0.1, "dagnn": 0.2, "vgai": 3.0}
"""Rough seconds to train a model and to fly one episode of 200 steps with 50 agents on this
machine: the progress display's estimate of the time left (nothing else uses them)."""


def _cost_estimate(spec: ModelSpec, flight: FlockConfig, episodes: int, out: Path, trained: set,
                   retrain: bool = False) -> float:
    """Rough seconds a cell will take (training its model first if no checkpoint exists yet)."""
    seconds = EPISODE_SECONDS[spec.kind] * episodes * flight.T / 200 * (flight.N / 50) ** (2 if spec.kind == "vgai" else 1)
    if spec.kind != "local" and spec.key() not in trained:
        trained.add(spec.key())
        if retrain or not model_path(spec, out).is_file():
            seconds += TRAIN_SECONDS[spec.kind] * (0.01 if spec.cfg.T < 200 else 1.0)
    return seconds


# ---------------------------------------------------------------------------------------------
# The run


def provenance(rc: ReproduceConfig, seconds: float, started: str) -> dict:
    def version(p):
        try:
            return md.version(p)
        except md.PackageNotFoundError:
            return None

    commit, dirty = git_state()
    return {"reproduce_config": dataclasses.asdict(rc), "started": started, "wall_seconds": round(seconds, 1),
            "git_commit": commit, "library_modified_since_commit": dirty,
            "python": platform.python_version(), "platform": platform.platform(),
            "torch_threads": torch.get_num_threads(),
            "packages": {p: version(p) for p in ("torch", "numpy", "pymunk", "matplotlib", "vgai-lite")},
            "command": " ".join(["python -m vgai_lite"] + sys.argv[1:]) if sys.argv else None}


def _aggregate(records: list[dict]) -> dict:
    means = [r["relative_cost_mean"] for r in records]
    first = records[0]
    out = {"relative_cost_mean": round(sum(means) / len(means), 4), "per_seed": means,
           "seed_std": round(float(torch.tensor(means).std()), 4) if len(means) > 1 else None,
           "ci95": first["relative_cost_mean_ci95"] if len(records) == 1 else None,
           "median": first["relative_cost_median"], "quartiles": first["relative_cost_quartiles"],
           "episodes": first["episodes"], "min_distance": min(r["min_distance"] for r in records),
           "median_min_distance": first["median_min_distance"],
           "share_below_0.05m": first["share_below_0.05m"],
           "expert_min_distance": first["expert_min_distance"],
           "expert_median_min_distance": first["expert_median_min_distance"],
           "expert_share_below_0.05m": first["expert_share_below_0.05m"],
           "cells": [r["key"] for r in records]}
    trained = [r["model"].get("train_config") for r in records if r["model"].get("kind") == "vgai"]
    if trained:  # whether every VGAI of the cell was trained with the book's recipe (``book_recipe``)
        book = [book_recipe(F=t["F"], K=t["K"], seed=t["seed"]).to_dict() for t in trained]
        out["book_recipe"] = all(json.dumps(t, sort_keys=True) == json.dumps(b, sort_keys=True)  # tuples as lists
                                 for t, b in zip(trained, book))
    if all("velocity_variance_median" in r for r in records):  # did it flock: median over training seeds
        times = list(first["velocity_variance_median"])
        out["velocity_variance_median"] = {
            t: float(torch.tensor([r["velocity_variance_median"][t] for r in records]).median()) for t in times}
        out["share_connected_at_end"] = float(torch.tensor([r["share_connected_at_end"] for r in records]).median())
    return out


def _tables(rc: ReproduceConfig, tables: list[str], records: dict) -> tuple[dict, list]:
    """Every table's cells (aggregated over training seeds, the paper's number beside) and the CSV rows."""
    out = {}
    rows_csv = []
    for table in tables:
        t = TABLES[table]
        entry = {"title": t["title"], "column": t["column"], "columns": t["columns"], "rows": {}}
        for row in rows_of(rc, table):
            cells = {}
            for column in t["columns"]:
                if (table, row, column) not in records:
                    continue
                agg = _aggregate(records[(table, row, column)])
                agg["paper"] = PAPER.get(table, {}).get(row, {}).get(column)
                cells[str(column)] = agg
                rows_csv.append({"table": table, "row": row, "column": t["column"], "value": column,
                                 "relative_cost_mean": agg["relative_cost_mean"],
                                 "ci95_low": (agg["ci95"] or [None, None])[0],
                                 "ci95_high": (agg["ci95"] or [None, None])[1],
                                 "seed_std": agg["seed_std"], "seeds": len(agg["per_seed"]),
                                 "episodes": agg["episodes"], "min_distance": agg["min_distance"],
                                 "share_below_0.05m": agg["share_below_0.05m"],
                                 "velocity_variance_2s": agg.get("velocity_variance_median", {}).get("2s"),
                                 "velocity_variance_5s": agg.get("velocity_variance_median", {}).get("5s"),
                                 "share_connected_5s": agg.get("share_connected_at_end"), "paper": agg["paper"]})
            entry["rows"][row] = cells
        out[table] = entry
    return out, rows_csv


def run(tables: Optional[list[str]] = None, rc: ReproduceConfig = ReproduceConfig(),
        out: Optional[Union[str, Path]] = None, progress: bool = True, ray: Optional[dict] = None) -> dict:
    """Compute (or read back) every cell of ``tables`` and write OUT/results.json and .csv.

    ``ray``: compute the trainings and cells as Ray tasks (``ray_runner``) instead of one after the
    other: a dict of ``ray_runner.run_jobs``'s options (``address``, ``cpus``, ``threads``); the
    files and numbers are those of a serial run with as many torch threads as ``threads``."""
    tables = list(tables or TABLES)
    unknown = [t for t in tables if t not in TABLES]
    if unknown:
        raise ValueError(f"unknown table(s) {unknown}; the tables are {list(TABLES)}")
    out = Path(out) if out is not None else DATA_DIR / ("results_quick" if rc.quick else "results")
    out.mkdir(parents=True, exist_ok=True)
    started = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    start = time.perf_counter()
    jobs = plan(rc, tables)
    seen: set = set()
    estimates = [_cost_estimate(s, f, e, out, seen, rc.retrain) for _, _, _, s, f, e in jobs]
    if rc.retrain:  # from scratch: no stage 1 left by an earlier run either
        for old in (out / "stage1").glob("*.pt"):
            old.unlink()
    retrained: set = set()
    total = sum(estimates)
    records: dict[tuple, list] = {}
    bar = tqdm(total=total, desc="reproduce", unit="est-s", disable=not progress,
               bar_format="{desc}: {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}] {postfix}")
    if ray is not None:
        bar.close()
        computed, ray_info = run_jobs(jobs, rc, out, progress=progress, **ray)
        for (table, row, column, *_), rec in zip(jobs, computed):
            records.setdefault((table, row, column), []).append(rec)
    for i, (table, row, column, spec, flight, episodes) in enumerate(jobs if ray is None else []):
        bar.set_postfix_str(f"cell {i + 1}/{len(jobs)}: table {table}, {row}, {TABLES[table]['column']} = {column:g}")
        retrain = rc.retrain and spec.kind != "local" and spec.key() not in retrained
        retrained.add(spec.key())
        rec = evaluate_cell(spec, flight, episodes, rc.seed, out, progress=False, retrain=retrain, fresh=rc.retrain)
        records.setdefault((table, row, column), []).append(rec)
        bar.update(estimates[i])
    bar.close()
    seconds = time.perf_counter() - start
    results = {"provenance": provenance(rc, seconds, started), "tables": {}}
    if ray is not None:
        results["provenance"]["ray"] = ray_info
    previous = out / "results.json"
    history = []
    if previous.is_file():
        try:
            history = json.loads(previous.read_text())["provenance"].get("invocations", [])
        except (ValueError, KeyError) as err:
            warnings.warn(f"{previous} is not a results file of this command ({err!r}): the list of earlier "
                          "invocations starts again with this one")
    every = {r["key"]: r for recs in records.values() for r in recs}.values()
    trained = {r["checkpoint"]: r.get("train_seconds_recorded", 0.0) for r in every if r.get("checkpoint")}
    results["provenance"]["compute_seconds"] = {
        "cells": len(every), "cells_computed_now": sum(r["computed_now"] for r in every),
        "evaluation": round(sum(r["eval_seconds"] for r in every), 1),
        "training_recorded": round(sum(trained.values()), 1),
        "note": "wall_seconds is this invocation; cells read back from OUT/cells were computed by earlier ones. "
                "evaluation: seconds each cell's evaluation took when it was computed; training_recorded: the "
                "training time recorded in each checkpoint used (shipped or trained by this command)"}
    p = results["provenance"]
    p["invocations"] = history + [{"started": started, "command": p["command"], "wall_seconds": p["wall_seconds"],
                                   **({"ray": ray_info} if ray is not None else {}),
                                   "git_commit": p["git_commit"], "retrain": rc.retrain, "tables": tables,
                                   "cells_computed_now": p["compute_seconds"]["cells_computed_now"],
                                   "models_trained_now": sum(1 for r in every if r["computed_now"]
                                                             and r.get("trained_now"))}]
    results["tables"], rows_csv = _tables(rc, tables, records)
    (out / "results.json").write_text(json.dumps(results, indent=1) + "\n")
    with open(out / "results.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows_csv[0]))
        w.writeheader()
        w.writerows(rows_csv)
    return results


def load_results(out: Optional[Union[str, Path]] = None) -> dict:
    """The results of the last run written to ``out`` (default data/results/)."""
    path = Path(out or DATA_DIR / "results") / "results.json"
    if not path.is_file():
        raise FileNotFoundError(f"no results at {path}: run `python -m vgai_lite reproduce` first")
    return json.loads(path.read_text())


def format_table(results: dict, table: str) -> str:
    """One table as text: ours (paper's) per row and column."""
    t = results["tables"][table]
    head = f"{t['column']:>18s} " + " ".join(f"{c:>14g}" for c in t["columns"])
    lines = [t["title"], head]
    for row, cells in t["rows"].items():
        parts = []
        for c in t["columns"]:
            cell = cells.get(str(c))
            if cell is None:
                parts.append(f"{'':>14s}")
                continue
            paper = f"({cell['paper']:.2f})" if cell["paper"] is not None else "(-)"
            parts.append(f"{cell['relative_cost_mean']:>7.2f} {paper:>6s}")
        lines.append(f"{row:>18s} " + " ".join(parts))
    return "\n".join(lines)

"""One cell of a reproduced table: a trained controller flown in one flight configuration.

Introduced in notebook 07. A cell is one (controller, flight configuration, episodes, seed); its
result is written to ``OUT/cells/KEY.json`` (KEY: ``checkpoints.config_hash`` of everything that
defines it) before the next starts, so an interrupted run resumes where it stopped and a cell shared
by several tables is computed once. Trained models are reused: the book's shipped checkpoints
(``runs.DAGNN_RUNS``, ``runs.VGAI_RUNS``, ``runs.VGAI_SEED_RUNS``) when the configuration is the same, otherwise
``OUT/models/``; VGAI runs that differ only in K share their first stage through ``OUT/stage1/``.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional

from ..book import DATA_DIR
from ..checkpoints import config_hash, is_finished_with, load_controller
from ..config import FlockConfig
from ..controllers import LocalController
from ..dagnn_training import train_dagnn
from ..evaluate import FLOCK_TIMES, relative_cost
from ..imitation import load_or_train
from .runs import DAGNN_RUNS, VGAI_RUNS, VGAI_SEED_RUNS
from ..vgai_training import train_vgai
from .provenance import repo_relative
from .stage1_cache import cached


@dataclass(frozen=True)
class ModelSpec:
    """A trained controller: kind ("dagnn", "vgai" or "local"), training configuration and name."""

    kind: str
    cfg: FlockConfig
    tcfg: Optional[object] = None
    name: str = ""

    def identity(self) -> dict:
        return {"kind": self.kind, "config": self.cfg.to_dict(),
                "train_config": self.tcfg.to_dict() if self.tcfg is not None else None}

    def key(self) -> str:
        return config_hash(self.identity())


def _shipped_path(spec: ModelSpec) -> Optional[Path]:
    """The book's checkpoint for ``spec`` when it ships one with exactly this configuration."""
    if spec.cfg != FlockConfig():
        return None
    shelves = ([(DAGNN_RUNS, "dagnn")] if spec.kind == "dagnn"
               else [(VGAI_RUNS, "vgai"), (VGAI_SEED_RUNS, "vgai/seeds")])
    for runs, folder in shelves:
        for name, t in runs.items():
            if t == spec.tcfg:
                return DATA_DIR / folder / f"{name}.pt"
    return None


QUICK_CHECK_EPISODES = 2
"""Episodes of the round check a quick run's training (short episodes, ``reproduce --quick``) logs after
each round (a full run: 10); the log never chooses anything, so fewer only save the test suite time."""


def model_path(spec: ModelSpec, out: Path) -> Path:
    return _shipped_path(spec) or out / "models" / f"{spec.name}_{spec.key()}.pt"


def obtain(spec: ModelSpec, out: Path, progress: bool = False,
           retrain: bool = False) -> tuple[Optional[Path], float, bool]:
    """Make sure ``spec`` has a finished checkpoint (train and save it now if none of the same
    configuration exists, or if ``retrain``). Returns (its path, None for the local heuristic;
    seconds spent; whether it was trained now). VGAI runs share their stage 1 through ``OUT/stage1/``."""
    if spec.kind == "local":
        return None, 0.0, False
    path = model_path(spec, out)
    path.parent.mkdir(parents=True, exist_ok=True)
    trained = retrain or not is_finished_with(path, spec.cfg, spec.tcfg.to_dict(), read=spec.tcfg.read_stored)
    start = time.perf_counter()
    if trained:  # otherwise the checkpoint is ready; evaluate_cell loads it in the flight configuration
        # the round check is logged, never used to choose: a quick run logs fewer episodes
        val = {"check_episodes": QUICK_CHECK_EPISODES} if spec.cfg.T < 200 else {}
        if spec.kind == "dagnn":
            load_or_train(path, spec.cfg, spec.tcfg, train_dagnn, retrain=retrain, progress=progress, **val)
        else:
            load_or_train(path, spec.cfg, spec.tcfg, train_vgai, retrain=retrain, progress=progress,
                          stage1=cached(out / "stage1"), **val)
    return path, time.perf_counter() - start, trained


def cell_identity(spec: ModelSpec, flight: FlockConfig, episodes: int, seed: int) -> dict:
    """Everything that defines a cell; its hash names the cell's file, OUT/cells/KEY.json."""
    return {"model": spec.identity(), "flight": flight.to_dict(), "episodes": episodes, "seed": seed}


def cell_path(spec: ModelSpec, flight: FlockConfig, episodes: int, seed: int, out: Path) -> Path:
    return Path(out) / "cells" / f"{config_hash(cell_identity(spec, flight, episodes, seed))}.json"


def evaluate_cell(spec: ModelSpec, flight: FlockConfig, episodes: int, seed: int, out: Path,
                  progress: bool = False, retrain: bool = False, fresh: bool = False,
                  obtained: Optional[tuple] = None) -> dict:
    """Fly the controller of ``spec`` in ``flight`` (episodes from ``seed``) and record its figures;
    read from OUT/cells/ if this exact cell was computed before, unless ``fresh``. ``retrain``:
    train the controller anew first. ``obtained``: what ``obtain`` returned when it ran elsewhere
    (a training task of ``ray_runner``), so that the record says the same as a serial run's."""
    ident = cell_identity(spec, flight, episodes, seed)
    return cached_cell(out, ident, lambda key: _fly_cell(key, ident, spec, flight, episodes, seed, out, progress,
                                                         retrain, obtained), fresh=fresh)


def _fly_cell(key, ident, spec, flight, episodes, seed, out, progress, retrain, obtained) -> dict:
    ckpt, train_seconds, trained = obtained or obtain(spec, out, progress, retrain=retrain)
    # fly it in this column's configuration (trained in spec.cfg)
    controller = LocalController(flight) if ckpt is None else load_controller(ckpt, cfg=flight)
    start = time.perf_counter()
    # did it flock: read at 2 s and 5 s (evaluate.FLOCK_TIMES); a quick run's short episodes (reproduce
    # --quick, T < 200) read it at their own end instead of flying on to 5 s, which would be most of their cost
    times = FLOCK_TIMES if flight.T >= 200 else (flight.T * flight.Ts,)
    res = relative_cost(controller, flight, episodes=episodes, seed=seed, name=spec.name, flock_times=times)
    record = {"key": key, **ident, "name": spec.name, **res.summary(),
              "min_distance": round(float(res.safety.min_distance.min()), 4),
              "expert_min_distance": round(float(res.expert_safety.min_distance.min()), 4),
              "eval_seconds": round(time.perf_counter() - start, 1),
              "train_seconds_now": round(train_seconds, 1) if trained else 0.0,
              "trained_now": trained,
              "checkpoint": repo_relative(ckpt) if ckpt is not None else None}
    if spec.kind != "local":
        record["train_seconds_recorded"] = round(controller.meta.get("history", {}).get("seconds", 0.0), 1)
    return record


def cached_cell(out: Path, ident: dict, compute: Callable[[str], dict], fresh: bool = False) -> dict:
    """The record of the cell ``ident`` (a dict of everything that defines it), with ``computed_now``:
    read from OUT/cells/KEY.json (KEY = ``config_hash(ident)``) if an earlier run computed it, unless
    ``fresh``; otherwise ``compute(KEY)``, written there before the next cell starts. The tables'
    cells and the robustness sweep's (``robustness.evaluate``) are cached by this one rule."""
    key = config_hash(ident)
    path = Path(out) / "cells" / f"{key}.json"
    if path.is_file() and not fresh:
        return {**json.loads(path.read_text()), "computed_now": False}
    record = compute(key)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record, indent=1) + "\n")
    return {**record, "computed_now": True}


"""How the learned controllers degrade: the shipped DAGNN and VGAI flown in perturbed worlds.

Introduced in notebook 08; run with ``python -m vgai_lite reproduce --only robustness``. A sweep is
one config object, ``RobustnessConfig``: for every perturbation of ``perturbations`` and every size
in its list, each controller it applies to is flown on the book's test episodes (seed
``book.TEST_SEED``, the tables' episodes: the sweep reports, it chooses nothing) and judged as everywhere in the book: the relative cost of eq. 1 (expert = 1.00),
whether it flocked (velocity variance at 2 s and 5 s, connected at the end) and whether it was safe
(closest approaches). The Local heuristic and the expert fly unperturbed, as the reference lines.

As in ``reproduce``, every cell (controller, team size, perturbations, episodes, seed) is written to
``OUT/cells/KEY.json`` before the next starts, so an interrupted sweep resumes; KEY hashes the
checkpoint's bytes, so a retrained controller gets new cells. ``OUT/results.json`` gathers them.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Optional, Union

import torch
from tqdm.auto import tqdm

from ..book import DATA_DIR, QUICK_T, TEST_SEED
from ..checkpoints import load_controller
from ..config import FlockConfig
from ..controllers import LocalController
from ..evaluate import FLOCK_TIMES, relative_cost
from .provenance import sha256
from .table_cells import cached_cell
from .perturbations import (Blur, DeadCamera, DroppedLinks, ImageNoise, MessageDelay, PositionNoise,
                            perturbed)

CONTROLLERS = {"DAGNN": DATA_DIR / "dagnn" / "dagnn_K4.pt", "VGAI": DATA_DIR / "vgai" / "vgai_F24.pt"}
"""The shipped controllers under test: the book's default DAGNN and VGAI."""

KINDS = {"links": DroppedLinks, "delay": MessageDelay, "image_noise": ImageNoise, "blur": Blur,
         "dead_camera": DeadCamera, "position_noise": PositionNoise}
"""Perturbation names used in the sweep's records, and their classes (``perturbations``)."""

APPLIES_TO = {"links": ("DAGNN", "VGAI"), "delay": ("DAGNN", "VGAI"), "image_noise": ("VGAI",),
              "blur": ("VGAI",), "dead_camera": ("VGAI",), "position_noise": ("DAGNN",)}
"""Which controllers each perturbation can reach: the cameras are VGAI's, the exact positions the DAGNN's."""


TARGETS = {"links_p": 0.2, "connected": 0.9, "image_noise_sigma": 0.05, "image_noise_ratio": 1.2}
"""What VGAI should survive (criteria of the book, not of the paper): with a share ``links_p`` of its
messages lost, a cost below the Local heuristic's and the swarm connected at the end in at least
``connected`` of episodes; with pixel noise ``image_noise_sigma``, a cost at most ``image_noise_ratio``
times its clean cost."""


def make(kind: str, size) -> object:
    """The perturbation ``kind`` of ``size`` (DeadCamera takes none: size 1 means on)."""
    if kind not in KINDS:
        raise ValueError(f"unknown perturbation {kind!r}; expected one of {sorted(KINDS)}")
    if kind == "dead_camera":
        return DeadCamera()
    if kind == "delay":
        return MessageDelay(int(size))
    return KINDS[kind](float(size))


@dataclass(frozen=True)
class RobustnessConfig:
    """The sweep of notebook 08.

    Attributes:
        perturbations: (name, sizes) pairs, each flown alone from the clean controller; sizes are the
            perturbation's parameter (p, sigma in pixel values or pixels or metres, steps of delay).
            The sweep spans p = 0 to 0.5 and sigma = 0 to 0.2 (size 0 is the clean flight); VGAI's
            pixel-noise curve stops at 0.1 and its blur at one pixel to keep the sweep short (a VGAI
            cell renders every drone's view at every step, the DAGNN's position noise does not and
            goes to 0.2; results.json records the sweep's minutes).
        combined: perturbation sets flown together, e.g. the noise with a blur that averages it away.
        large_teams: N' flown with the clean controllers and with ``large_perturbations``.
        large_perturbations: the perturbations that hurt most at N = 50, read off its curves: pixel
            noise for VGAI, position noise for the DAGNN (lost messages barely move either), at the
            size of the sweep's target (0.05).
        episodes, episodes_large: held-out episodes per cell at N = 50 and at N' >= 100 (where a VGAI
            episode renders N'^2 views per step).
        flock_times: seconds at which "did it flock" is read at N = 50; at N' >= 100 only the paper's
            2 s (T = 200 steps), to keep the largest VGAI flights short.
        seed: the episodes (the book's TEST_SEED, as the tables: every figure here is reported, none
            chooses anything; ``large_perturbations`` and the sizes were read off an earlier sweep on
            WORKING_SEED's episodes); the perturbations' draws use it too.
        quick: a tiny sweep of short episodes (the tests).
    """

    perturbations: tuple = (("links", (0.1, 0.2, 0.3, 0.5)), ("image_noise", (0.02, 0.05, 0.1)),
                            ("position_noise", (0.02, 0.05, 0.1, 0.2)), ("blur", (1.0,)),
                            ("dead_camera", (1,)), ("delay", (1,)))
    combined: tuple = ((("image_noise", 0.05), ("blur", 1.0)),)
    large_teams: tuple = (100, 200)
    large_perturbations: tuple = (("image_noise", 0.05), ("position_noise", 0.05))
    episodes: int = 20
    episodes_large: int = 4
    flock_times: tuple = FLOCK_TIMES
    seed: int = TEST_SEED
    quick: bool = False

    def __post_init__(self):
        for kind, sizes in self.perturbations:
            make(kind, sizes[0])
        for name in ("episodes", "episodes_large"):
            if not isinstance(getattr(self, name), int) or getattr(self, name) < 1:
                raise ValueError(f"{name} must be a positive integer, got {getattr(self, name)!r}")

    @staticmethod
    def quick_sweep() -> "RobustnessConfig":
        return RobustnessConfig(perturbations=(("links", (0.2,)), ("image_noise", (0.05,)),
                                               ("position_noise", (0.05,)), ("delay", (1,))),
                                combined=(), large_teams=(), episodes=2, flock_times=(0.2,), quick=True)




def flight(rc: RobustnessConfig, N: int = 50) -> FlockConfig:
    cfg = FlockConfig(N=N, init_method="repair" if N >= 75 else "reject")
    return cfg.replace(T=QUICK_T) if rc.quick else cfg


def plan(rc: RobustnessConfig) -> list[dict]:
    """Every cell of the sweep: {controller, N, perturbations: ((name, size), ...)}, in order."""
    cells = []
    teams = (50,) + tuple(rc.large_teams)
    for N in teams:
        cells.append({"controller": "Local", "N": N, "perturbations": ()})
        for c in CONTROLLERS:
            cells.append({"controller": c, "N": N, "perturbations": ()})
    for kind, sizes in rc.perturbations:
        for size in sizes:
            for c in APPLIES_TO[kind]:
                cells.append({"controller": c, "N": 50, "perturbations": ((kind, size),)})
    for combo in rc.combined:
        for c in CONTROLLERS:
            if all(c in APPLIES_TO[k] for k, _ in combo):
                cells.append({"controller": c, "N": 50, "perturbations": tuple(combo)})
    for N in rc.large_teams:
        for kind, size in rc.large_perturbations:
            for c in APPLIES_TO[kind]:
                cells.append({"controller": c, "N": N, "perturbations": ((kind, size),)})
    return cells


def checkpoint_id(path: Path) -> str:
    """The first 12 digits of a checkpoint's sha256: what a cell's key knows of the controller it flew."""
    return sha256(path)[:12]


def controller_for(name: str, cfg: FlockConfig, perturbations: tuple, seed: int):
    """The controller of a cell: Local (never perturbed) or a shipped learned one in its world."""
    if name == "Local":
        if perturbations:
            raise ValueError("the Local heuristic is the unperturbed reference")
        return LocalController(cfg)
    base = load_controller(CONTROLLERS[name], cfg=cfg)
    return perturbed(base, *(make(k, s) for k, s in perturbations), seed=seed) if perturbations else base


def evaluate(cell: dict, rc: RobustnessConfig, out: Path) -> dict:
    """Fly one cell (or read it back from OUT/cells/) and return its record."""
    cfg = flight(rc, cell["N"])
    episodes = rc.episodes if cell["N"] < 100 else rc.episodes_large
    times = tuple(rc.flock_times) if cell["N"] < 100 else (min(rc.flock_times),)
    ident = {"controller": cell["controller"], "perturbations": [list(p) for p in cell["perturbations"]],
             "checkpoint": checkpoint_id(CONTROLLERS[cell["controller"]]) if cell["controller"] in CONTROLLERS else None,
             "flight": cfg.to_dict(), "episodes": episodes, "seed": rc.seed, "flock_times": list(times)}

    def fly(key: str) -> dict:
        controller = controller_for(cell["controller"], cfg, cell["perturbations"], rc.seed)
        start = time.perf_counter()
        res = relative_cost(controller, cfg, episodes=episodes, seed=rc.seed, flock_times=times,
                            name=getattr(controller, "name", cell["controller"]))
        return {"key": key, **res.summary(), **ident, "name": res.name,
                "min_distance": round(float(res.safety.min_distance.min()), 4),
                "eval_seconds": round(time.perf_counter() - start, 1)}
    return cached_cell(out, ident, fly)


def run(rc: RobustnessConfig = RobustnessConfig(), out: Optional[Union[str, Path]] = None,
        progress: bool = True) -> dict:
    """Every cell of the sweep; writes OUT/results.json (default data/robustness/, or _quick)."""
    out = Path(out) if out is not None else DATA_DIR / ("robustness_quick" if rc.quick else "robustness")
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    cells = plan(rc)
    records = []
    for cell in tqdm(cells, desc="robustness", disable=not progress):
        records.append(evaluate(cell, rc, out))
    results = {"config": asdict(rc), "torch_threads": torch.get_num_threads(),
               "wall_seconds": round(time.perf_counter() - start, 1),
               "cells_computed_now": sum(r["computed_now"] for r in records),
               "evaluation_seconds": round(sum(r["eval_seconds"] for r in records), 1),
               "cells": [{k: v for k, v in r.items() if k != "computed_now"} for r in records]}
    (out / "results.json").write_text(json.dumps(results, indent=1) + "\n")
    return results


def load(out: Optional[Union[str, Path]] = None) -> dict:
    path = Path(out or DATA_DIR / "robustness") / "results.json"
    if not path.is_file():
        raise FileNotFoundError(f"no robustness results at {path}: run "
                                "`python -m vgai_lite reproduce --only robustness` first")
    return json.loads(path.read_text())


def find(results: dict, controller: str, perturbations: tuple = (), N: int = 50) -> dict:
    """The record of one cell of a sweep's results."""
    want = [list(p) for p in perturbations]
    for c in results["cells"]:
        if c["controller"] == controller and c["perturbations"] == want and c["flight"]["N"] == N:
            return c
    raise KeyError(f"no cell {controller} with {perturbations} at N = {N} in these results")


def curve(results: dict, controller: str, kind: str) -> tuple[list, list]:
    """(sizes, records) of one perturbation's curve for ``controller``, size 0 being the clean cell."""
    sizes, recs = [0.0], [find(results, controller)]
    for c in results["cells"]:
        p = c["perturbations"]
        if c["controller"] == controller and c["flight"]["N"] == 50 and len(p) == 1 and p[0][0] == kind:
            sizes.append(float(p[0][1])), recs.append(c)
    order = sorted(range(len(sizes)), key=sizes.__getitem__)
    return [sizes[i] for i in order], [recs[i] for i in order]


def format_results(results: dict) -> str:
    """The sweep as text: one line per cell, cost beside did-it-flock and safety."""
    lines = [f"{'controller':>8s} {'N':>4s} {'perturbation':<34s} {'cost':>6s} {'95% CI':>13s} "
             f"{'var 2 s':>8s} {'var end':>8s} {'conn.':>6s} {'<5cm':>5s}"]
    for c in results["cells"]:
        what = " + ".join(f"{k} {v:g}" for k, v in c["perturbations"]) or "none"
        var = c.get("velocity_variance_median", {})
        lo, hi = c["relative_cost_mean_ci95"]
        end = var.get(max(var, key=lambda t: float(t.rstrip("s")))) if var else float("nan")
        lines.append(f"{c['controller']:>8s} {c['flight']['N']:>4d} {what:<34s} {c['relative_cost_mean']:>6.2f} "
                     f"{lo:>6.2f}-{hi:<6.2f} {var.get('2s', float('nan')):>8.1e} {end:>8.1e} "
                     f"{c.get('share_connected_at_end', float('nan')):>6.0%} {c['share_below_0.05m']:>5.0%}")
    return "\n".join(lines)

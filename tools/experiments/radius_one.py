"""Experiment: can a decentralized DAGNN keep the swarm connected at R = 1 m? (issue: one controller for every
team and radius; target: connected at 5 s in at least 90 % of episodes, variance at 5 s at most 1e-2)

    python tools/experiments/radius_one.py --threads 1 \
        --recipe "per neighbour, R = 1.5 m=data/experiments/dagnn_per_neighbour.pt,data/experiments/dagnn_per_neighbour_seed1.pt,data/experiments/dagnn_per_neighbour_seed2.pt" ...

Flies each recipe's trainings (one checkpoint per training seed, trained by ``teams_and_radii.py``) and the
centralized expert and the k-hop oracles of ``khop_oracle.py`` (the expert's gain on the exact mean velocity
within k hops: the most a controller exchanging k times could know) at R = 1 m, N = 50, on validation episodes (``book.VALIDATION_SEED``: the recipes are
chosen here, so never the test episodes), and records per checkpoint the relative cost, the velocity
variance at 5 s and the share connected at 5 s; per recipe the mean and the spread between its seeds.

Which swarms start in one piece: the initial conditions ask every drone for two neighbours, not for one
connected graph, and at R = 1 m some episodes start in pieces (``consensus.connected_at_start``). Nothing in
eq. 2 pulls pieces together (its potential acts within rho only); they rejoin only if their first motions bring
them within R. So the record also gives, for every controller, the share of the episodes that start connected
which it keeps connected, and how many pieces rejoined.
With ``--gains``, the first recipe's trainings fly again with their actions scaled (``Scaled``): whether
braking harder on the same features holds more links.
Writes ``data/experiments/radius_one.json``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from vgai_lite import ExpertController, load_controller, relative_cost  # noqa: E402
from vgai_lite.book import DATA_DIR, VALIDATION_SEED  # noqa: E402
from vgai_lite.consensus import connected_at_start  # noqa: E402
from vgai_lite.flocking import saturate  # noqa: E402
from vgai_lite.lab.provenance import Provenance, repo_relative, sha256  # noqa: E402
from vgai_lite.lab.reproduce import ReproduceConfig, flight_config  # noqa: E402
from khop_oracle import KHopOracle  # noqa: E402


class Scaled:
    """A controller's action times ``gain``, saturated again: how hard it brakes, with its exchanges' delays
    unchanged (a measurement of what limits it, not a controller of the book)."""

    def __init__(self, controller, gain: float, cfg):
        self.controller, self.gain, self.cfg, self.name = controller, gain, cfg, f"x{gain:g}"

    def reset(self) -> None:
        self.controller.reset()

    def __call__(self, r: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
        return saturate(self.gain * self.controller(r, v), self.cfg)


def _figures(res, start: torch.Tensor) -> dict:
    s = res.summary()
    end = res.flocking.groups_at_end == 1
    return {"relative_cost_mean": s["relative_cost_mean"], "relative_cost_mean_ci95": s["relative_cost_mean_ci95"],
            "velocity_variance_5s": s["velocity_variance_median"]["5s"],
            "share_connected_at_end": s["share_connected_at_end"],
            "share_kept_connected": round(float(end[start].double().mean()), 3),
            "rejoined": int((end & ~start).sum()), "share_below_0.05m": s["share_below_0.05m"],
            "expert_share_below_0.05m": s["expert_share_below_0.05m"]}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--recipe", action="append", required=True, metavar="LABEL=CKPT,CKPT",
                   help="a recipe's label and its trainings' checkpoints (one per training seed)")
    p.add_argument("--R", type=float, default=1.0)
    p.add_argument("--oracle-hops", default="3,5", help="k of the k-hop oracles flown beside (khop_oracle.py)")
    p.add_argument("--episodes", type=int, default=30)
    p.add_argument("--gains", default="2,4", help="the first recipe's trainings flown again with their action times "
                                                   "each of these gains (Scaled)")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--out", default=str(DATA_DIR / "experiments" / "radius_one.json"))
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    command = " ".join(["python tools/experiments/radius_one.py"] + (argv or sys.argv[1:]))
    flight = flight_config(ReproduceConfig(), "R", args.R)
    seed = VALIDATION_SEED
    start = connected_at_start(flight, args.episodes, seed=seed)
    out = {"command": command, "N": flight.N, "R": flight.R, "episodes": args.episodes, "seed": seed,
           "share_connected_at_start": round(float(start.double().mean()), 3), "recipes": {}}
    with Provenance(command) as prov:
        expert = relative_cost(ExpertController(flight), flight, episodes=args.episodes, seed=seed, name="expert")
        out["expert"] = _figures(expert, start)
        print("expert", out["expert"], flush=True)
        out["oracles"] = {}
        for k in (int(x) for x in args.oracle_hops.split(",") if x):  # the most a k-exchange controller could know
            res = relative_cost(KHopOracle(flight, k), flight, episodes=args.episodes, seed=seed, name=f"{k}-hop")
            out["oracles"][f"{k}-hop"] = _figures(res, start)
            print(f"{k}-hop oracle", out["oracles"][f"{k}-hop"], flush=True)
        for spec in args.recipe:
            label, _, paths = spec.rpartition("=")  # labels may hold "=", paths do not
            if not paths:
                raise ValueError(f"--recipe wants LABEL=CKPT,CKPT..., got {spec!r}")
            runs = []
            for path in paths.split(","):
                res = relative_cost(load_controller(path, cfg=flight), flight, episodes=args.episodes, seed=seed,
                                    name=Path(path).stem)
                runs.append({"checkpoint": repo_relative(path), "checkpoint_sha256": sha256(path), **_figures(res, start)})
                print(label, runs[-1], flush=True)
            connected = [r["share_connected_at_end"] for r in runs]
            costs = [r["relative_cost_mean"] for r in runs]
            out["recipes"][label] = {
                "runs": runs, "seeds": len(runs),
                "share_connected_at_end_mean": round(statistics.mean(connected), 3),
                "share_connected_at_end_seed_std": round(statistics.stdev(connected), 3) if len(runs) > 1 else None,
                "relative_cost_mean": round(statistics.mean(costs), 4),
                "relative_cost_seed_std": round(statistics.stdev(costs), 4) if len(runs) > 1 else None,
                "velocity_variance_5s_median_of_seeds": statistics.median(r["velocity_variance_5s"] for r in runs)}
        first = next(iter(out["recipes"].values()))["runs"]
        out["gains"] = {}
        for gain in (float(x) for x in args.gains.split(",") if x):
            runs = []
            for run in first:
                res = relative_cost(Scaled(load_controller(run["checkpoint"], cfg=flight), gain, flight), flight,
                                    episodes=args.episodes, seed=seed, name=f"x{gain:g}")
                runs.append({"checkpoint": run["checkpoint"], **_figures(res, start)})
                print(f"gain x{gain:g}", runs[-1], flush=True)
            out["gains"][f"{gain:g}"] = runs
    flown = [run["checkpoint"] for recipe in out["recipes"].values() for run in recipe["runs"]]
    out["provenance"] = prov.record(seed=seed, episodes=args.episodes, checkpoints={c: sha256(c) for c in flown})
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    print("wrote", args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

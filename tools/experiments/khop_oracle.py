"""Experiment: is information what keeps a local controller from flocking at R = 1 m? (issue: one
controller for every team and radius).

    python tools/experiments/khop_oracle.py --threads 1

Flies, on validation episodes (``book.VALIDATION_SEED``) of Table 3's columns R = 1.0 and 1.5 m, an
oracle that knows exactly what a controller exchanging k times could know at best: the mean velocity
of the drones within k hops (itself included), with no delay, and applies the expert's gain to it,

    u_i = N (vbar_i^k - v_i) - sum_{j: ||r_ij|| <= rho} grad U(r_ij)      (eq. 2 with the k-hop mean),

beside the expert itself (every drone's velocity). Writes ``data/experiments/khop_oracle.json``: per
radius and k the relative cost, the velocity variance at 5 s and the share of episodes whose
communication graph is connected at 5 s. Not a controller of the book: a measurement of the limit.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from vgai_lite import ExpertController, relative_cost  # noqa: E402
from vgai_lite.book import DATA_DIR, VALIDATION_SEED  # noqa: E402
from vgai_lite.controllers import _repulsion  # noqa: E402
from vgai_lite.flocking import pairwise_offsets, saturate  # noqa: E402
from vgai_lite.graphs import adjacency, k_hop_reach  # noqa: E402
from vgai_lite.lab.provenance import Provenance  # noqa: E402
from vgai_lite.lab.reproduce import ReproduceConfig, flight_config  # noqa: E402


class KHopOracle:
    """The expert's gain on the exact k-hop mean velocity: the most a k-exchange controller could know."""

    def __init__(self, cfg, hops: int):
        self.cfg, self.hops, self.name = cfg, hops, f"{hops}-hop oracle"

    def __call__(self, r: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
        reach = k_hop_reach(adjacency(r, self.cfg.R), self.hops).to(v.dtype)
        vbar = (reach @ v) / reach.sum(-1, keepdim=True)
        dx, dy, d2 = pairwise_offsets(r)
        return saturate(r.shape[1] * (vbar - v) + _repulsion(dx, dy, d2, d2 <= self.cfg.rho ** 2, self.cfg), self.cfg)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--radii", default="1.0,1.5")
    p.add_argument("--hops", default="1,3,6")
    p.add_argument("--episodes", type=int, default=10)
    p.add_argument("--threads", type=int, default=2)
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    command = " ".join(["python tools/experiments/khop_oracle.py"] + (argv or sys.argv[1:]))
    out = {"command": command, "controller": "k-hop oracle", "radii": {}}
    with Provenance(command) as prov:
        for R in (float(x) for x in args.radii.split(",")):
            flight = flight_config(ReproduceConfig(), "R", R)
            ctrls = {"expert": ExpertController(flight), **{f"{k}-hop": KHopOracle(flight, k)
                                                           for k in (int(x) for x in args.hops.split(","))}}
            out["radii"][str(R)] = {}
            for name, ctrl in ctrls.items():
                s = relative_cost(ctrl, flight, episodes=args.episodes, seed=VALIDATION_SEED, name=name).summary()
                out["radii"][str(R)][name] = {k: s[k] for k in ("relative_cost_mean", "relative_cost_mean_ci95",
                                                               "velocity_variance_median", "share_connected_at_end",
                                                               "share_below_0.05m", "episodes")}
                print(R, name, out["radii"][str(R)][name], flush=True)
    out["provenance"] = prov.record(seed=VALIDATION_SEED, episodes=args.episodes)
    (DATA_DIR / "experiments" / "khop_oracle.json").write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Experiment: does the expert itself flock in the large teams the tables fly? (issue: one controller
for every team and radius.)

    python tools/experiments/expert_stability.py

The expert of eq. 2 aligns every drone with the whole swarm, u_i = -sum_j (v_i - v_j) = N (vbar - v_i),
and the double integrator steps v(t+1) = v(t) + Ts u(t). Unsaturated and away from the potential, a
drone's velocity deviation from the mean therefore obeys

    v_i(t+1) - vbar = (1 - N Ts) (v_i(t) - vbar),

which decays for N Ts < 2 (at once for N Ts = 1: N = 100 at the paper's Ts = 0.01), alternates
without decaying at N Ts = 2 (N = 200), and grows for N Ts > 2 until the saturation u_max holds it.
A controller that imitates the expert in those teams imitates an oscillation.

Flies the expert and the DAGNNs of ``DEFAULT_CONTROLLERS`` (or those given with ``--controller NAME=CKPT``) on validation episodes
(``book.VALIDATION_SEED``) at each N' of ``--teams``, as ``reproduce.flight_config`` flies Table 2b's
columns, to 5 s, and writes ``data/experiments/expert_stability.json``: per team the predicted factor
1 - N Ts, the measured one (late in the flight, the regression of each drone's velocity deviation on
its deviation one step before), the velocity variance at 2 and 5 s and connectivity at 5 s.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from vgai_lite import load_controller  # noqa: E402
from vgai_lite.book import DATA_DIR, VALIDATION_SEED  # noqa: E402
from vgai_lite.consensus import groups  # noqa: E402
from vgai_lite.controllers import ExpertController  # noqa: E402
from vgai_lite.flocking import rollout, sample_initial_state, velocity_variance  # noqa: E402
from vgai_lite.lab.provenance import Provenance, repo_relative, sha256  # noqa: E402
from vgai_lite.lab.reproduce import ReproduceConfig, flight_config  # noqa: E402

HORIZON_S = 5.0
LATE_S = 1.0  # the measured factor is read over the flight's last second
# the book's DAGNN (trained at N = 50) and the one trained on teams of 50, 100 and 200 (teams_and_radii.py)
DEFAULT_CONTROLLERS = ("dagnn_K4=data/dagnn/dagnn_K4.pt", "dagnn_teams=data/experiments/dagnn_teams.pt")


def step_factor(v: torch.Tensor, Ts: float):
    """Least-squares a in dv(t+1) = a dv(t) over the last LATE_S, dv = v_i - vbar; v is (T, B, N, 2).
    None where the deviations have died out (mean square below 1e-12 m²/s²: nothing left to measure)."""
    dv = v - v.mean(dim=2, keepdim=True)
    late = dv[-int(round(LATE_S / Ts)) - 1:].double()
    now, nxt = late[:-1], late[1:]
    if now.square().mean() < 1e-12:
        return None
    return round(float((now * nxt).sum() / now.square().sum()), 4)


def fly(controller, cfg, episodes: int) -> dict:
    steps = int(round(HORIZON_S / cfg.Ts)) + 1
    g = torch.Generator().manual_seed(VALIDATION_SEED)
    r0, v0 = sample_initial_state(cfg, episodes, g)
    traj = rollout(controller, cfg, r0, v0, steps=steps)
    var = velocity_variance(traj.v)
    at = {f"{t:g}s": round(float(var[int(round(t / cfg.Ts))].median()), 8) for t in (2.0, HORIZON_S)}
    connected = float((groups(traj.r[-1], cfg.R) == 1).double().mean())
    return {"measured_factor": step_factor(traj.v, cfg.Ts), "velocity_variance_median": at,
            "share_connected_at_end": round(connected, 4)}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--teams", default="50,100,150,200,250")
    p.add_argument("--controller", action="append", default=None, metavar="NAME=CKPT",
                   help="also fly this checkpoint in every team (repeatable; default: " + ", ".join(DEFAULT_CONTROLLERS) + ")")
    p.add_argument("--episodes", type=int, default=10)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--out", default=str(DATA_DIR / "experiments" / "expert_stability.json"))
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    command = " ".join(["python tools/experiments/expert_stability.py"] + (argv or sys.argv[1:]))
    others = []
    for spec in args.controller or DEFAULT_CONTROLLERS:
        name, sep, ckpt = spec.partition("=")
        if not sep or not name or not ckpt:
            raise SystemExit(f"--controller expects NAME=CKPT, got {spec!r}")
        others.append((name, Path(ckpt)))
    rc = ReproduceConfig()
    out = {"command": command, "horizon_s": HORIZON_S, "teams": {}}
    with Provenance(command) as prov:
        for n in (int(x) for x in args.teams.split(",") if x):
            cfg = flight_config(rc, "N", n)
            row = {"N": n, "Ts": cfg.Ts, "predicted_factor": round(1 - n * cfg.Ts, 4),
                   "expert": fly(ExpertController(cfg), cfg, args.episodes)}
            for name, ckpt in others:
                row[name] = fly(load_controller(ckpt, cfg=cfg), cfg, args.episodes)
            out["teams"][str(n)] = row
            print(json.dumps(row), flush=True)
    out["provenance"] = prov.record(seed=VALIDATION_SEED, episodes=args.episodes,
                                    checkpoints={repo_relative(c): sha256(c) for _, c in others})
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    print("wrote", args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Experiment: does VGAI's visual state estimator see the velocity disagreements that
VGAI's own late flight still has, and does training it on synthetic relative velocities help?

    python tools/experiments/stage1_velocity.py --out data/experiments/stage1_velocity.json

Trains two stand-alone estimators exactly like stage 1 of the book's VGAI (expert flights, 3,000
steps, seed 0): as shipped, and with half of the training states shown with synthetic velocities
(``state_estimation.synthetic_velocities``). Each is probed along flights of the shipped VGAI
(``data/vgai/vgai_F24.pt``) from the book's held-out initial conditions: correlation of each of the
6 estimated local features with the exact ones, at t = 20, 60, 120, 190, with the median speed of
the drones relative to the swarm's mean velocity at those steps.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from vgai_lite import FlockConfig, load_controller, rollout, sample_initial_state  # noqa: E402
from vgai_lite.book import DATA_DIR, WORKING_SEED  # noqa: E402
from vgai_lite.state_estimation import estimator_quality, train_state_estimator  # noqa: E402
from vgai_lite.vision import VisionConfig  # noqa: E402

TIMES = (20, 60, 120, 190)


def relative_speeds(cfg: FlockConfig, pilot, episodes: int) -> dict:
    r0, v0 = sample_initial_state(cfg, episodes, torch.Generator().manual_seed(WORKING_SEED))
    v = rollout(pilot, cfg, r0, v0, steps=max(TIMES) + 1).v
    return {t: float((v[t] - v[t].mean(1, keepdim=True)).norm(dim=-1).median()) for t in TIMES}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--steps", type=int, default=3000)
    p.add_argument("--episodes", type=int, default=8, help="held-out VGAI flights probed")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--out", default=None)
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    cfg, vision = FlockConfig(), VisionConfig()
    pilot = load_controller(DATA_DIR / "vgai" / "vgai_F24.pt")
    out = {"command": " ".join(["python tools/experiments/stage1_velocity.py"] + (argv or sys.argv[1:])),
           "relative_speed_median_m_s": relative_speeds(cfg, pilot, args.episodes), "estimators": {}}
    for label, share in (("as shipped", 0.0), ("half synthetic velocities", 0.5)):
        start = time.perf_counter()
        cnn, losses, _ = train_state_estimator(cfg, vision, steps=args.steps, progress=False, synthetic_share=share)
        q = estimator_quality(cnn, vision, cfg, episodes=args.episodes, times=TIMES, pilot=pilot)
        out["estimators"][label] = {"synthetic_share": share, "seconds": round(time.perf_counter() - start, 1),
                                    "correlation_along_vgai_flights": {t: [round(x, 3) for x in c] for t, c in q.items()}}
        print(label, json.dumps(out["estimators"][label]["correlation_along_vgai_flights"]), flush=True)
    print(json.dumps(out, indent=1))
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

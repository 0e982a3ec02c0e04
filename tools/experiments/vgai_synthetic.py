"""Experiment: the book's default VGAI trained with half of stage 1's states shown with
synthetic velocities, everything else as ``runs.VGAI_RUNS["vgai_F24"]``; relative cost on 50
held-out episodes and the flocking figures (velocity variance at 0.5-5 s, connectivity) on 10.

    python tools/experiments/vgai_synthetic.py --out data/experiments/vgai_synthetic.json

The checkpoint goes to data/experiments/ (not a shipped model).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from vgai_lite import FlockConfig, consensus, relative_cost, train_vgai  # noqa: E402
from vgai_lite.book import DATA_DIR, WORKING_SEED  # noqa: E402
from vgai_lite.lab.runs import VGAI_RUNS  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--share", type=float, default=0.5)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--out", required=True)
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    cfg = FlockConfig()
    tcfg = dataclasses.replace(VGAI_RUNS["vgai_F24"], synthetic_share=args.share)
    ckpt = DATA_DIR / "experiments" / f"vgai_F24_synthetic{args.share:g}.pt"
    controller, hist = train_vgai(cfg, tcfg, checkpoint=ckpt, progress=False)
    res = relative_cost(controller, cfg, episodes=50, seed=WORKING_SEED, name="VGAI, synthetic stage 1")
    flock = consensus(controller, cfg, episodes=10, seed=WORKING_SEED)
    print(res), print(flock)
    out = {"command": " ".join(["python tools/experiments/vgai_synthetic.py"] + sys.argv[1:]),
           "train_config": tcfg.to_dict(), "train_seconds": round(hist["seconds"], 1),
           "validation": hist["rounds"], **res.summary(), "consensus": flock.summary()}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Experiment: how well a VGAI's CNN still reads the six local features through a noisy camera.

    python tools/experiments/estimator_under_noise.py --out data/experiments/estimator_under_noise.json

For each checkpoint (the book's recipe on clean frames (training seed 0), and the VGAIs trained through the
camera), its CNN's state-estimation head (kept by the book's recipe, ``aux_weight`` > 0) is read on
expert flights from validation initial conditions (``book.VALIDATION_SEED``) seen through sensor
noise of each sigma (on the gray channel): the correlation of each of the six estimated local features (eq. 9:
velocity differences, two repulsion sums) with the exact ones at t = 2, 8 and 20 steps, when the
drones still move relative to each other. It says whether the images still carry what the
controller needs at a noise level, or whether the CNN has stopped reading it.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from vgai_lite import FlockConfig, load_controller  # noqa: E402
from vgai_lite.book import DATA_DIR, VALIDATION_SEED  # noqa: E402
from vgai_lite.camera import CameraRanges  # noqa: E402
from vgai_lite.features import FEATURE_NAMES  # noqa: E402
from vgai_lite.lab.provenance import Provenance, sha256  # noqa: E402
from vgai_lite.state_estimation import estimator_quality  # noqa: E402

SIGMAS = (0.0, 0.02, 10 / 255, 0.05, 0.1)
TIMES = (2, 8, 20)
CHECKPOINTS = ("experiments/vgai_clean_seed0", "experiments/vgai_depthcam_wide", "experiments/vgai_camera_gray",
               "experiments/vgai_depthcam", "experiments/vgai_camera_narrow_gray")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--episodes", type=int, default=8)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--out", default=str(DATA_DIR / "experiments" / "estimator_under_noise.json"))
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    cfg = FlockConfig()
    command = " ".join(["python tools/experiments/estimator_under_noise.py"] + (argv or sys.argv[1:]))
    out = {"command": command, "features": list(FEATURE_NAMES), "times": list(TIMES), "checkpoints": {}}
    with Provenance(command) as prov:
        for name in CHECKPOINTS:
            path = DATA_DIR / f"{name}.pt"
            vgai = load_controller(path)
            cnn = vgai.model.cnn.eval()
            rows = {}
            for sigma in SIGMAS:
                cam = CameraRanges(noise=(sigma, sigma)) if sigma else None
                q = estimator_quality(cnn, vgai.vision, cfg, episodes=args.episodes, times=TIMES,
                                      seed=VALIDATION_SEED, camera=cam)
                rows[f"{sigma:.4g}"] = {str(t): [round(c, 3) for c in q[t]] for t in TIMES}
                print(name, f"sigma {sigma:.4g}", {t: [round(c, 2) for c in q[t][:2]] for t in TIMES}, flush=True)
            out["checkpoints"][name] = {"channels": list(vgai.vision.render.channels), "correlation": rows}
    out["provenance"] = prov.record(seed=VALIDATION_SEED, episodes=args.episodes,
                                    checkpoints={f"data/{name}.pt": sha256(DATA_DIR / f"{name}.pt") for name in CHECKPOINTS})
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    print("wrote", args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

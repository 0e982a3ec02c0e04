"""Experiment: what limits the gray-only VGAI? Does its CNN still read the neighbours' small velocity
disagreements late in a flight, where the book's depth-camera VGAI does?

    python tools/experiments/estimator_late_flight.py --out data/experiments/estimator_late_flight.json

The gray-only VGAIs trained through the camera (``runs.CAMERA_RUNS``, notebook 08) do not flock: their
velocity variance at 5 s stays near 1e-2 m²/s² where the depth camera's reaches 1e-3. Early in a flight
their CNNs read the six local features about as well as the depth camera's does
(``estimator_under_noise.json``: velocity correlations 0.79 against 0.81 at t = 8). The flock is won or
lost late, when the drones' velocities differ by a few cm/s. Here every CNN's state-estimation head
(eq. 9's six local features) is read on the SAME states: flights of the depth-camera VGAI
(``--pilot``, clean frames) from validation initial conditions (``book.VALIDATION_SEED``), at t = 20, 60,
120 and 190 steps, beside the median speed of the drones relative to their swarm's mean velocity. A CNN
whose velocity correlation falls late, while the depth camera's holds, cannot see what the flock's last
decade of variance needs.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from vgai_lite import FlockConfig, load_controller, rollout, sample_initial_state  # noqa: E402
from vgai_lite.book import DATA_DIR, VALIDATION_SEED  # noqa: E402
from vgai_lite.features import FEATURE_NAMES  # noqa: E402
from vgai_lite.lab.provenance import Provenance, sha256  # noqa: E402
from vgai_lite.state_estimation import estimator_quality  # noqa: E402

TIMES = (20, 60, 120, 190)
CHECKPOINTS = ("experiments/vgai_depthcam", "experiments/vgai_camera_narrow_gray", "experiments/vgai_camera_gray_rounds8",
               "experiments/vgai_camera_gray24", "experiments/vgai_camera_narrow_rgb",
               "experiments/vgai_camera_narrow_rgb_seed1", "experiments/vgai_camera_narrow_gray_cnn16",
               "experiments/vgai_camera_narrow_gray_cnn16_seed1")
"""The depth-camera VGAI (the book's recipe through the camera, seed 0) and the gray-only ones (the same
recipe and camera without the depth channel; 4 and 8 DAgger rounds; and 24 rows per camera instead of 12:
does a taller image, a finer apparent size, read distances better?), then the same recipe in colour (red, green,
blue instead of gray; training seeds 0 and 1): does colour, which tells fog from coverage, read them better? Last,
the gray-only recipe with a CNN twice as wide (16 and 32 channels; seeds 0 and 1): does capacity read them better?"""


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--pilot", default="experiments/vgai_depthcam", help="the VGAI whose flights are read (under data/)")
    p.add_argument("--episodes", type=int, default=8)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--out", default=str(DATA_DIR / "experiments" / "estimator_late_flight.json"))
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    cfg = FlockConfig()
    command = " ".join(["python tools/experiments/estimator_late_flight.py"] + (argv or sys.argv[1:]))
    pilot = load_controller(DATA_DIR / f"{args.pilot}.pt")
    out = {"command": command, "pilot": args.pilot, "features": list(FEATURE_NAMES), "times": list(TIMES),
           "checkpoints": {}}
    with Provenance(command) as prov:
        r0, v0 = sample_initial_state(cfg, args.episodes, torch.Generator().manual_seed(VALIDATION_SEED))
        v = rollout(pilot, cfg, r0, v0, steps=max(TIMES) + 1).v
        out["relative_speed_median_m_s"] = {str(t): round(float((v[t] - v[t].mean(1, keepdim=True)).norm(dim=-1).median()), 4)
                                            for t in TIMES}
        for name in CHECKPOINTS:
            vgai = load_controller(DATA_DIR / f"{name}.pt")
            q = estimator_quality(vgai.model.cnn.eval(), vgai.vision, cfg, episodes=args.episodes, times=TIMES,
                                  seed=VALIDATION_SEED, pilot=pilot)
            out["checkpoints"][name] = {"channels": list(vgai.vision.render.channels),
                                        "correlation": {str(t): [round(c, 3) for c in q[t]] for t in TIMES}}
            print(name, {t: [round(c, 2) for c in q[t][:2]] for t in TIMES}, flush=True)
    out["provenance"] = prov.record(seed=VALIDATION_SEED, episodes=args.episodes,
                                    checkpoints={f"data/{n}.pt": sha256(DATA_DIR / f"{n}.pt")
                                                 for n in (args.pilot, *CHECKPOINTS)})
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    print("wrote", args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Experiment: a camera-only modular pilot judged as a user would judge a controller.

    python tools/experiments/modular_pilot_eval.py --checkpoint data/experiments/vgai_camera_quiet_gray.pt --name vgai_camera_quiet_gray

A modular pilot (``estimator_in_the_loop.VisionDAGNN``) is a VGAI training's CNN reading the six local features
from each drone's own frames (its state-estimation head), fed to the shipped DAGNN's MLP, which was trained on
the exact features (data/dagnn/dagnn_K4.pt). Every drone still sees only its own camera frames and hears only
its neighbours. Notebook 08 found the gray-only VGAI's CNN, after its joint training, reading enough to flock
so while the VGAI itself does not (``stage1_noise_joint.json``): this flies that pilot on ``--episodes``
episodes of ``--seed`` (default: the validation episodes) with clean frames and through the sensor noise
sigmas of ``--noise``, and writes data/experiments/NAME_modular.json: per setting the relative cost with its
interval, the velocity variance at 2 and 5 s, the share connected at 5 s, whether it flocked and whether
it was as safe as the expert (``evaluate.flocked``, ``evaluate.as_safe_as_expert``), and the provenance.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from vgai_lite import FlockConfig, load_controller, relative_cost  # noqa: E402
from vgai_lite.book import DATA_DIR, VALIDATION_SEED  # noqa: E402
from vgai_lite.evaluate import as_safe_as_expert, flocked  # noqa: E402
from vgai_lite.lab.provenance import Provenance, sha256  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from estimator_in_the_loop import VisionDAGNN  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--checkpoint", required=True, help="a VGAI training's checkpoint, whose CNN reads the features")
    p.add_argument("--name", required=True, help="writes data/experiments/NAME_modular.json")
    p.add_argument("--noise", type=lambda x: [float(s) for s in x.split(",") if s], default=[10 / 255],
                   metavar="S1,S2", help="sensor noise sigmas flown besides clean frames (default: the authors' 10/255)")
    p.add_argument("--episodes", type=int, default=20)
    p.add_argument("--seed", type=int, default=VALIDATION_SEED)
    p.add_argument("--threads", type=int, default=2)
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    cfg = FlockConfig()
    command = " ".join(["python tools/experiments/modular_pilot_eval.py"] + (argv or sys.argv[1:]))
    vgai = load_controller(args.checkpoint)
    dagnn_path = DATA_DIR / "dagnn" / "dagnn_K4.pt"
    dagnn = load_controller(dagnn_path)
    out = {"command": command, "checkpoint": args.checkpoint, "dagnn": "dagnn/dagnn_K4", "settings": {}}
    for sigma in [0.0] + args.noise:
        label = "clean" if sigma == 0 else f"noise{sigma:.4g}"
        pilot = VisionDAGNN(dagnn, vgai.model.cnn.eval(), vgai.vision, noise=sigma, seed=args.seed)
        with Provenance(command) as prov:
            res = relative_cost(pilot, cfg, episodes=args.episodes, seed=args.seed, name=f"modular pilot, {label}")
        s = res.summary()
        out["settings"][label] = {**s, "noise": sigma, "flocked": flocked(s), "safe": as_safe_as_expert(s),
                                  "provenance": prov.record(checkpoint=args.checkpoint, seed=args.seed, episodes=args.episodes,
                                                            dagnn_sha256=sha256(dagnn_path))}
        print(res, "| flocked" if flocked(s) else "| did not flock", "| safe" if as_safe_as_expert(s) else "| unsafe",
              flush=True)
    path = DATA_DIR / "experiments" / f"{args.name}_modular.json"
    path.write_text(json.dumps(out, indent=1) + "\n")
    print("wrote", path)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Experiment: a VGAI flown through the cameras of notebook 08's curves, judged as a user would.

    python tools/experiments/camera_eval.py --checkpoint data/experiments/vgai_depthcam.pt --name vgai_depthcam

Flies the checkpoint on ``--episodes`` episodes of ``--seed`` (default the validation episodes: the
recipes are choices) with clean frames, with sensor noise sigma in NOISE and with lens blur in BLUR
(degrees of view, ``camera.blur_degrees``), with one dead camera per drone, and, for a depth
camera, with the depth channel's relative range error in DEPTH (``camera.range_noise``); writes
``data/experiments/NAME_cameras.json``: per setting the relative cost with its interval, the velocity
variance at 2 and 5 s, the share connected at 5 s, whether it flocked and whether it was as safe as
the expert (``evaluate.flocked``, ``evaluate.as_safe_as_expert``), and the provenance.
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
from vgai_lite.lab.perturbations import DeadCamera, DepthNoise, ImageNoise, LensBlur, perturbed  # noqa: E402
from vgai_lite.lab.provenance import Provenance  # noqa: E402

NOISE = (0.01, 0.02, 10 / 255, 0.05, 0.1)
"""Sensor noise sigmas of the curves (10/255: the authors' test)."""
BLUR = (0.5, 1.4, 2.8)
"""Lens blur, degrees of view (0.5°: the authors' 5 x 5 box at 144 x 256)."""
DEPTH = (0.02, 0.05)
"""A depth channel's relative range error (about 2 %: a commodity depth camera at 2 m)."""


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--checkpoint", required=True)
    p.add_argument("--name", required=True, help="writes data/experiments/NAME_cameras.json")
    p.add_argument("--episodes", type=int, default=20)
    p.add_argument("--seed", type=int, default=VALIDATION_SEED)
    p.add_argument("--only", nargs="*", default=None, help="settings to fly, e.g. clean noise0.0392 blur0.5 dead")
    p.add_argument("--threads", type=int, default=2)
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    cfg = FlockConfig()
    base = load_controller(args.checkpoint)
    settings = {"clean": ()}
    settings.update({f"noise{s:.4g}": (ImageNoise(s),) for s in NOISE})
    settings.update({f"blur{b:g}": (LensBlur(b, base.vision.render),) for b in BLUR})
    settings["dead"] = (DeadCamera(),)
    if "depth" in base.vision.render.channels:
        settings.update({f"depth{d:g}": (DepthNoise(d),) for d in DEPTH})
    if args.only:
        settings = {k: v for k, v in settings.items() if k in args.only}
    command = " ".join(["python tools/experiments/camera_eval.py"] + (argv or sys.argv[1:]))
    out_path = DATA_DIR / "experiments" / f"{args.name}_cameras.json"
    out = json.loads(out_path.read_text()) if out_path.is_file() else {"checkpoint": args.checkpoint, "settings": {}}
    for label, ps in settings.items():
        c = perturbed(base, *ps, seed=args.seed) if ps else base
        with Provenance(command) as prov:
            res = relative_cost(c, cfg, episodes=args.episodes, seed=args.seed, name=label)
        s = res.summary()
        out["settings"][label] = {**s, "flocked": flocked(s), "safe": as_safe_as_expert(s),
                                  "provenance": prov.record(checkpoint=args.checkpoint, seed=args.seed,
                                                            episodes=args.episodes)}
        print(res, "| flocked" if flocked(s) else "| did not flock", "| safe" if as_safe_as_expert(s) else "| unsafe",
              flush=True)
        out_path.write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

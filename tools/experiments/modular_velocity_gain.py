"""Experiment: is the gray camera's velocity reading too weak, or only too small? A gain on it, in the loop.

    python tools/experiments/modular_velocity_gain.py --threads 2 --gains 1,1.5,2,2.4,3 --swaps

``stage1_capacity.py`` flies each camera recipe's stage-1 CNN as a modular pilot (its six estimated local
features fed to the shipped DAGNN's MLP, ``estimator_in_the_loop.VisionDAGNN``): the depth camera's flocks,
no gray one does. Late in a flight an estimate whose cue is weak shrinks toward zero (stage 1's loss is L1): the
gray CNN's estimated velocity sums are a fraction of the true ones (the slope below). Here the gray recipe's stage-1 CNN (seed 0, the
book's width; read from the book's stage-1 cache, or trained as ``train_vgai`` trains it) flies again with its
two velocity estimates (eq. 4's sums of relative velocities) multiplied by a gain k, the other four as read,
on clean frames of the working episodes; each with the velocity variance, damping gain and forcing at rest of
``consensus_limit.py`` at 2 and 5 s. A diagnostic, not a recipe: k = 1 is the modular pilot of
``stage1_capacity.json``; a k that makes it brake says the reading points the right way but is too small.
Also the slope of the estimated velocity sums on the true ones, at step 190 of flights of the depth camera's
VGAI from validation initial conditions (the states of ``estimator_late_flight.py``), for the gray and the
depth camera's stage 1.

``--swaps``: which reading does the gray camera lack? Two modular pilots that take the two velocity estimates from
one stage 1 and the four distance features from the other (each CNN reading its own frames of the same flight):
the gray camera's distances with the depth camera's velocities, and the reverse.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from vgai_lite import FlockConfig, VGAITrainConfig, load_controller, local_features, rollout, sample_initial_state  # noqa: E402
from vgai_lite.book import DATA_DIR, VALIDATION_SEED, WORKING_SEED  # noqa: E402
from vgai_lite.lab.provenance import Provenance, sha256  # noqa: E402
from vgai_lite.lab.runs import STAGE1_CACHE  # noqa: E402
from vgai_lite.lab.stage1_cache import stage1_file  # noqa: E402
from vgai_lite.vision import stored_images  # noqa: E402

from consensus_limit import damping_and_forcing  # noqa: E402
from estimator_in_the_loop import VisionDAGNN  # noqa: E402
from stage1_capacity import stage_one  # noqa: E402

RECORDS = {"gray": "vgai_camera_narrow_gray", "gray + depth": "vgai_depthcam"}
"""sensor -> the training record whose stage 1 is read (its ``train_config``)."""
SLOPE_STEP = 190


class VelocityGain(VisionDAGNN):
    """The modular pilot with its two estimated velocity features multiplied by ``gain``."""

    def __init__(self, base, cnn, vision, gain: float):
        super().__init__(base, cnn, vision)
        self.gain = gain

    def features(self, r, v):
        X = super().features(r, v).clone()
        X[..., :2] *= self.gain
        return X


class SwappedVelocity(VisionDAGNN):
    """The modular pilot with its four distance features from ``cnn`` and its two velocity estimates from
    ``other_cnn``, each reading its own frames (``vision``, ``other_vision``) of the same flight."""

    def __init__(self, base, cnn, vision, other_cnn, other_vision):
        self.other = VisionDAGNN(base, other_cnn, other_vision)
        super().__init__(base, cnn, vision)

    def reset(self):
        super().reset()
        self.other.reset()

    def features(self, r, v):
        X = super().features(r, v).clone()
        X[..., :2] = self.other.features(r, v)[..., :2]
        return X


@torch.no_grad()
def velocity_slope(cnn, vision, cfg: FlockConfig, pilot, episodes: int, step: int) -> list:
    """Least-squares slope of the estimated velocity sums on the exact ones (x, y), through the origin, at
    ``step`` of ``pilot``'s flights from the validation initial conditions."""
    r0, v0 = sample_initial_state(cfg, episodes, torch.Generator().manual_seed(VALIDATION_SEED))
    traj = rollout(pilot, cfg, r0, v0, steps=step + 1)
    e, t = torch.arange(episodes), torch.full((episodes,), step)
    est = cnn.estimate_local_features(stored_images(vision, cfg, traj.r, traj.v, e, t).flatten(0, 1))
    X = local_features(traj.r[step], traj.v[step], cfg.R).flatten(0, 1)
    return [round(float((est[:, k] * X[:, k]).sum() / X[:, k].square().sum()), 3) for k in range(2)]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--gains", type=lambda x: [float(k) for k in x.split(",")], default=[1.0, 1.5, 2.0, 3.0])
    p.add_argument("--flights", type=int, default=10, help="working episodes each pilot flies")
    p.add_argument("--episodes", type=int, default=8, help="validation flights the slope is read on")
    p.add_argument("--pilot", default="experiments/vgai_depthcam", help="the VGAI whose flights the slope is read on")
    p.add_argument("--swaps", action="store_true",
                   help="also the pilots that swap the velocity estimates between the gray and the depth stage 1")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--out", default=str(DATA_DIR / "experiments" / "modular_velocity_gain.json"))
    args = p.parse_args(argv)
    if any(not k > 0 for k in args.gains):
        raise SystemExit(f"--gains must be positive numbers, got {args.gains}")
    torch.set_num_threads(args.threads)
    cfg = FlockConfig()
    command = " ".join(["python tools/experiments/modular_velocity_gain.py"] + (argv or sys.argv[1:]))
    dagnn_path, pilot_path = DATA_DIR / "dagnn" / "dagnn_K4.pt", DATA_DIR / f"{args.pilot}.pt"
    dagnn, pilot = load_controller(dagnn_path), load_controller(pilot_path)
    out = {"command": command, "dagnn": "dagnn/dagnn_K4", "flights_seed": WORKING_SEED, "slope_step": SLOPE_STEP,
           "slope_pilot": args.pilot, "stage1": {}, "gains": {}, "swaps": {}}
    with Provenance(command) as prov:
        cnns = {}
        for sensor, record in RECORDS.items():
            tcfg = VGAITrainConfig.from_dict(json.loads((DATA_DIR / "experiments" / f"{record}.json").read_text())["train_config"])
            cnn, _ = stage_one(cfg, tcfg)
            cnns[sensor] = (cnn, tcfg.vision)
            out["stage1"][sensor] = {"record": record, "stage1_file": stage1_file(STAGE1_CACHE, cfg, tcfg).name,
                                     "stage1_sha256": sha256(stage1_file(STAGE1_CACHE, cfg, tcfg)),
                                     "velocity_slope": velocity_slope(cnn, tcfg.vision, cfg, pilot, args.episodes, SLOPE_STEP)}
            print(sensor, "slope of the estimated velocity sums on the exact ones:", out["stage1"][sensor]["velocity_slope"],
                  flush=True)
        cnn, vision = cnns["gray"]
        for k in args.gains:
            res = damping_and_forcing(VelocityGain(dagnn, cnn, vision, k), cfg, args.flights)
            out["gains"][f"{k:g}"] = res
            print(f"gain {k:g}:", {t: f"variance {x['velocity_variance_median']:.2e}, gamma {x['damping_gain_median']:.2f}, "
                                      f"f {x['forcing_at_rest_rms_median']:.3f}" for t, x in res.items()}, flush=True)
        for dist, vel in ((("gray", "gray + depth"), ("gray + depth", "gray")) if args.swaps else ()):
            res = damping_and_forcing(SwappedVelocity(dagnn, *cnns[dist], *cnns[vel]), cfg, args.flights)
            out["swaps"][f"distances: {dist}; velocities: {vel}"] = res
            print(f"distances {dist}, velocities {vel}:", {t: f"variance {x['velocity_variance_median']:.2e}, gamma "
                  f"{x['damping_gain_median']:.2f}, f {x['forcing_at_rest_rms_median']:.3f}" for t, x in res.items()}, flush=True)
    out["provenance"] = prov.record(seed=WORKING_SEED, episodes=args.flights,
                                    checkpoints={"data/dagnn/dagnn_K4.pt": sha256(dagnn_path),
                                                 f"data/{args.pilot}.pt": sha256(pilot_path)})
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    print("wrote", args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

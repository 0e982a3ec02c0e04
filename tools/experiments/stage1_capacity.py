"""Experiment: stage 1 alone. Does a wider CNN, or colour, read the distances better before any joint training?

    python tools/experiments/stage1_capacity.py --threads 2 --motion-gaps 20,50 --view-widths 64
    python tools/experiments/stage1_capacity.py --threads 2 --stack-scales 5,0.5 --only-changes --out data/experiments/stage1_stack.json
    python tools/experiments/stage1_capacity.py --threads 2 --warm-steps 6000 --only-changes --out data/experiments/stage1_longer.json
    python tools/experiments/stage1_capacity.py --threads 2 --noise-max 0,0.02,0.05 --pilot-noise 0.01,0.0392 --only-changes --out data/experiments/stage1_noise.json
    python tools/experiments/stage1_capacity.py --threads 2 --noise-max 0.005 --trained vgai_camera_quiet_gray --only-changes --out data/experiments/stage1_noise_joint.json
    python tools/experiments/stage1_capacity.py --threads 2 --noise-max 0,0.01 --noise-gap 20 --pilot-noise 0.01,0.0392 --only-changes --out data/experiments/stage1_noise_gap20.json

The camera-only VGAIs of notebook 08 do not flock; what limits them, measured, is a forcing at rest several
times the depth camera's (``consensus_limit*.json``), with the r/r⁴ sums (eq. 9's collision-avoidance
features) read less well late in a flight (``estimator_late_flight.json``). Those heads were read after the
joint training (stage 3) had moved the CNN. Here each recipe's CNN is read at the END OF STAGE 1 (visual
state estimation alone, ``vgai_training.fit_state_estimator``), the stage whose only task is reading the
six local features: is a CNN of 8 and 16 channels too small to read distances from gray frames, or is the
gray image itself short of them?

Each recipe is a training record's own configuration (its ``train_config``, so the stage 1 is the very one
that training trained first). Its stage 1 is read from the book's cache of first
stages (``runs.STAGE1_CACHE``, ``lab.stage1_cache``) where a training left it, else trained here exactly as
``train_vgai`` trains it (the expert's flights of round 0, then stage 1; written to the cache), and the run
stops there. Every CNN is then read on the same states as ``estimator_late_flight.py``: flights of the
depth-camera VGAI (clean frames) from validation initial conditions, at t = 20, 60, 120 and 190 steps.

And each is flown as a modular pilot: its six estimated local features fed to the shipped DAGNN's MLP (trained on
the exact ones; ``estimator_in_the_loop.VisionDAGNN``), on clean frames of the working episodes, with the
damping gain and forcing at rest of ``consensus_limit.py``. A stage-1 CNN whose modular pilot flocks reads
enough from its frames for a controller that acts on the local features as the DAGNN does; where the joint
training's VGAI of the same frames does not flock, what fails is the end-to-end training, not the sensor.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from vgai_lite import FlockConfig, VGAITrainConfig, load_controller, train_vgai  # noqa: E402
from vgai_lite.book import DATA_DIR, VALIDATION_SEED, WORKING_SEED  # noqa: E402
from vgai_lite.features import FEATURE_NAMES  # noqa: E402
from vgai_lite.lab.provenance import Provenance, sha256  # noqa: E402
from vgai_lite.lab.runs import STAGE1_CACHE  # noqa: E402
from vgai_lite.lab.stage1_cache import cached, stage1_file  # noqa: E402
from vgai_lite.state_estimation import estimator_quality  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from consensus_limit import damping_and_forcing  # noqa: E402
from estimator_in_the_loop import VisionDAGNN  # noqa: E402

TIMES = (20, 60, 120, 190)
RECIPES = {
    "gray + depth, 8 and 16 channels (vgai_depthcam)": "vgai_depthcam",
    "gray, 8 and 16 channels (vgai_camera_narrow_gray)": "vgai_camera_narrow_gray",
    "gray, 16 and 32 channels (vgai_camera_narrow_gray_cnn16)": "vgai_camera_narrow_gray_cnn16",
    "gray, 16 and 32 channels, seed 1 (vgai_camera_narrow_gray_cnn16_seed1)": "vgai_camera_narrow_gray_cnn16_seed1",
    "red, green, blue, 8 and 16 channels (vgai_camera_narrow_rgb)": "vgai_camera_narrow_rgb",
}
"""label -> the training record whose configuration (``train_config``) it is."""
GAP_RECORD = "vgai_camera_narrow_gray"
"""The recipe ``--motion-gaps`` and ``--view-widths`` vary: the gray-only camera of seed 0, its motion frame g steps old
instead of 5, or W columns per camera instead of 32 (a neighbour's apparent width, the cue to its motion along the
line of sight, resolved more finely)."""


class _StageOneDone(Exception):
    """Raised by the stage-1 function below to end a training once its stage 1 is done."""

    def __init__(self, cnn, record):
        super().__init__("stage 1 done")
        self.cnn, self.record = cnn, record


def stage_one(cfg: FlockConfig, tcfg: VGAITrainConfig):
    """(the CNN at the end of stage 1 of ``train_vgai(cfg, tcfg)``, its stage-1 record): read from the cache, or
    trained as that training trains it (and cached)."""
    read = cached(STAGE1_CACHE)

    def stop_after(cnn, cfg_, tcfg_, flights, gen, progress=True):
        raise _StageOneDone(cnn, read(cnn, cfg_, tcfg_, flights, gen, progress))

    try:
        train_vgai(cfg, tcfg, progress=False, stage1=stop_after)
    except _StageOneDone as done:
        return done.cnn.eval(), done.record
    raise RuntimeError("train_vgai returned without running stage 1 (warm_starts off?)")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--pilot", default="experiments/vgai_depthcam", help="the VGAI whose flights are read (under data/)")
    p.add_argument("--episodes", type=int, default=8)
    p.add_argument("--motion-gaps", type=lambda x: [int(g) for g in x.split(",") if g], default=[], metavar="G1,G2",
                   help="also the gray recipe of seed 0 with its motion frame G steps old (stage 1 trained here, about 8 min each)")
    p.add_argument("--view-widths", type=lambda x: [int(w) for w in x.split(",") if w], default=[], metavar="W1,W2",
                   help="also the gray recipe of seed 0 with W columns per camera instead of its 32 (finer apparent sizes)")
    p.add_argument("--stack-scales", type=lambda x: [float(s) for s in x.split(",") if s], default=[], metavar="S1,S2",
                   help="also the gray recipe of seed 0 reading each frame alone (motion_mode 'stack': its odd features "
                        "are S times the change of the trunk's reading between the frames, OddMotionCNN's pairing)")
    p.add_argument("--warm-steps", type=lambda x: [int(n) for n in x.split(",") if n], default=[], metavar="N1,N2",
                   help="also the gray recipe of seed 0 with N stage-1 steps instead of its own (is its reading still improving?)")
    p.add_argument("--noise-max", type=lambda x: [float(n) for n in x.split(",") if n], default=[], metavar="S1,S2",
                   help="also the gray recipe of seed 0 with its cameras' sensor noise drawn from [0, S] instead of its own "
                        "range (the other camera settings unchanged): does training through the noise shrink its reading?")
    p.add_argument("--only-changes", action="store_true",
                   help="only the changed recipes (--motion-gaps, --view-widths, --stack-scales, --warm-steps, --noise-max), "
                        "not the training records'")
    p.add_argument("--noise-gap", type=int, default=None, metavar="G",
                   help="the --noise-max recipes with their motion frame G steps old instead of the recipe's own")
    p.add_argument("--trained", default=[], type=lambda x: [n for n in x.split(",") if n], metavar="NAME1,NAME2",
                   help="also the CNN of finished VGAI trainings (data/experiments/NAME.pt) after their joint training, read "
                        "and flown the same way: does the joint training keep what its stage 1 read?")
    p.add_argument("--pilot-noise", type=lambda x: [float(n) for n in x.split(",") if n], default=[], metavar="S1,S2",
                   help="also fly each modular pilot with sensor noise of sigma S on its frames (e.g. 0.0392, the paper's 10/255)")
    p.add_argument("--flights", type=int, default=10, help="working episodes each modular pilot flies")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--out", default=str(DATA_DIR / "experiments" / "stage1_capacity.json"))
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    cfg = FlockConfig()
    command = " ".join(["python tools/experiments/stage1_capacity.py"] + (argv or sys.argv[1:]))
    pilot = load_controller(DATA_DIR / f"{args.pilot}.pt")
    dagnn_path = DATA_DIR / "dagnn" / "dagnn_K4.pt"
    dagnn = load_controller(dagnn_path)
    out = {"command": command, "pilot": args.pilot, "dagnn": "dagnn/dagnn_K4", "flights_seed": WORKING_SEED, "features": list(FEATURE_NAMES), "times": list(TIMES), "recipes": {}}
    with Provenance(command) as prov:
        recipes = [(label, record, {}) for label, record in RECIPES.items() if not args.only_changes] + [
            (f"gray, 8 and 16 channels, motion frame {g} steps old ({GAP_RECORD}, g = {g})", GAP_RECORD, {"motion_gap": g})
            for g in args.motion_gaps] + [
            (f"gray, 8 and 16 channels, {w} columns per camera ({GAP_RECORD}, {w} columns)", GAP_RECORD, {"view_width": w})
            for w in args.view_widths] + [
            (f"gray, 8 and 16 channels, each frame read alone, s = {x:g} ({GAP_RECORD}, stack)", GAP_RECORD,
             {"motion_mode": "stack", "motion_scale": x}) for x in args.stack_scales] + [
            (f"gray, 8 and 16 channels, {n} stage-1 steps ({GAP_RECORD}, {n} steps)", GAP_RECORD, {"warm_steps": n})
            for n in args.warm_steps] + [
            (f"gray, 8 and 16 channels, sensor noise in [0, {x:g}]"
             + (f", motion frame {args.noise_gap} steps old" if args.noise_gap is not None else "") + f" ({GAP_RECORD}, noise)",
             GAP_RECORD, {"noise_max": x, **({"motion_gap": args.noise_gap} if args.noise_gap is not None else {})})
            for x in args.noise_max]
        def read(cnn, vision) -> dict:
            """The CNN's correlation with the six features on the pilot's flights, at each of TIMES."""
            q = estimator_quality(cnn, vision, cfg, episodes=args.episodes, times=TIMES, seed=VALIDATION_SEED, pilot=pilot)
            return {str(t): [round(c, 3) for c in q[t]] for t in TIMES}

        def fly(cnn, vision) -> dict:
            """The CNN's modular pilot flown on clean frames and through each --pilot-noise sigma."""
            return {"modular_pilot": damping_and_forcing(VisionDAGNN(dagnn, cnn, vision), cfg, args.flights),
                    "modular_pilot_noise": {f"{x:g}": damping_and_forcing(VisionDAGNN(dagnn, cnn, vision, noise=x), cfg, args.flights)
                                            for x in args.pilot_noise}}

        def report(label: str, row: dict) -> None:
            m = row["modular_pilot"]["5s"]
            print(label, {int(t): [round(x, 2) for x in c[2:4]] for t, c in row["correlation"].items()}, f"modular pilot at 5 s: variance "
                  f"{m['velocity_variance_median']:.2e}, gamma {m['damping_gain_median']:.2f}, f {m['forcing_at_rest_rms_median']:.3f}",
                  flush=True)
            for x, res in row["modular_pilot_noise"].items():
                print(f"  ... through sensor noise of sigma {x}: variance {res['5s']['velocity_variance_median']:.2e}, "
                      f"gamma {res['5s']['damping_gain_median']:.2f}, f {res['5s']['forcing_at_rest_rms_median']:.3f}", flush=True)

        for name in args.trained:  # a finished training's CNN, after stages 2 and 3
            path = DATA_DIR / "experiments" / f"{name}.pt"
            trained = load_controller(path)
            vision = trained.vision
            label = f"{name}, after its joint training"
            out["recipes"][label] = {"record": name, "checkpoint_sha256": sha256(path), "motion_gap": vision.motion_gap,
                                     "view_width": vision.render.view_width, "channels": list(vision.render.channels),
                                     "correlation": read(trained.model.cnn.eval(), vision), **fly(trained.model.cnn, vision)}
            report(label, out["recipes"][label])
        for label, record, change in recipes:
            tcfg = VGAITrainConfig.from_dict(json.loads((DATA_DIR / "experiments" / f"{record}.json").read_text())["train_config"])
            if "motion_gap" in change:
                tcfg = dataclasses.replace(tcfg, vision=dataclasses.replace(tcfg.vision, motion_gap=change["motion_gap"]))
            if "motion_mode" in change:
                tcfg = dataclasses.replace(tcfg, vision=dataclasses.replace(tcfg.vision, motion_mode=change["motion_mode"],
                                                                            motion_scale=change["motion_scale"]))
            if "warm_steps" in change:
                tcfg = dataclasses.replace(tcfg, warm_steps=change["warm_steps"])
            if "noise_max" in change:
                tcfg = dataclasses.replace(tcfg, camera=dataclasses.replace(tcfg.camera, noise=(0.0, change["noise_max"])))
            if "view_width" in change:
                render = dataclasses.replace(tcfg.vision.render, view_width=change["view_width"])
                tcfg = dataclasses.replace(tcfg, vision=dataclasses.replace(tcfg.vision, render=render))
            was_cached = stage1_file(STAGE1_CACHE, cfg, tcfg).is_file()
            start = time.perf_counter()
            cnn, rec = stage_one(cfg, tcfg)
            correlation = read(cnn, tcfg.vision)
            out["recipes"][label] = {
                "record": record, "motion_gap": tcfg.vision.motion_gap, "motion_mode": tcfg.vision.motion_mode, "motion_scale": tcfg.vision.motion_scale, "view_width": tcfg.vision.render.view_width, "cnn_widths": list(tcfg.cnn_widths), "channels": list(tcfg.vision.render.channels),
                "seed": tcfg.seed, "warm_steps": tcfg.warm_steps, "camera_noise": list(tcfg.camera.noise) if tcfg.camera else None, "stage1_file": stage1_file(STAGE1_CACHE, cfg, tcfg).name,
                "stage1_sha256": sha256(stage1_file(STAGE1_CACHE, cfg, tcfg)),
                "read_from_cache": was_cached, "stage1_seconds": round(rec["stage1_seconds"], 1),
                "parameters": sum(x.numel() for x in cnn.parameters()),
                "final_loss": round(sum(rec["warm_loss"][-100:]) / len(rec["warm_loss"][-100:]), 4),
                "loss_every_1000_steps": [round(sum(rec["warm_loss"][k - 100:k]) / 100, 4)  # mean of the 100 steps before step k
                                          for k in range(1000, len(rec["warm_loss"]) + 1, 1000)],
                "seconds_here": round(time.perf_counter() - start, 1),
                "correlation": correlation, **fly(cnn, tcfg.vision)}
            report(label, out["recipes"][label])
    out["provenance"] = prov.record(seed=VALIDATION_SEED, episodes=args.episodes,
                                    checkpoints={f"data/{args.pilot}.pt": sha256(DATA_DIR / f"{args.pilot}.pt"),
                                                 "data/dagnn/dagnn_K4.pt": sha256(dagnn_path)})
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    print("wrote", args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

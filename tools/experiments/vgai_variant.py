"""Experiment: one VGAI training recipe, trained and judged as a user would.

    python tools/experiments/vgai_variant.py --name odd8_synth0.5 --motion-features 8 --synthetic-share 0.5

Trains the book's default VGAI (``runs.VGAI_RUNS["vgai_F24"]``) with the given changes, then writes
``data/experiments/NAME.json``: the relative cost on ``--episodes`` validation episodes (seed
book.VALIDATION_SEED: variants are choices, so they are compared on validation episodes, never on
the test episodes) with the safety figures and the flocking figures (velocity variance at 2 and
5 s, connectivity at 5 s), and the record's provenance (``vgai_lite.lab.provenance``). The checkpoint goes to ``data/experiments/NAME.pt`` (not a shipped
model), so a record and its controller can be checked against each other.

    python tools/experiments/vgai_variant.py --name vgai_F24_plain --evaluate data/experiments/vgai_F24_plain.pt

writes the same record for a checkpoint trained before (its training time read from the checkpoint); given with
the flags it was trained with, the record keeps them as its changes, and flags that give another recipe are refused.
``--note`` is stored in the record (e.g. that two trainings shared the two cores, so their
training time is not the time of one alone).

The hypotheses of notebook 11 that did not make VGAI flock (longer stored flights, stage 3's own
early share, the MLP fitted on exact features through the aux head, an anchor loss) are no longer
knobs of the method; their records (``data/experiments/vgai_late500.json``, ``vgai_exact_mlp.json``,
``vgai_learner_late.json``) carry a ``rerun`` command that checks out the commit that trained them.
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

from vgai_lite import PAPER, CameraRanges, FlockConfig, VGAITrainConfig, load_controller, relative_cost, train_vgai  # noqa: E402
from vgai_lite.book import DATA_DIR, VALIDATION_SEED  # noqa: E402
from vgai_lite.vgai_config import PAPER_VISION, book_recipe  # noqa: E402
from vgai_lite.vision import VisionConfig  # noqa: E402
from vgai_lite.lab.provenance import Provenance  # noqa: E402
from vgai_lite.lab.runs import STAGE1_CACHE, VGAI_RUNS  # noqa: E402
from vgai_lite.lab.stage1_cache import cached  # noqa: E402

BASES = {**VGAI_RUNS, "vgai_F24": book_recipe(seed=0), "paper": PAPER}
"""The recipes a variant starts from, all at training seed 0 unless --seed says otherwise (the shipped vgai_F24
is the seed the book's rule chose, ``runs.VGAI_F24_SEED``; a variant is compared with seed 0's training)."""


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--name", required=True, help="names data/experiments/NAME.pt and NAME.json")
    p.add_argument("--base", default="vgai_F24", choices=sorted(BASES),
                   help="the recipe the changes apply to: a shipped run's, or 'paper' (PAPER, the paper's VGAI)")
    p.add_argument("--motion-features", type=int, default=None)
    p.add_argument("--synthetic-share", type=float, default=None)
    p.add_argument("--aux-weight", type=float, default=None)
    p.add_argument("--early-share", type=float, default=None)
    p.add_argument("--dagger-rounds", type=int, default=None)
    p.add_argument("--seed", type=int, default=None)
    p.add_argument("--learner-swarms", type=float, default=None, help="share of DAgger swarms the learner flies alone")
    p.add_argument("--camera", default=None, metavar="NOISE:BLUR:GAIN:OFFSET:DEAD[:DEPTH]",
                   help="the training's cameras (VGAITrainConfig.camera, drawn per flight and window): ranges "
                        "lo,hi of sensor noise sigma, lens blur (degrees), gain and offset, then the share of "
                        "drones with a dead camera, then optionally the range of the depth channel's relative range "
                        "error, e.g. 0,0.08:0,1.5:0.8,1.2:-0.05,0.05:0.1:0,0.05")
    p.add_argument("--view-height", type=int, default=None,
                   help="rows per camera (the renderer's view_height; default 12): apparent size, the monocular "
                        "distance cue, in finer steps")
    p.add_argument("--channels", default=None,
                   help="the rendered channels, comma-separated (e.g. gray: no depth; the motion channel follows)")
    p.add_argument("--sensor", choices=("paper", "book"), default=None,
                   help="the vision: the paper's (PAPER_VISION: one gray frame) or the book's (gray, depth, motion)")
    p.add_argument("--motion-mode", choices=("difference", "stack"), default=None,
                   help="how the CNN sees the earlier frame (VisionConfig.motion_mode); 'stack' with odd motion "
                        "features: the trunk reads each frame alone, motion is the change of its reading")
    p.add_argument("--motion-gap", type=int, default=None,
                   help="the motion channel's gap g in steps; 0: one frame, no motion channel (with --motion-features 0)")
    p.add_argument("--warm-starts", choices=("on", "off"), default=None,
                   help="stages 1-2 before the joint training (on: the book's) or joint BPTT from random weights (off)")
    p.add_argument("--teams", default=None, metavar="N1,N2,...",
                   help="team sizes the training's swarms fly with, drawn per group (VGAITrainConfig.teams)")
    p.add_argument("--radii", default=None, metavar="LOW,HIGH",
                   help="the range of communication radii R (m) drawn per group (VGAITrainConfig.radii)")
    p.add_argument("--cnn-widths", default=None, metavar="C1,C2",
                   help="channels of the CNN's two stages (VGAITrainConfig.cnn_widths; the book's: 8,16)")
    p.add_argument("--cnn-hidden", type=int, default=None,
                   help="width of the CNN's hidden FC layer (VGAITrainConfig.cnn_hidden; the book's: 64)")
    p.add_argument("--feature-means", action="store_true",
                   help="the CNN learns the local features as means over neighbours (VGAITrainConfig.feature_means)")
    p.add_argument("--readout", choices=("features", "local"), default=None,
                   help="what the MLP reads of each image: the CNN's F features, or its estimate of the 6 local features")
    p.add_argument("--mlp-start", default=None, metavar="fit|DAGNN",
                   help="stage 2: fit the MLP (default), or start it as this DAGNN's (a file or a shipped name; --readout local)")
    p.add_argument("--joint-mlp", choices=("on", "off"), default=None,
                   help="off: stage 3 trains the CNN only, through the MLP stage 2 left")
    p.add_argument("--episodes", type=int, default=20, help="validation episodes of the evaluation")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--evaluate", default=None, metavar="CKPT", help="no training: evaluate this checkpoint")
    p.add_argument("--note", default="")
    p.add_argument("--stage1-cache", default=str(STAGE1_CACHE),
                   help="folder of cached first stages (default: the book's); a variant that leaves stage 1 "
                        "unchanged (e.g. --aux-weight, --dagger-rounds) reuses it")
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    changes = {k: v for k, v in (("motion_features", args.motion_features), ("synthetic_share", args.synthetic_share),
                                 ("aux_weight", args.aux_weight), ("early_share", args.early_share),
                                 ("dagger_rounds", args.dagger_rounds), ("seed", args.seed),
                                 ("learner_swarms", args.learner_swarms), ("cnn_hidden", args.cnn_hidden),
                                 ("readout", args.readout), ("mlp_start", args.mlp_start))
               if v is not None}
    if args.cnn_widths is not None:
        changes["cnn_widths"] = tuple(int(c) for c in args.cnn_widths.split(","))
    if args.warm_starts is not None:
        changes["warm_starts"] = args.warm_starts == "on"
    if args.joint_mlp is not None:
        changes["joint_mlp"] = args.joint_mlp == "on"
    if args.feature_means:
        changes["feature_means"] = True
    if args.teams is not None:
        changes["teams"] = tuple(int(n) for n in args.teams.split(","))
    if args.radii is not None:
        changes["radii"] = tuple(float(x) for x in args.radii.split(","))
    cfg, tcfg = FlockConfig(), dataclasses.replace(BASES[args.base], **changes)
    if args.sensor is not None:  # recorded by name, like --channels
        tcfg = dataclasses.replace(tcfg, vision=PAPER_VISION if args.sensor == "paper" else VisionConfig())
        changes["sensor"] = args.sensor
    if args.camera is not None:
        parts = args.camera.split(":")
        if len(parts) not in (5, 6):
            raise SystemExit(f"--camera takes NOISE:BLUR:GAIN:OFFSET:DEAD[:DEPTH], got {args.camera!r}")
        ranges = [tuple(float(x) for x in part.split(",")) for part in parts[:4] + parts[5:]]
        tcfg = dataclasses.replace(tcfg, camera=CameraRanges(*ranges[:4], dead_share=float(parts[4]),
                                                             **({"depth_noise": ranges[4]} if len(parts) == 6 else {})))
        changes["camera"] = tcfg.camera.to_dict()
    if args.motion_gap is not None:  # a change inside the vision configuration: recorded by name
        tcfg = dataclasses.replace(tcfg, vision=dataclasses.replace(tcfg.vision, motion_gap=args.motion_gap))
        changes["motion_gap"] = args.motion_gap
    if args.motion_mode is not None:  # a change inside the vision configuration: recorded by name
        tcfg = dataclasses.replace(tcfg, vision=dataclasses.replace(tcfg.vision, motion_mode=args.motion_mode))
        changes["motion_mode"] = args.motion_mode
    if args.channels is not None:  # a change inside the vision configuration: recorded by name
        channels = tuple(args.channels.split(","))
        render = dataclasses.replace(tcfg.vision.render, channels=channels)
        tcfg = dataclasses.replace(tcfg, vision=dataclasses.replace(tcfg.vision, render=render))
        changes["channels"] = list(channels)
    if args.view_height is not None:  # a change inside the vision configuration: recorded by name
        render = dataclasses.replace(tcfg.vision.render, view_height=args.view_height)
        tcfg = dataclasses.replace(tcfg, vision=dataclasses.replace(tcfg.vision, render=render))
        changes["view_height"] = args.view_height
    folder = DATA_DIR / "experiments"
    command = " ".join(["python tools/experiments/vgai_variant.py"] + (argv or sys.argv[1:]))
    ckpt = Path(args.evaluate) if args.evaluate else folder / f"{args.name}.pt"
    with Provenance(command) as train_prov:
        if args.evaluate:
            controller = load_controller(ckpt)
            hist, stored = controller.meta["history"], VGAITrainConfig.from_dict(controller.meta["train_config"])
            if changes and stored.to_dict() != tcfg.to_dict():  # a record's changes must be the checkpoint's
                diff = sorted(k for k, v in stored.to_dict().items() if tcfg.to_dict()[k] != v)
                raise SystemExit(f"--evaluate {ckpt}: its training differs from the recipe these flags give in {diff}")
            tcfg = stored
        else:
            controller, hist = train_vgai(cfg, tcfg, checkpoint=ckpt, progress=False,
                                          **({"stage1": cached(args.stage1_cache)} if args.stage1_cache else {}))
    with Provenance(command) as eval_prov:
        res = relative_cost(controller, cfg, episodes=args.episodes, seed=VALIDATION_SEED, name=args.name)
    print(res)
    out = {"command": command, "note": args.note, "base": args.base, "changes": changes, "config": dataclasses.asdict(cfg),
           "train_config": tcfg.to_dict(),
           "train_seconds": round(hist["seconds"], 1), "stage1_cached": hist.get("stage1_cached"),
           "stage1_seconds": round(hist.get("stage1_seconds", 0.0), 1),
           "seconds_by_phase": {k: round(v, 1) for k, v in hist.get("seconds_by_phase", {}).items()},
           "evaluation_seconds": round(eval_prov.seconds, 1), "round_checks": hist["rounds"], **res.summary(),
           "pinned": res.pinned(),
           "provenance": {"training": None if args.evaluate else train_prov.record(),
                          "evaluation": eval_prov.record(checkpoint=ckpt, seed=VALIDATION_SEED,
                                                         episodes=args.episodes)}}
    (folder / f"{args.name}.json").write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

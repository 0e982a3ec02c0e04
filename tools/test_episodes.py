"""The book's headline figures on the test episodes: each shipped controller flown
once on ``book.TEST_SEED``'s episodes, nothing chosen on them.

    python tools/test_episodes.py                        # Local, the DAGNN, the shipped VGAI -> data/test/
    python tools/test_episodes.py --only vgai_F24        # one of them
    python tools/test_episodes.py --controller data/experiments/vgai_learner.pt --name vgai_learner
    python tools/test_episodes.py --only pilot          # the modular vision pilot (not a checkpoint: composed)

Each record (``data/test/NAME.json``) holds the relative cost with its interval, the safety figures,
did it flock (velocity variance at 2 s and 5 s, connected at 5 s), its first episodes one by one and
its provenance (command, commit, versions, threads, load average, the checkpoint's sha256).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from vgai_lite import FlockConfig, LocalController, load_controller, relative_cost  # noqa: E402
from vgai_lite.book import DATA_DIR, TEST_SEED  # noqa: E402
from vgai_lite.lab.provenance import Provenance, repo_relative, sha256  # noqa: E402
from vgai_lite.lab.runs import write_evaluation  # noqa: E402

SHIPPED = {"local": None, "dagnn_K4": DATA_DIR / "dagnn" / "dagnn_K4.pt", "vgai_F24": DATA_DIR / "vgai" / "vgai_F24.pt",
           "pilot": "pilot"}
"""The controllers whose headline figures the book reports: name -> checkpoint (None: the local heuristic;
"pilot": the modular vision pilot, ``pilot``)."""

PILOT_NAME = "modular vision pilot"
PILOT_CHECKPOINTS = (DATA_DIR / "dagnn" / "dagnn_K4.pt", DATA_DIR / "experiments" / "estimator_odd8_synth0.5.pt")


def pilot(cfg: FlockConfig):
    """The modular vision pilot: a state estimator trained alone (odd motion features, synthetic
    velocities; data/experiments/estimator_odd8_synth0.5.pt) feeding the shipped DAGNN's MLP, never
    trained end to end: the pipeline the paper's joint training is meant to beat."""
    sys.path.insert(0, str(ROOT / "tools" / "experiments"))
    from estimator_in_the_loop import VisionDAGNN, odd_estimator

    return VisionDAGNN(load_controller(PILOT_CHECKPOINTS[0]), *odd_estimator(cfg))


def evaluate(name: str, checkpoint, episodes: int, command: str) -> Path:
    cfg = FlockConfig()
    if checkpoint == "pilot":
        controller, label, reads = pilot(cfg), PILOT_NAME, {"checkpoints": {
            repo_relative(p): sha256(p) for p in PILOT_CHECKPOINTS}}
        checkpoint = None
    else:
        controller = LocalController(cfg) if checkpoint is None else load_controller(checkpoint)
        label, reads = name, {}
    with Provenance(command) as prov:
        res = relative_cost(controller, cfg, episodes=episodes, seed=TEST_SEED, name=label)
    print(res)
    return write_evaluation(DATA_DIR / "test" / f"{name}.json", res, cfg,
                            provenance=prov.record(checkpoint=checkpoint, seed=TEST_SEED, episodes=episodes, **reads))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--only", nargs="*", choices=sorted(SHIPPED), default=None)
    p.add_argument("--controller", default=None, help="a checkpoint to evaluate instead (with --name)")
    p.add_argument("--name", default=None)
    p.add_argument("--episodes", type=int, default=50)
    p.add_argument("--threads", type=int, default=2)
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    command = " ".join(["python tools/test_episodes.py"] + (sys.argv[1:] if argv is None else argv))
    if args.controller:
        if not args.name:
            p.error("--controller needs --name")
        todo = {args.name: Path(args.controller)}
    else:
        todo = {k: v for k, v in SHIPPED.items() if args.only is None or k in args.only}
    for name, ckpt in todo.items():
        print("wrote", evaluate(name, ckpt, args.episodes, command))
    return 0


if __name__ == "__main__":
    sys.exit(main())

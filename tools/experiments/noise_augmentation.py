"""Experiment: the obvious cure for VGAI's sensitivity to pixel noise, measured.

    python tools/experiments/noise_augmentation.py            # the record says how long it took

Starts from the book's VGAI (data/vgai/vgai_F24.pt) and continues its stage 3 (joint K-step BPTT,
``vgai_training.joint_round``) for ``ROUNDS`` DAgger rounds, exactly as its training did, except
that every window's raw frames pass through a noisy camera first: pixel noise of a standard
deviation drawn uniformly in [0, SIGMA_MAX] for every batch of frames, clipped to [0, 1] as
``perturbations.ImageNoise`` does. The flights are flown by the expert (40 episodes, as in round 0)
and by the learner (16 per round, DAgger's mixture), in the clean world.

A control run does the same rounds without noise (``--control``), so that the difference between
the two is the noise's and not the extra training's. Each writes ``data/experiments/NAME.pt`` and
``NAME.json``: the relative cost with did-it-flock and safety figures on the robustness sweep's
episodes (``robustness.RobustnessConfig``: the test episodes, same perturbation seed), clean and
with ImageNoise at every sigma of the sweep (the control: at sigma = 0.05 only), and its provenance:
the command, the sha256 of the VGAI it started from, the threads and the machine's load.
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

from vgai_lite import FlockConfig, VGAITrainConfig, load_controller, relative_cost, sample_initial_state  # noqa: E402
from vgai_lite.book import DATA_DIR  # noqa: E402
from vgai_lite.checkpoints import save_controller  # noqa: E402
from vgai_lite.imitation import EpisodeStore  # noqa: E402
from vgai_lite.lab.perturbations import ImageNoise, perturbed  # noqa: E402
from vgai_lite.lab.provenance import Provenance, sha256  # noqa: E402
from vgai_lite.lab.robustness import RobustnessConfig  # noqa: E402
from vgai_lite.vgai_training import joint_round  # noqa: E402

ROUNDS = 2
SIGMA_MAX = 0.1
SEED = 15  # of the new flights and draws (the shipped training used 0; evaluation uses the sweep's seed)
BASE = DATA_DIR / "vgai" / "vgai_F24.pt"


def train(noise: bool, progress: bool = True):
    cfg = FlockConfig()
    learner = load_controller(BASE)
    tcfg = VGAITrainConfig.from_dict(learner.meta["train_config"])
    model = learner.model
    gen = torch.Generator().manual_seed(SEED)
    store = EpisodeStore()
    store.fly(None, cfg, *sample_initial_state(cfg, tcfg.expert_episodes, gen), 0.0, gen)

    def camera(frame: torch.Tensor, lag: int) -> torch.Tensor:
        sigma = SIGMA_MAX * torch.rand((), generator=gen).item()
        n = torch.randn(frame.shape, generator=gen, dtype=frame.dtype)
        return (frame + sigma * n).clamp(0.0, 1.0)

    opt = torch.optim.Adam(model.parameters(), lr=tcfg.lr)
    start, losses = time.perf_counter(), []
    for rnd in range(ROUNDS):
        model.eval()
        store.fly(learner, cfg, *sample_initial_state(cfg, tcfg.episodes_per_round, gen), tcfg.p_learner, gen)
        losses += joint_round(model, opt, cfg, tcfg, store, gen, desc=f"fine-tune round {rnd + 1}/{ROUNDS}",
                              progress=progress, camera=camera if noise else None)
    model.eval()
    return learner, {"seconds": time.perf_counter() - start, "joint_loss": losses}


def evaluate(controller, sigmas) -> dict:
    rc = RobustnessConfig()
    cfg = FlockConfig()
    out = {}
    for sigma in (0.0,) + tuple(sigmas):
        c = perturbed(controller, ImageNoise(sigma), seed=rc.seed) if sigma else controller
        res = relative_cost(c, cfg, episodes=rc.episodes, seed=rc.seed, flock_times=rc.flock_times)
        out[f"{sigma:g}"] = {**res.summary(), "min_distance": round(float(res.safety.min_distance.min()), 4)}
        print(f"sigma {sigma:g}: {res}")
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--control", action="store_true", help="the same rounds without noise")
    p.add_argument("--threads", type=int, default=2)
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    name = "vgai_F24_finetuned_clean" if args.control else "vgai_F24_noise_augmented"
    command = f"python tools/experiments/noise_augmentation.py{' --control' if args.control else ''} --threads {args.threads}"
    base_sha = sha256(BASE)
    with Provenance(command) as prov:
        learner, hist = train(noise=not args.control)
    folder = DATA_DIR / "experiments"
    meta = {"train_config": learner.meta["train_config"], "finished": True,
            "history": {**learner.meta["history"], "finetune": hist},
            "finetune": {"from": str(BASE.relative_to(ROOT)), "from_sha256": base_sha, "rounds": ROUNDS, "seed": SEED,
                         "noise_sigma_max": 0.0 if args.control else SIGMA_MAX}}
    learner.meta = meta
    save_controller(folder / f"{name}.pt", learner, meta=meta)
    sigmas = (0.05,) if args.control else dict(RobustnessConfig().perturbations)["image_noise"]
    rc = RobustnessConfig()
    with Provenance(command) as evaluation:
        flown = evaluate(learner, sigmas)
    record = {"name": name, "finetune": meta["finetune"], "finetune_seconds": round(hist["seconds"], 1),
              "torch_threads": torch.get_num_threads(),
              "provenance": {"training": prov.record(checkpoint=folder / f"{name}.pt"),
                             "evaluation": evaluation.record(checkpoint=folder / f"{name}.pt", seed=rc.seed,
                                                             episodes=rc.episodes)},
              "image_noise": flown}
    (folder / f"{name}.json").write_text(json.dumps(record, indent=1) + "\n")
    print("wrote", folder / f"{name}.json")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Experiment: is the visual state estimator good enough to flock with? Put it in the loop.

    python tools/experiments/estimator_in_the_loop.py --out data/experiments/estimator_in_the_loop.json

The shipped DAGNN (data/dagnn/dagnn_K4.pt, trained on the 6 exact local features) flies with its
velocity features replaced by noise, and with all 6 features replaced by a visual state
estimator's estimate from each drone's own images (``VisionDAGNN``): the estimator shipped with
notebook 05 (data/vgai/estimator_motion.pt, the plain CNN) and one whose velocity estimates are odd
in the motion channels (``OddMotionCNN(motion_features=8)``) trained with half of its states shown
with synthetic relative velocities (data/experiments/estimator_odd8_synth0.5.pt, trained here when
missing, about 6 minutes). For each: the flocking figures (velocity variance at 0.5-5 s, 10 held-out
500-step flights; for the odd estimator also the relative cost with safety and flocking figures on
50 held-out episodes) and, along expert flights, the estimate of the velocity features where the truth
is 0 (the swarm already aligned): the bias a plain CNN settles on.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from vgai_lite import (ExpertController, FlockConfig, consensus, load_controller, local_features,  # noqa: E402
                       relative_cost, rollout, sample_initial_state)
from vgai_lite.book import DATA_DIR, WORKING_SEED  # noqa: E402
from vgai_lite.camera import sensor_noise  # noqa: E402
from vgai_lite.checkpoints import load_estimator, save_estimator  # noqa: E402
from vgai_lite.learned_controllers import DAGNNController  # noqa: E402
from vgai_lite.state_estimation import train_state_estimator  # noqa: E402
from vgai_lite.vision import VisionConfig, camera_input, flown_backwards, stored_images  # noqa: E402

ODD = {"steps": 3000, "synthetic_share": 0.5, "motion_features": 8}


class NoisyDAGNN(DAGNNController):
    """The DAGNN with white noise of std ``sigma`` added to its two velocity features each step."""

    def __init__(self, base: DAGNNController, sigma: float, seed: int = 0):
        super().__init__(base.model, base.cfg, base.gso_kind, base.feature_transform)
        self.sigma, self.gen = sigma, torch.Generator().manual_seed(seed)

    def features(self, r, v):
        X = super().features(r, v).clone()
        X[..., :2] += self.sigma * torch.randn(X[..., :2].shape, generator=self.gen)
        return X


class VisionDAGNN(DAGNNController):
    """The DAGNN's MLP fed with a state estimator's 6 features, estimated from each drone's images; with
    ``noise`` > 0, each frame through a camera with Gaussian sensor noise of that sigma (``camera.sensor_noise``,
    a frame's draws fixed by ``seed`` and the step it was taken at, so the motion frame g steps later is the
    same noisy frame)."""

    def __init__(self, base: DAGNNController, cnn, vision: VisionConfig, noise: float = 0.0, seed: int = 0):
        super().__init__(base.model, base.cfg, base.gso_kind, base.feature_transform)
        if not 0.0 <= noise <= 1.0:
            raise ValueError(f"VisionDAGNN: noise is a pixel sigma in [0, 1], got {noise!r}")
        self.cnn, self.vision, self.seen = cnn, vision, []
        self.noise, self.seed, self.t = noise, seed, 0

    def reset(self):
        super().reset()
        self.seen, self.t = [], 0

    def _camera(self, img, lag):
        gen = torch.Generator().manual_seed(self.seed * 1_000_003 + self.t - lag + 1_000_000)
        return sensor_noise(img, self.noise, gen, self.vision.render.channels)

    def features(self, r, v):
        g = self.vision.motion_gap
        if not self.seen:  # the frames before t = 0, as VGAIController draws them
            self.seen = [flown_backwards(r, v, k, self.cfg.Ts) for k in range(g, 0, -1)]
        self.seen = (self.seen + [r])[-(g + 1):]
        images = camera_input(self.vision, self.cfg, r, self.seen[0], self._camera if self.noise > 0 else None)
        self.t += 1
        with torch.no_grad():
            return self.cnn.estimate_local_features(images.flatten(0, 1)).view(*r.shape[:2], 6)


def odd_estimator(cfg: FlockConfig):
    path = DATA_DIR / "experiments" / "estimator_odd8_synth0.5.pt"
    if path.is_file():
        cnn, vision, meta = load_estimator(path)
        if all(meta.get(k) == x for k, x in ODD.items()):
            return cnn, vision
    vision = VisionConfig()
    cnn, _, seconds = train_state_estimator(cfg, vision, progress=False, **ODD)
    save_estimator(path, cnn, vision, {**ODD, "seconds": round(seconds, 1)})
    return cnn.eval(), vision


@torch.no_grad()
def bias_at_rest(cnn, vision, cfg, episodes: int = 8, t: int = 190) -> dict:
    """Along expert flights at step t (the swarm aligned: relative velocities ~1e-7 m/s), the size
    of the estimated velocity features (they should be 0)."""
    r0, v0 = sample_initial_state(cfg, episodes, torch.Generator().manual_seed(WORKING_SEED))
    tr = rollout(ExpertController(cfg), cfg, r0, v0, steps=t + 1)
    e, tt = torch.arange(episodes), torch.full((episodes,), t)
    est = cnn.estimate_local_features(stored_images(vision, cfg, tr.r, tr.v, e, tt).flatten(0, 1))[:, :2]
    true = local_features(tr.r[t], tr.v[t], cfg.R).flatten(0, 1)[:, :2]
    return {"step": t, "true_mean_abs": float(true.abs().mean()), "estimate_mean_abs": round(float(est.abs().mean()), 6)}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--out", default=None)
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    cfg = FlockConfig()
    dagnn = load_controller(DATA_DIR / "dagnn" / "dagnn_K4.pt")
    out = {"command": " ".join(["python tools/experiments/estimator_in_the_loop.py"] + (argv or sys.argv[1:])),
           "flights": {}, "bias_at_rest": {}}
    pilots = {"DAGNN, exact features": dagnn}
    for sigma in (0.3, 1.0):
        pilots[f"DAGNN, white noise sigma = {sigma:g} on the velocity features"] = NoisyDAGNN(dagnn, sigma)
    estimators = {"plain CNN (data/vgai/estimator_motion.pt)": load_estimator(DATA_DIR / "vgai" / "estimator_motion.pt")[:2],
                  "odd motion features, synthetic velocities": odd_estimator(cfg)}
    for label, (cnn, vision) in estimators.items():
        pilots[f"DAGNN fed by the {label}"] = VisionDAGNN(dagnn, cnn, vision)
        out["bias_at_rest"][label] = bias_at_rest(cnn, vision, cfg)
    for label, pilot in pilots.items():
        flock = consensus(pilot, cfg, episodes=10, seed=WORKING_SEED, name=label)
        print(flock, flush=True)
        out["flights"][label] = flock.summary()
    # the vision-only pilot that flocks, judged like every controller of the book (50 held-out episodes)
    label = "DAGNN fed by the odd motion features, synthetic velocities"
    res = relative_cost(pilots[label], cfg, episodes=50, seed=WORKING_SEED, name=label)
    print(res, flush=True)
    out["relative_cost"] = {label: res.summary()}
    print(json.dumps(out["bias_at_rest"], indent=1))
    if args.out:
        Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Visual state estimators on their own (section 3.3; notebook 05): stage 1 of VGAI's training
(``vgai_training.fit_state_estimator``: the CNN, through its ``aux`` head, regresses the standardised
exact local features of every agent from its own images) run alone, and how well an estimator reads
the local features on flights it was not trained on.
"""

from __future__ import annotations

import time
from typing import Optional

import torch

from .camera import CameraRanges, draw_camera
from .config import FlockConfig
from .controllers import ExpertController
from .features import N_LOCAL_FEATURES, local_features
from .flocking import rollout, sample_initial_state
from .imitation import EpisodeStore
from .models import VisualCNN
from .vgai_config import VGAITrainConfig
from .vgai_training import fit_state_estimator
from .vision import VisionConfig, stored_images


@torch.no_grad()
def estimator_quality(cnn: VisualCNN, vision: VisionConfig, cfg: FlockConfig, episodes: int = 8,
                      times=(2, 8, 20, 60), *, seed: int, pilot=None, camera: Optional[CameraRanges] = None) -> dict:
    """Correlation between the CNN's estimate (aux head) and the exact local features, per feature,
    at a few time steps of flights from the initial conditions of ``seed`` (held out from the
    training: e.g. ``book.WORKING_SEED``) flown by ``pilot`` (default the expert; a VGAI shows the states VGAI meets):
    {t: [6 values]}. ``camera``: the images seen through cameras drawn from these ranges, one per
    flight (default: the renderer's frames)."""
    gen = torch.Generator().manual_seed(seed)
    r0, v0 = sample_initial_state(cfg, episodes, gen)
    pilot = ExpertController(cfg) if pilot is None else pilot
    traj = rollout(pilot, cfg, r0, v0, steps=max(max(times) + 1, cfg.T))
    cam = draw_camera(camera, vision.render, episodes, cfg.N, gen)
    out = {}
    for t in times:
        e, tt = torch.arange(episodes), torch.full((episodes,), t)
        images = stored_images(vision, cfg, traj.r, traj.v, e, tt, cam.at(t) if cam is not None else None)
        pred = cnn.aux_standardized(cnn(images.flatten(0, 1)))
        X = local_features(traj.r[t], traj.v[t], cfg.R).flatten(0, 1)
        out[t] = [torch.corrcoef(torch.stack((pred[:, k], X[:, k])))[0, 1].item() for k in range(N_LOCAL_FEATURES)]
    return out


def train_state_estimator(cfg: FlockConfig, vision: VisionConfig, steps: int = 3000, states: int = 8,
                          F: int = 24, episodes: int = 40, seed: int = 0, progress: bool = True,
                          synthetic_share: float = 0.0, motion_features: int = 0):
    """Fly ``episodes`` expert episodes, then train a fresh VisualCNN to estimate the exact local
    features from images (stage 1 of VGAI's training, on its own; notebook 05).
    Returns (cnn, losses, seconds)."""
    tcfg = VGAITrainConfig(F=F, vision=vision, seed=seed, motion_features=motion_features, warm_steps=steps,
                           warm_states=states, synthetic_share=synthetic_share)
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        gen = torch.Generator().manual_seed(seed)
        start = time.perf_counter()
        store = EpisodeStore()
        store.fly(None, cfg, *sample_initial_state(cfg, episodes, gen), 0.0, gen)
        cnn = tcfg.new_model().cnn
        losses = fit_state_estimator(cnn, cfg, tcfg, store.groups(), gen, progress)
    return cnn, losses, time.perf_counter() - start

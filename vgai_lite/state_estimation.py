"""Visual state estimation (section 3.3; notebook 05): the CNN taught to see the 6 exact local features.

Stage 1 of VGAI's training (``vgai_training``) and the stand-alone estimators of notebook 05. The CNN,
through its ``aux`` head, regresses the standardised exact local features (``features``) of every
agent from that agent's own images, on stored expert flights. ``synthetic_velocities`` shows a
share of those swarm states with relative velocities they did not have, from the smallest
disagreements a late flight leaves to the early ones, so that the estimator learns to read small
motions too (the expert's own late states have almost none to learn from).
"""

from __future__ import annotations

import math
import time

import torch
import torch.nn.functional as nnf
from tqdm.auto import tqdm

from .book import EVAL_SEED
from .config import FlockConfig
from .controllers import ExpertController
from .features import local_features
from .flocking import rollout, sample_initial_state
from .imitation import EpisodeStore
from .models import VisualCNN
from .vgai_config import VGAITrainConfig, sample_times
from .vision import VisionConfig, camera_input, flown_backwards, positions_before, stored_images

SYNTHETIC_SPEEDS = (0.01, 1.5)
"""Range (m/s) of the per-agent velocity deviations of ``synthetic_velocities``: from below the
late-flight disagreements eq. 1 must remove to the early ones."""




def feature_scale(cfg: FlockConfig, r: torch.Tensor, v: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Mean and spread of the 6 exact local features over stored states r, v (T, E, N, 2)."""
    X = local_features(r.flatten(0, 1), v.flatten(0, 1), cfg.R)
    return X.mean((0, 1)), X.std((0, 1)).clamp(min=1e-6)


def synthetic_velocities(v: torch.Tensor, gen: torch.Generator) -> torch.Tensor:
    """Velocities a swarm could have: its mean velocity plus independent per-agent deviations of a
    scale drawn log-uniformly in [SYNTHETIC_SPEEDS] m/s, one scale per swarm. v (M, N, 2) -> (M, N, 2)."""
    lo, hi = SYNTHETIC_SPEEDS
    scale = torch.empty(v.shape[0], 1, 1).uniform_(math.log(lo), math.log(hi), generator=gen).exp()
    return v.mean(1, keepdim=True) + scale * torch.randn(v.shape, generator=gen)


def _estimation_batch(vision, cfg, r, v, states, tcfg, gen, synthetic_share):
    """Images and exact local features of ``states`` stored swarm states; a ``synthetic_share`` of
    them with synthetic velocities (the motion frame drawn from the state flown backwards at them)."""
    T, E = r.shape[:2]
    e = torch.randint(0, E, (states,), generator=gen)
    t = sample_times(states, T, tcfg, gen)
    if synthetic_share <= 0:
        return stored_images(vision, cfg, r, v, e, t), local_features(r[t, e], v[t, e], cfg.R)
    synth = (torch.rand(states, generator=gen) < synthetic_share)[:, None, None]
    vs = torch.where(synth, synthetic_velocities(v[t, e], gen), v[t, e])
    before = torch.where(synth, flown_backwards(r[t, e], vs, vision.motion_gap, cfg.Ts),
                         positions_before(vision, cfg, r, v, e, t))
    return camera_input(vision, cfg, r[t, e], before), local_features(r[t, e], vs, cfg.R)


def fit_state_estimator(cnn: VisualCNN, vision: VisionConfig, cfg: FlockConfig, r: torch.Tensor,
                        v: torch.Tensor, steps: int, states: int, tcfg: VGAITrainConfig,
                        gen: torch.Generator, progress: bool = True, synthetic_share: float = 0.0) -> list:
    """Visual state estimation: train the CNN (through its ``aux`` head) to regress the standardised
    exact local features of every agent from its own images, on stored states r, v (T, E, N, 2).
    Each step draws ``states`` swarm states (all N agents' images). ``synthetic_share``: the share of
    them shown with synthetic velocities (``synthetic_velocities``; ``VGAITrainConfig.synthetic_share``,
    0.5 in the book's VGAI). Returns the L1 loss per step."""
    x_mean, x_std = feature_scale(cfg, r, v)
    if cnn.motion_features:  # the odd velocity estimates are 0 when nothing moves, so is their offset
        x_mean[:2] = 0.0
    cnn.aux_mean.copy_(x_mean), cnn.aux_std.copy_(x_std)
    opt = torch.optim.Adam(cnn.parameters(), lr=tcfg.lr)
    cnn.train()
    losses = []
    for _ in tqdm(range(steps), desc="stage 1: visual state estimation", disable=not progress):
        img, X = _estimation_batch(vision, cfg, r, v, states, tcfg, gen, synthetic_share)
        target = (X - x_mean) / x_std
        loss = nnf.l1_loss(cnn.aux_standardized(cnn(img.flatten(0, 1))), target.flatten(0, 1))
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        losses.append(loss.item())
    cnn.eval()
    return losses


@torch.no_grad()
def estimator_quality(cnn: VisualCNN, vision: VisionConfig, cfg: FlockConfig, episodes: int = 8,
                      times=(2, 8, 20, 60), seed: int = EVAL_SEED, pilot=None) -> dict:
    """Correlation between the CNN's estimate (aux head) and the exact local features, per feature,
    at a few time steps of flights from held-out initial conditions (``seed``, the book's EVAL_SEED
    by default) flown by ``pilot`` (default the expert; a VGAI shows the states VGAI meets):
    {t: [6 values]}."""
    r0, v0 = sample_initial_state(cfg, episodes, torch.Generator().manual_seed(seed))
    pilot = ExpertController(cfg) if pilot is None else pilot
    traj = rollout(pilot, cfg, r0, v0, steps=max(max(times) + 1, cfg.T))
    out = {}
    for t in times:
        e, tt = torch.arange(episodes), torch.full((episodes,), t)
        pred = cnn.aux_standardized(cnn(stored_images(vision, cfg, traj.r, traj.v, e, tt).flatten(0, 1)))
        X = local_features(traj.r[t], traj.v[t], cfg.R).flatten(0, 1)
        out[t] = [torch.corrcoef(torch.stack((pred[:, k], X[:, k])))[0, 1].item() for k in range(6)]
    return out


def train_state_estimator(cfg: FlockConfig, vision: VisionConfig, steps: int = 3000, states: int = 8,
                          F: int = 24, episodes: int = 40, seed: int = 0, progress: bool = True,
                          synthetic_share: float = 0.0, motion_features: int = 0):
    """Fly ``episodes`` expert episodes, then train a fresh VisualCNN to estimate the exact local
    features from images (stage 1 of VGAI's training, on its own; notebook 05).
    Returns (cnn, losses, seconds)."""
    tcfg = VGAITrainConfig(F=F, vision=vision, seed=seed, motion_features=motion_features)
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        gen = torch.Generator().manual_seed(seed)
        start = time.perf_counter()
        store = EpisodeStore()
        store.fly(None, cfg, *sample_initial_state(cfg, episodes, gen), 0.0, gen)
        r, v, _ = store.tensors()
        cnn = tcfg.new_model().cnn
        losses = fit_state_estimator(cnn, vision, cfg, r, v, steps, states, tcfg, gen, progress, synthetic_share)
    return cnn, losses, time.perf_counter() - start

"""Training VGAI: the CNN and the aggregation MLP together, by imitation with DAgger and K-step BPTT.

Introduced in notebook 06. Images are rendered on the fly from stored swarm states (no image dataset
on disk; ``vision.stored_images``). The paper trains CNN_Psi and NN_Theta jointly end to end, by
K-step backpropagation through time (its figure 3): for a window of K consecutive steps, every
agent's K images go through the CNN, the features travel through the delayed aggregation (eq. 6),
the MLP acts once at the last step, and the L1 loss against the expert's action flows back through
all K CNN passes (``bptt_loss``).

The paper is silent on how long to train and on warm starts. Ours, in three stages, to train in
minutes on two CPU cores (``train_vgai``):
  1. visual state estimation (``fit_state_estimator``): the CNN (through a linear head) regresses
     the DAGNN's 6 exact local features from single agents' images;
  2. ``fit_mlp``: the MLP is fitted on Z(t) built from the (frozen) CNN's features, like the DAGNN;
  3. ``joint_round``: joint K-step BPTT of both on windows, after each DAgger round (learner
     followed with probability 0.33) has added the learner's own states.
Loss L1 (eq. 10) and Adam at learning rate 1e-3 (the paper's) in every stage.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Union

import torch
import torch.nn.functional as nnf
from tqdm.auto import tqdm

from .aggregation import aggregation_sequence
from .book import EVAL_SEED
from .checkpoints import load_stage1, save_controller, save_stage1, stage1_file
from .config import FlockConfig, config_dict
from .controllers import ExpertController
from .features import local_features
from .flocking import rollout, sample_initial_state
from .graphs import DEFAULT_GSO, adjacency, gso
from .imitation import EpisodeStore, fit_l1, validation_record
from .learned_controllers import VGAIController
from .models import AggregationMLP, VGAIModel, VisualCNN
from .vision import VisionConfig, camera_input, flown_backwards, positions_before, stored_images

log = logging.getLogger(__name__)

MLP_LATE_STRIDE = 4
"""Stage 2 keeps every step of the first ``early_steps`` of each flight and 1 step in 4 after: the
expert's labels live early (as the DAGNN's ``keep_late`` = 0.25)."""
SYNTHETIC_SPEEDS = (0.01, 1.5)
"""Range (m/s) of the per-agent velocity deviations of ``synthetic_velocities`` (experimental): from
below the late-flight disagreements eq. 1 must remove to the early ones."""
MLP_BATCH = 1024
"""Rows (agent-steps) per gradient step of stage 2 (as the DAGNN's ``batch_size``)."""


@dataclass(frozen=True)
class VGAITrainConfig:
    """Everything that defines a VGAI training run.

    Attributes:
        F, K, hidden, gso: features per agent (paper default 24), taps (K - 1 = 3 exchanges),
            MLP hidden widths, graph shift operator.
        cnn_widths, cnn_hidden: channels of the CNN's two stages, width of its hidden FC layer.
        vision: what the agents see (view, resolution, motion frames).
        expert_episodes: episodes of round 0, flown by the expert alone.
        dagger_rounds, episodes_per_round, p_learner: DAgger rounds after the warm starts, new
            episodes per round, probability of following the learner at each step (paper: 0.33).
        warm_steps, warm_states: stage 1, gradient steps and swarm states (x N agents' images) per step.
        mlp_epochs: stage 2, passes over the frozen-CNN dataset.
        joint_steps, windows: stage 3, gradient steps per DAgger round and K-step windows per step.
        lr: Adam's learning rate (paper: 1e-3).
        early_steps, early_share: sampled states and window ends fall in the first ``early_steps``
            steps with probability ``early_share`` (the expert's labels live early).
        seed: seed of the training initial conditions, sampling and weights.
        synthetic_share: stage 1 shows this share of its states with synthetic velocities
            (``synthetic_velocities``; experimental, 0 in the book's runs so far). Stored by
            ``to_dict`` only when not 0: files written before the field existed had none, so the
            shipped checkpoints and table cells keep their identity.
        motion_features: F_m, the CNN's features made odd in the motion channels (``VisualCNN``;
            0: the plain CNN). Needs the "difference" motion mode. Stored like ``synthetic_share``.
    """

    F: int = 24
    K: int = 4
    hidden: tuple = (64, 64)
    gso: str = DEFAULT_GSO
    cnn_widths: tuple = (8, 16)
    cnn_hidden: int = 64
    vision: VisionConfig = VisionConfig()
    expert_episodes: int = 40
    dagger_rounds: int = 4
    episodes_per_round: int = 16
    p_learner: float = 0.33
    warm_steps: int = 3000
    warm_states: int = 8
    mlp_epochs: int = 4
    joint_steps: int = 600
    windows: int = 4
    lr: float = 1e-3
    early_steps: int = 50
    early_share: float = 0.75
    seed: int = 0
    synthetic_share: float = 0.0
    motion_features: int = 0

    def __post_init__(self) -> None:
        if not 0.0 <= self.synthetic_share <= 1.0:
            raise ValueError(f"VGAITrainConfig: synthetic_share must be in [0, 1], got {self.synthetic_share!r}")
        if self.motion_features and (self.vision.motion_gap == 0 or self.vision.motion_mode != "difference"):
            raise ValueError("VGAITrainConfig: motion_features needs a motion frame in the 'difference' mode "
                             f"(got motion_gap={self.vision.motion_gap}, motion_mode={self.vision.motion_mode!r})")

    def to_dict(self) -> dict:
        d = config_dict(self)
        for optional in ("synthetic_share", "motion_features"):  # absent from files written before them
            if d[optional] == 0:
                del d[optional]
        return d

    def new_model(self) -> VGAIModel:
        """Freshly initialised CNN_Psi and NN_Theta of this configuration (global torch RNG)."""
        C, H, W = self.vision.image_shape()
        return VGAIModel(VisualCNN(C, H, W, self.F, self.cnn_widths, self.cnn_hidden, self.motion_features),
                         AggregationMLP(self.K, self.F, self.hidden))


def sample_times(n: int, T: int, tcfg: VGAITrainConfig, g: torch.Generator) -> torch.Tensor:
    """n time steps in [0, T): in the first ``early_steps`` with probability ``early_share``, else uniform."""
    early = torch.rand(n, generator=g) < tcfg.early_share
    t_early = torch.randint(0, min(tcfg.early_steps, T), (n,), generator=g)
    t_any = torch.randint(0, T, (n,), generator=g)
    return torch.where(early, t_early, t_any)


# ---------------------------------------------------------------------------------------------
# Stage 1: visual state estimation (section 3.3; notebook 05)


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
    them shown with synthetic velocities (``synthetic_velocities``; experimental, off in the book's
    runs). Returns the L1 loss per step."""
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


def stage1_identity(cfg: FlockConfig, tcfg: VGAITrainConfig) -> dict:
    """What stage 1 depends on (not K, the MLP or the DAgger schedule): runs that agree on it train
    the very same stage-1 CNN, and share it through the cache."""
    t = tcfg.to_dict()
    fields = ("F", "cnn_widths", "cnn_hidden", "vision", "expert_episodes", "warm_steps", "warm_states",
              "lr", "early_steps", "early_share", "seed", "synthetic_share", "motion_features")
    return {"config": cfg.to_dict(), "train": {k: t[k] for k in fields if k in t}}


def stage1_cache_file(folder: Union[str, Path], cfg: FlockConfig, tcfg: VGAITrainConfig) -> Path:
    return stage1_file(folder, stage1_identity(cfg, tcfg), tcfg.F)


def cached_stage1(cnn, cfg, tcfg, r, v, gen, progress, cache: Optional[Union[str, Path]]) -> dict:
    """Stage 1, read from ``cache`` when this exact stage 1 was trained before (the CNN and the
    sampling generator restored as they were at its end), else trained and written there.
    Returns the history entries of stage 1."""
    path = stage1_cache_file(cache, cfg, tcfg) if cache is not None else None
    if path is not None and path.is_file():
        return {**load_stage1(path, cnn, gen), "stage1_cached": path.name}
    start = time.perf_counter()
    record = {"warm_loss": fit_state_estimator(cnn, tcfg.vision, cfg, r, v, tcfg.warm_steps, tcfg.warm_states,
                                               tcfg, gen, progress, tcfg.synthetic_share)}
    record["stage1_seconds"] = time.perf_counter() - start
    if path is not None:
        save_stage1(path, stage1_identity(cfg, tcfg), cnn, gen, record)
    return record


# ---------------------------------------------------------------------------------------------
# Stage 2: the MLP on the frozen CNN's features


def fit_mlp(model: VGAIModel, cfg: FlockConfig, tcfg: VGAITrainConfig, r: torch.Tensor, v: torch.Tensor,
            u: torch.Tensor, gen: torch.Generator, progress: bool = True) -> list:
    """Fit NN_Theta on Z(t) built from the frozen CNN's features along stored flights r, v, u*
    (T, E, N, 2), like the DAGNN on its exact features. Returns the mean L1 loss per epoch."""
    T, E = r.shape[:2]
    model.eval()
    with torch.no_grad():
        S = gso(adjacency(r.flatten(0, 1), cfg.R), tcfg.gso).view(T, E, cfg.N, cfg.N)
        X = torch.stack([model.features(stored_images(tcfg.vision, cfg, r, v, torch.arange(E), torch.full((E,), t)))
                         for t in range(T)])  # (T, E, N, F)
        Z = aggregation_sequence(X.transpose(0, 1), S.transpose(0, 1), tcfg.K)  # (E, T, N, K, F)
    early = min(tcfg.early_steps, T)
    keep_t = torch.cat((torch.arange(early), torch.arange(early, T, MLP_LATE_STRIDE)))
    Zr = Z[:, keep_t].reshape(-1, tcfg.K, tcfg.F)
    Ur = u.transpose(0, 1)[:, keep_t].reshape(-1, 2)
    model.mlp.set_normalization(Zr)
    opt = torch.optim.Adam(model.mlp.parameters(), lr=tcfg.lr)
    return fit_l1(model.mlp, Zr, Ur, opt, tcfg.mlp_epochs, MLP_BATCH, gen,
                  desc="stage 2: MLP on CNN features", progress=progress)


# ---------------------------------------------------------------------------------------------
# Stage 3: joint K-step BPTT (the paper's figure 3)


def bptt_loss(model: VGAIModel, cfg: FlockConfig, tcfg: VGAITrainConfig, r: torch.Tensor, v: torch.Tensor,
              u: torch.Tensor, gen: torch.Generator) -> torch.Tensor:
    """The L1 loss of one joint step on ``tcfg.windows`` windows of K steps drawn from stored flights
    r, v, u* (T, E, N, 2). Every agent's K images of a window go through the CNN, the features
    through the unrolled aggregation (eq. 6), the MLP acts once at the window's last step; calling
    ``backward`` on the result is K-step BPTT. Steps before t = 0 contribute nothing (X = 0, S = 0)."""
    T, E = r.shape[:2]
    K, M = tcfg.K, tcfg.windows
    e = torch.randint(0, E, (M,), generator=gen)
    t_end = sample_times(M, T, tcfg, gen)
    tau = t_end[:, None] - (K - 1) + torch.arange(K)  # (M, K) times of the window
    valid = (tau >= 0).float()[:, :, None, None]
    tau_c, ee = tau.clamp(min=0).flatten(), e[:, None].expand_as(tau).flatten()
    X = model.features(stored_images(tcfg.vision, cfg, r, v, ee, tau_c)).view(M, K, cfg.N, tcfg.F) * valid
    S = gso(adjacency(r[tau_c, ee], cfg.R), tcfg.gso).view(M, K, cfg.N, cfg.N) * valid
    Z = aggregation_sequence(X, S, K)[:, -1]  # Z(t) at the window's last step, (M, N, K, F)
    return nnf.l1_loss(model.mlp(Z), u[t_end, e])


def joint_round(model: VGAIModel, opt: torch.optim.Optimizer, cfg: FlockConfig, tcfg: VGAITrainConfig,
                store: EpisodeStore, gen: torch.Generator, desc: str, progress: bool = True) -> list:
    """``tcfg.joint_steps`` steps of joint K-step BPTT on the stored flights. Returns the losses."""
    r, v, u = store.tensors()
    model.train()
    losses = []
    bar = tqdm(range(tcfg.joint_steps), desc=desc, disable=not progress)
    for _ in bar:
        loss = bptt_loss(model, cfg, tcfg, r, v, u, gen)
        opt.zero_grad(set_to_none=True)
        loss.backward()  # through the MLP once and the CNN K times (K-step BPTT)
        opt.step()
        losses.append(loss.item())
        bar.set_postfix(loss=f"{loss.item():.2f}")
    model.eval()
    return losses


# ---------------------------------------------------------------------------------------------
# The three stages together


def train_vgai(cfg: FlockConfig, tcfg: VGAITrainConfig = VGAITrainConfig(),
               checkpoint: Optional[Union[str, Path]] = None, progress: bool = True,
               validation_episodes: int = 10, stage1_cache: Optional[Union[str, Path]] = None
               ) -> tuple[VGAIController, dict]:
    """Train VGAI in the three stages of the module docstring; save to ``checkpoint`` as it goes.

    ``stage1_cache``: a folder where the CNN at the end of stage 1 is kept, keyed by what stage 1
    depends on (:func:`stage1_identity`); a run that finds its stage 1 there skips it and continues
    exactly as if it had trained it (the K = 2, 3, 4 runs of Table 1b share one). The history then
    says ``stage1_cached`` and keeps the seconds the cached stage 1 took when it was trained.

    Returns the controller and its history: per stage the losses, and per DAgger round the
    validation relative cost (seed + 1000) with the seconds elapsed. The global torch RNG is left
    as it was.
    """
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(tcfg.seed)  # the weights' initialisation
        return _train_vgai(cfg, tcfg, checkpoint, progress, validation_episodes, stage1_cache)


def _train_vgai(cfg, tcfg, checkpoint, progress, validation_episodes, stage1_cache):
    gen = torch.Generator().manual_seed(tcfg.seed)
    model = tcfg.new_model()
    learner = VGAIController(model, cfg, tcfg.vision, tcfg.gso)
    history = {"warm_loss": [], "mlp_loss": [], "joint_loss": [], "rounds": []}
    start = time.perf_counter()
    store = EpisodeStore()

    def save(finished: bool = False) -> None:
        history["seconds"] = time.perf_counter() - start
        learner.meta = {"train_config": tcfg.to_dict(), "history": history, "finished": finished}
        if checkpoint is not None:
            save_controller(checkpoint, learner, meta=learner.meta)

    def validate(stage: str) -> None:
        model.eval()
        history["rounds"].append({"stage": stage, "episodes": store.episodes,
                                  **validation_record(learner, cfg, validation_episodes, tcfg.seed),
                                  "seconds": time.perf_counter() - start})
        log.info("%s: validation relative cost %.2f after %.0f s", stage,
                 history["rounds"][-1]["val_relative_cost"], time.perf_counter() - start)
        save()

    # Round 0: the expert flies alone; stages 1 and 2 learn from its flights.
    store.fly(None, cfg, *sample_initial_state(cfg, tcfg.expert_episodes, gen), 0.0, gen)
    r, v, u = store.tensors()
    history.update(cached_stage1(model.cnn, cfg, tcfg, r, v, gen, progress, stage1_cache))
    history["mlp_loss"] = fit_mlp(model, cfg, tcfg, r, v, u, gen, progress)
    validate("after stages 1-2")

    # Stage 3: each DAgger round adds the learner's own flights, then joint K-step BPTT on all.
    opt = torch.optim.Adam(model.parameters(), lr=tcfg.lr)
    for rnd in range(tcfg.dagger_rounds):
        model.eval()
        store.fly(learner, cfg, *sample_initial_state(cfg, tcfg.episodes_per_round, gen), tcfg.p_learner, gen)
        history["joint_loss"] += joint_round(model, opt, cfg, tcfg, store, gen, progress=progress,
                                             desc=f"stage 3: joint BPTT, round {rnd + 1}/{tcfg.dagger_rounds}")
        validate(f"DAgger round {rnd + 1}")
    save(finished=True)
    return learner, history


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

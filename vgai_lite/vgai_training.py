"""Training VGAI: the CNN and the aggregation MLP together, by imitation with DAgger and K-step BPTT.

Introduced in notebook 06. Images are rendered on the fly from stored swarm states (no image dataset
on disk; ``vision.stored_images``). The paper trains CNN_Psi and NN_Theta jointly end to end, by
K-step backpropagation through time (its figure 3): for a window of K consecutive steps, every
agent's K images go through the CNN, the features travel through the delayed aggregation (eq. 6),
the MLP acts once at the last step, and the L1 loss against the expert's action flows back through
all K CNN passes (``bptt_loss``).

The paper is silent on how long to train and on warm starts. Ours, in three stages, to train in
minutes on two CPU cores (``train_vgai``):
  1. visual state estimation (``state_estimation.fit_state_estimator``): the CNN (through a linear
     head) regresses the DAGNN's 6 exact local features from single agents' images;
  2. ``fit_mlp``: the MLP is fitted on Z(t) built from the (frozen) CNN's features, like the DAGNN;
  3. ``joint_round``: joint K-step BPTT of both on windows, after each DAgger round (learner
     followed with probability 0.33) has added the learner's own states.
Loss L1 (eq. 10) and Adam at learning rate 1e-3 (the paper's) in every stage.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import Optional, Union

import torch
import torch.nn.functional as nnf
from tqdm.auto import tqdm

from .aggregation import aggregation_sequence
from .checkpoints import load_stage1, save_controller, save_stage1, stage1_file
from .config import FlockConfig
from .features import local_features
from .flocking import sample_initial_state
from .graphs import adjacency, gso
from .imitation import EpisodeStore, fit_l1, validation_record
from .learned_controllers import VGAIController
from .models import VGAIModel
from .state_estimation import fit_state_estimator
from .vgai_config import VGAITrainConfig, sample_times
from .vision import stored_images

log = logging.getLogger(__name__)

MLP_LATE_STRIDE = 4
"""Stage 2 keeps every step of the first ``early_steps`` of each flight and 1 step in 4 after: the
expert's labels live early (as the DAGNN's ``keep_late`` = 0.25)."""
MLP_BATCH = 1024
"""Rows (agent-steps) per gradient step of stage 2 (as the DAGNN's ``batch_size``)."""


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


def exact_through_aux(cnn, X: torch.Tensor, r: torch.Tensor, v: torch.Tensor, R: float) -> torch.Tensor:
    """The CNN's features X (..., N, F) of states r, v (..., N, 2) with their estimation error removed:
    the features closest to X that the aux head reads as the exact local features,

        X* = X + A^+ (x_exact - aux(X)),   A the aux head's (masked) weight, A^+ its pseudo-inverse,

    so aux(X*) = x_exact (standardised) and the part of X the aux head does not read stays the CNN's.
    With odd motion features A is block-diagonal (velocities from odd features only), so is A^+: the
    velocity error is removed from the odd features, the position error from the even ones."""
    N = r.shape[-2]
    exact = local_features(r.reshape(-1, N, 2), v.reshape(-1, N, 2), R).view(*r.shape[:-1], 6)
    target = (exact - cnn.aux_mean) / cnn.aux_std
    eye = torch.eye(cnn.F, dtype=X.dtype, device=X.device)
    A = cnn.aux_standardized(eye).T - cnn.aux_standardized(torch.zeros_like(eye[:1])).T  # (6, F)
    return X + (target - cnn.aux_standardized(X.flatten(0, -2)).view_as(target)) @ torch.linalg.pinv(A).T


def fit_mlp(model: VGAIModel, cfg: FlockConfig, tcfg: VGAITrainConfig, r: torch.Tensor, v: torch.Tensor,
            u: torch.Tensor, gen: torch.Generator, progress: bool = True) -> list:
    """Fit NN_Theta on Z(t) built from the frozen CNN's features along stored flights r, v, u*
    (T, E, N, 2), like the DAGNN on its exact features (with ``tcfg.mlp_on_exact``, on those features
    read as the exact ones, ``exact_through_aux``). Returns the mean L1 loss per epoch."""
    T, E = r.shape[:2]
    model.eval()
    with torch.no_grad():
        S = gso(adjacency(r.flatten(0, 1), cfg.R), tcfg.gso).view(T, E, cfg.N, cfg.N)
        X = torch.stack([model.features(stored_images(tcfg.vision, cfg, r, v, torch.arange(E), torch.full((E,), t)))
                         for t in range(T)])  # (T, E, N, F)
        if tcfg.mlp_on_exact:
            X = exact_through_aux(model.cnn, X, r, v, cfg.R)
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
              u: torch.Tensor, gen: torch.Generator, camera=None) -> torch.Tensor:
    """The L1 loss of one joint step on ``tcfg.windows`` windows of K steps drawn from stored flights
    r, v, u* (T, E, N, 2). Every agent's K images of a window go through the CNN, the features
    through the unrolled aggregation (eq. 6), the MLP acts once at the window's last step; calling
    ``backward`` on the result is K-step BPTT. Steps before t = 0 contribute nothing (X = 0, S = 0).
    With ``tcfg.aux_weight`` > 0 the loss adds that times stage 1's state-estimation loss on the
    window's images (``VisualCNN.aux_standardized`` against the standardised exact features).
    ``camera``: what the cameras do to the raw frames (``vision.camera_input``), e.g. noise augmentation."""
    T, E = r.shape[:2]
    K, M = tcfg.K, tcfg.windows
    e = torch.randint(0, E, (M,), generator=gen)
    t_end = sample_times(M, T, tcfg, gen, tcfg.joint_early_share)
    tau = t_end[:, None] - (K - 1) + torch.arange(K)  # (M, K) times of the window
    valid = (tau >= 0).float()[:, :, None, None]
    tau_c, ee = tau.clamp(min=0).flatten(), e[:, None].expand_as(tau).flatten()
    X = model.features(stored_images(tcfg.vision, cfg, r, v, ee, tau_c, camera)).view(M, K, cfg.N, tcfg.F)
    S = gso(adjacency(r[tau_c, ee], cfg.R), tcfg.gso).view(M, K, cfg.N, cfg.N) * valid
    Z = aggregation_sequence(X * valid, S, K)[:, -1]  # Z(t) at the window's last step, (M, N, K, F)
    loss = nnf.l1_loss(model.mlp(Z), u[t_end, e])
    if tcfg.anchor_weight:  # the MLP's response to the same windows read as exact features
        Xa = exact_through_aux(model.cnn, X.detach(), r[tau_c, ee].view(M, K, cfg.N, 2),
                               v[tau_c, ee].view(M, K, cfg.N, 2), cfg.R)
        Za = aggregation_sequence(Xa * valid, S, K)[:, -1]
        loss = loss + tcfg.anchor_weight * nnf.l1_loss(model.mlp(Za), u[t_end, e])
    if tcfg.aux_weight:
        cnn = model.cnn
        target = (local_features(r[tau_c, ee], v[tau_c, ee], cfg.R) - cnn.aux_mean) / cnn.aux_std
        loss = loss + tcfg.aux_weight * nnf.l1_loss(cnn.aux_standardized(X.flatten(0, 2)), target.flatten(0, 1))
    return loss


def joint_round(model: VGAIModel, opt: torch.optim.Optimizer, cfg: FlockConfig, tcfg: VGAITrainConfig,
                store: EpisodeStore, gen: torch.Generator, desc: str, progress: bool = True, camera=None) -> list:
    """``tcfg.joint_steps`` steps of joint K-step BPTT on the stored flights (images through
    ``camera`` when given, see ``bptt_loss``). Returns the losses."""
    r, v, u = store.tensors()
    model.train()
    losses = []
    bar = tqdm(range(tcfg.joint_steps), desc=desc, disable=not progress)
    for _ in bar:
        loss = bptt_loss(model, cfg, tcfg, r, v, u, gen, camera)
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

    # Round 0: the expert flies alone; stages 1 and 2 learn from its flights (their first T steps).
    steps = tcfg.flight_steps or cfg.T
    store.fly(None, cfg, *sample_initial_state(cfg, tcfg.expert_episodes, gen), 0.0, gen, steps)
    r, v, u = (x[:cfg.T] for x in store.tensors())
    history.update(cached_stage1(model.cnn, cfg, tcfg, r, v, gen, progress, stage1_cache))
    history["mlp_loss"] = fit_mlp(model, cfg, tcfg, r, v, u, gen, progress)
    validate("after stages 1-2")

    # Stage 3: each DAgger round adds the learner's own flights, then joint K-step BPTT on all.
    opt = torch.optim.Adam(model.parameters(), lr=tcfg.lr)
    for rnd in range(tcfg.dagger_rounds):
        model.eval()
        p = tcfg.p_learner
        if tcfg.learner_swarms:  # some swarms flown by the learner alone
            alone = torch.rand(tcfg.episodes_per_round, generator=gen) < tcfg.learner_swarms
            p = torch.where(alone, 1.0, tcfg.p_learner)
        store.fly(learner, cfg, *sample_initial_state(cfg, tcfg.episodes_per_round, gen), p, gen, steps)
        history["joint_loss"] += joint_round(model, opt, cfg, tcfg, store, gen, progress=progress,
                                             desc=f"stage 3: joint BPTT, round {rnd + 1}/{tcfg.dagger_rounds}")
        validate(f"DAgger round {rnd + 1}")
    save(finished=True)
    return learner, history

"""Training VGAI, top to bottom: the CNN and the aggregation MLP together, by imitation with DAgger and
K-step BPTT. Its configuration (every knob, with the paper's values) is ``vgai_config.VGAITrainConfig``.

Introduced in notebook 06. Images are rendered on the fly from stored swarm states (no image dataset on disk;
``vision.stored_images``). The paper trains CNN_Psi and NN_Theta jointly end to end, by K-step backpropagation
through time (its figure 3): for a window of K consecutive steps, every agent's K images go through the CNN, the
features travel through the delayed aggregation (eq. 6), the MLP acts once at the last step, and the L1 loss of
eq. 10 against the expert's action flows back through all K CNN passes (``bptt_loss``).

The paper is silent on how long to train and on warm starts. The paper's VGAI (``warm_starts`` False) runs stage 0
and then stage 3 only, from random weights, first on the expert's flights. The book's, in three stages, sized for
two CPU cores (``train_vgai``, at the bottom; each record says how long it took, by phase):
  0. the expert flies ``expert_episodes`` swarms alone (DAgger's round 0, ``imitation.EpisodeStore``);
  1. visual state estimation (``fit_state_estimator``): the CNN, through a linear head, regresses the DAGNN's
     N_LOCAL_FEATURES = 6 exact local features from single agents' images;
  2. ``fit_mlp``: the MLP is fitted on Z(t) built from the (frozen) CNN's features, like the DAGNN;
  3. ``joint_round``: joint K-step BPTT of both on windows (``sample_windows``, ``window_batch``,
     ``bptt_loss``), after each DAgger round has added the learner's own flights.
Loss L1 (eq. 10) and Adam at learning rate 1e-3 (the paper's) in every stage. Randomness: one ``torch.Generator``
seeded with ``tcfg.seed`` (sampling) and the seeded global RNG (the weights).
"""

from __future__ import annotations

import logging
import math
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Optional, Union

import torch
import torch.nn.functional as nnf
from tqdm.auto import tqdm

from .aggregation import aggregation_sequence
from .camera import draw_camera
from .checkpoints import load_controller, save_controller
from .config import FlockConfig
from .features import N_LOCAL_FEATURES, local_features
from .flocking import sample_initial_state
from .graphs import adjacency, gso
from .imitation import EpisodeStore, Flights, fit_l1, flight_groups, round_check
from .learned_controllers import VGAIController
from .models import VGAIModel, VisualCNN
from .vgai_config import VGAITrainConfig
from .vision import camera_input, flown_backwards, positions_before, stored_images

log = logging.getLogger(__name__)


def sample_times(n: int, T: int, tcfg: VGAITrainConfig, g: torch.Generator) -> torch.Tensor:
    """n time steps in [0, T): in the first ``tcfg.early_steps`` with probability ``tcfg.early_share``
    (the expert's labels live early: most of eq. 1 accrues in the first 20 steps), else uniform."""
    early = torch.rand(n, generator=g) < tcfg.early_share
    t_early = torch.randint(0, min(tcfg.early_steps, T), (n,), generator=g)
    t_any = torch.randint(0, T, (n,), generator=g)
    return torch.where(early, t_early, t_any)


@contextmanager
def timed(seconds: Optional[dict], phase: str):
    """Add the ``with`` block's wall-clock seconds to ``seconds[phase]`` (unless None): a history's ``seconds_by_phase``."""
    start = time.perf_counter()
    yield
    if seconds is not None:
        seconds[phase] = seconds.get(phase, 0.0) + time.perf_counter() - start


def pick(flights: list, gen: torch.Generator) -> Flights:
    """One group of stored ``Flights``, each stored episode equally likely (no draw when there is one)."""
    if len(flights) == 1:
        return flights[0]
    episodes = torch.tensor([float(f.r.shape[1]) for f in flights])
    return flights[int(torch.multinomial(episodes, 1, generator=gen))]


def per_team(swarms: int, cfg: FlockConfig, flight: FlockConfig) -> int:
    """``swarms`` swarms of the training's N (``cfg``) as swarms of ``flight``'s: as many drone images."""
    return max(1, swarms * cfg.N // flight.N)


# ---------------------------------------------------------------------------------------------
# Stage 1: visual state estimation (section 3.3; notebook 05)


def feature_scale(flights: list, per_neighbour: bool = False) -> tuple[torch.Tensor, torch.Tensor]:
    """Mean and spread of the 6 exact local features over every agent's stored states (``Flights``): (6,), (6,)."""
    X = torch.cat([local_features(f.r.flatten(0, 1), f.v.flatten(0, 1), f.cfg.R, per_neighbour).flatten(0, 1)
                   for f in flights])
    return X.mean(0), X.std(0).clamp(min=1e-6)


def synthetic_velocities(v: torch.Tensor, speeds: tuple, gen: torch.Generator) -> torch.Tensor:
    """Velocities a swarm could have: its mean velocity plus independent per-agent deviations of a
    scale drawn log-uniformly in ``speeds`` = (low, high) m/s, one scale per swarm. v (M, N, 2) -> (M, N, 2)."""
    lo, hi = speeds
    scale = torch.empty(v.shape[0], 1, 1).uniform_(math.log(lo), math.log(hi), generator=gen).exp()
    return v.mean(1, keepdim=True) + scale * torch.randn(v.shape, generator=gen)


def estimation_batch(cfg: FlockConfig, tcfg: VGAITrainConfig, r: torch.Tensor, v: torch.Tensor,
                     gen: torch.Generator, states: Optional[int] = None) -> tuple[torch.Tensor, torch.Tensor]:
    """``states`` (default ``tcfg.warm_states``) stored swarm states of flights r, v (T, E, N, 2) of ``cfg``: every agent's image
    (M, N, C, H, W) and its exact local features (M, N, 6), seen through cameras drawn from
    ``tcfg.camera``. A ``tcfg.synthetic_share`` of them is shown with synthetic velocities (the motion
    frame drawn from the state flown backwards at them)."""
    T, E = r.shape[:2]
    vision, states = tcfg.vision, states or tcfg.warm_states
    e = torch.randint(0, E, (states,), generator=gen)
    t = sample_times(states, T, tcfg, gen)
    cam = draw_camera(tcfg.camera, vision.render, states, cfg.N, gen)
    camera = cam.at(0) if cam is not None else None
    if tcfg.synthetic_share <= 0:
        return stored_images(vision, cfg, r, v, e, t, camera), local_features(r[t, e], v[t, e], cfg.R, tcfg.feature_means)
    synth = (torch.rand(states, generator=gen) < tcfg.synthetic_share)[:, None, None]
    vs = torch.where(synth, synthetic_velocities(v[t, e], tcfg.synthetic_speeds, gen), v[t, e])
    before = torch.where(synth, flown_backwards(r[t, e], vs, vision.motion_gap, cfg.Ts),
                         positions_before(vision, cfg, r, v, e, t))
    return camera_input(vision, cfg, r[t, e], before, camera), local_features(r[t, e], vs, cfg.R, tcfg.feature_means)


def estimation_loss(cnn: VisualCNN, X: torch.Tensor, x_exact: torch.Tensor) -> torch.Tensor:
    """The state-estimation loss: L1 between the aux head's reading of the CNN's features X (..., F)
    and the standardised exact local features x_exact (..., 6)."""
    target = (x_exact - cnn.aux_mean) / cnn.aux_std
    return nnf.l1_loss(cnn.aux_standardized(X.reshape(-1, cnn.F)), target.reshape(-1, N_LOCAL_FEATURES))


def fit_state_estimator(cnn: VisualCNN, cfg: FlockConfig, tcfg: VGAITrainConfig, flights: list,
                        gen: torch.Generator, progress: bool = True) -> list:
    """Stage 1: train the CNN (through its ``aux`` head) to regress the standardised exact local
    features of every agent from its own images (``tcfg.vision``), on stored flights (a list of
    ``imitation.Flights``, e.g. ``EpisodeStore.groups()``) of a training in ``cfg``: ``tcfg.warm_steps``
    Adam steps on ``estimation_batch``, each of one group (``pick``). Returns the L1 loss per step."""
    x_mean, x_std = feature_scale(flights, tcfg.feature_means)
    if cnn.motion_features:  # the odd velocity estimates are 0 when nothing moves, so is their offset
        x_mean[:2] = 0.0
    cnn.aux_mean.copy_(x_mean), cnn.aux_std.copy_(x_std)
    opt = torch.optim.Adam(cnn.parameters(), lr=tcfg.lr)
    cnn.train()
    losses = []
    for _ in tqdm(range(tcfg.warm_steps), desc="stage 1: visual state estimation", disable=not progress):
        f = pick(flights, gen)
        img, x_exact = estimation_batch(f.cfg, tcfg, f.r, f.v, gen, per_team(tcfg.warm_states, cfg, f.cfg))
        loss = estimation_loss(cnn, cnn(img.flatten(0, 1)), x_exact)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        losses.append(loss.item())
    cnn.eval()
    return losses


def fit_stage1(cnn: VisualCNN, cfg: FlockConfig, tcfg: VGAITrainConfig, flights: list, gen: torch.Generator,
               progress: bool = True) -> dict:
    """Stage 1 as ``train_vgai`` runs it: ``fit_state_estimator``, timed. Returns its history entries.
    (A caller may pass ``train_vgai`` another function of this signature, e.g. one that reads a stage 1
    trained before: ``vgai_lite.lab.stage1_cache``.)"""
    start = time.perf_counter()
    losses = fit_state_estimator(cnn, cfg, tcfg, flights, gen, progress)
    return {"warm_loss": losses, "stage1_seconds": time.perf_counter() - start}


# ---------------------------------------------------------------------------------------------
# Stage 2: the MLP on the frozen CNN's features


def fit_mlp(model: VGAIModel, tcfg: VGAITrainConfig, flights: list, gen: torch.Generator, progress: bool = True) -> list:
    """Fit NN_Theta on Z(t) built from the frozen CNN's features along stored flights (``imitation.Flights``),
    like the DAGNN on its exact features, each flight seen through cameras drawn from ``tcfg.camera``.
    Returns the mean L1 loss per epoch."""
    model.eval()
    rows = [mlp_rows(model, f, tcfg, gen) for f in flights]
    Zr, Ur = torch.cat([z for z, _ in rows]), torch.cat([u for _, u in rows])
    model.mlp.set_normalization(Zr)
    opt = torch.optim.Adam(model.mlp.parameters(), lr=tcfg.lr)
    return fit_l1(model.mlp, Zr, Ur, opt, tcfg.mlp_epochs, tcfg.mlp_batch, gen,
                  desc="stage 2: MLP on CNN features", progress=progress)


def mlp_from_dagnn(model: VGAIModel, tcfg: VGAITrainConfig) -> list:
    """Stage 2 with ``tcfg.mlp_start`` a DAGNN: NN_Theta starts as that DAGNN's MLP (weights and normalisation), which reads
    the 6 local features the "local" readout estimates (sums; with ``feature_means``, a "per_neighbour" DAGNN's means). Fits nothing: []."""
    d, reads = load_controller(tcfg.mlp_start), "per_neighbour" if tcfg.feature_means else "none"
    want, got = (tcfg.K, list(tcfg.hidden), tcfg.gso, reads), (d.K, list(d.model.hidden), d.gso_kind, d.feature_transform)
    if want != got:
        raise ValueError(f"{tcfg.mlp_start}: expected a DAGNN of (K, hidden, GSO, feature transform) {want}, got {got}")
    model.mlp.load_state_dict(d.model.state_dict())
    return []


@torch.no_grad()
def mlp_rows(model: VGAIModel, flights: Flights, tcfg: VGAITrainConfig, gen: torch.Generator) -> tuple:
    """Stage 2's rows of one group of flights: Z (rows, K, F) from the frozen CNN and the expert's U* (rows, 2);
    every early step, 1 in ``tcfg.mlp_late_stride`` after."""
    cfg, r, v, u = flights
    T, E = r.shape[:2]
    cam = draw_camera(tcfg.camera, tcfg.vision.render, E, cfg.N, gen)
    S = gso(adjacency(r.flatten(0, 1), cfg.R), tcfg.gso).view(T, E, cfg.N, cfg.N)
    X = torch.stack([model.features(stored_images(tcfg.vision, cfg, r, v, torch.arange(E), torch.full((E,), t),
                                                  cam.at(t) if cam is not None else None))
                     for t in range(T)])  # (T, E, N, F)
    Z = aggregation_sequence(X.transpose(0, 1), S.transpose(0, 1), tcfg.K)  # (E, T, N, K, F)
    early = min(tcfg.early_steps, T)
    keep_t = torch.cat((torch.arange(early), torch.arange(early, T, tcfg.mlp_late_stride)))
    return Z[:, keep_t].reshape(-1, tcfg.K, model.mlp.F), u.transpose(0, 1)[:, keep_t].reshape(-1, 2)


# ---------------------------------------------------------------------------------------------
# Stage 3: joint K-step BPTT (the paper's figure 3)


def bptt_loss(model, images: torch.Tensor, S: torch.Tensor, u_star: torch.Tensor,
              valid: Optional[torch.Tensor] = None, also: Optional[Callable] = None) -> torch.Tensor:
    """Eq. 10 through the paper's figure 3: the L1 imitation loss of M windows of K steps.

    images (M, K, N, ...): every agent's CNN input at the window's K steps, oldest first;
    S (M, K, N, N): the GSOs at those steps; u_star (M, N, 2): the expert's action at each window's
    last step; valid (M, K), optional: False at steps before the flight began, which contribute
    nothing (their X and S are 0). ``model`` has ``cnn`` (inputs (P, ...) -> features (P, F)) and
    ``mlp`` (Z (M, N, K, F) -> actions (M, N, 2)); a ``VGAIModel``'s ``read`` sits between them.

        X(tau) = CNN_Psi(H(tau))  at every step of the window,
        Z(t)   = [X(t), S(t) X(t-1), ..., S(t)...S(t-K+2) X(t-K+1)]   (eq. 6, unrolled),
        loss   = mean |NN_Theta(Z(t)) - u*(t)|                          (eq. 10).

    ``loss.backward()`` is K-step BPTT: through the MLP once and through the CNN at all K steps.
    ``also(X)``, optional: a term of the same features X (M, K, N, F) added to the loss, so that the
    CNN runs once for both (the book's recipe adds stage 1's state-estimation loss, ``joint_loss``)."""
    X = window_features(model.cnn, images)
    loss = window_action_loss(model.mlp, model.read(X) if isinstance(model, VGAIModel) else X, S, u_star, valid)
    return loss if also is None else loss + also(X)


def window_features(cnn, images: torch.Tensor) -> torch.Tensor:
    """X = CNN_Psi(H) at every step of every window: images (M, K, N, ...) -> (M, K, N, F)."""
    M, K, N = images.shape[:3]
    return cnn(images.flatten(0, 2)).view(M, K, N, -1)


def window_action_loss(mlp, X: torch.Tensor, S: torch.Tensor, u_star: torch.Tensor,
                       valid: Optional[torch.Tensor] = None) -> torch.Tensor:
    """The second half of ``bptt_loss``, from the windows' features X (M, K, N, F) on."""
    K = X.shape[1]
    if valid is not None:
        mask = valid.to(X.dtype)[:, :, None, None]
        X, S = X * mask, S * mask
    return nnf.l1_loss(mlp(aggregation_sequence(X, S, K)[:, -1]), u_star)


def sample_windows(T: int, E: int, tcfg: VGAITrainConfig, gen: torch.Generator,
                   windows: Optional[int] = None) -> tuple[torch.Tensor, torch.Tensor]:
    """``windows`` (default ``tcfg.windows``) windows of stored flights (E episodes of T steps): each window's
    episode e and last step t_end, (M,) each; the last steps drawn by ``sample_times``."""
    M = windows or tcfg.windows
    e = torch.randint(0, E, (M,), generator=gen)
    return e, sample_times(M, T, tcfg, gen)


def window_batch(cfg: FlockConfig, tcfg: VGAITrainConfig, r: torch.Tensor, v: torch.Tensor, u: torch.Tensor,
                 e: torch.Tensor, t_end: torch.Tensor, camera=None) -> dict:
    """What ``bptt_loss`` needs of the windows (e, t_end) of stored flights r, v, u* (T, E, N, 2):
    ``images`` (M, K, N, C, H, W), ``S`` (M, K, N, N), ``u_star`` (M, N, 2), ``valid`` (M, K), and
    the exact local features at every step, ``x_exact`` (M, K, N, 6). Steps before t = 0 are
    rendered at t = 0 and marked invalid. ``camera``: what the cameras do to the raw frames
    (``vision.camera_input``)."""
    M, K = len(e), tcfg.K
    tau = t_end[:, None] - (K - 1) + torch.arange(K)  # (M, K) times of the window
    tau_c, ee = tau.clamp(min=0).flatten(), e[:, None].expand_as(tau).flatten()
    images = stored_images(tcfg.vision, cfg, r, v, ee, tau_c, camera)
    return {"images": images.view(M, K, *images.shape[1:]),
            "S": gso(adjacency(r[tau_c, ee], cfg.R), tcfg.gso).view(M, K, cfg.N, cfg.N),
            "u_star": u[t_end, e], "valid": tau >= 0,
            "x_exact": local_features(r[tau_c, ee], v[tau_c, ee], cfg.R, tcfg.feature_means).view(M, K, cfg.N, N_LOCAL_FEATURES)}


def joint_loss(model: VGAIModel, tcfg: VGAITrainConfig, w: dict) -> torch.Tensor:
    """The loss of one joint step on a ``window_batch`` w: ``bptt_loss`` (eq. 10), plus, with
    ``tcfg.aux_weight`` > 0, that times stage 1's ``estimation_loss`` on the same images' features (so
    that joint training keeps the CNN's features readable as the local features; the book's recipe)."""
    also = (lambda X: tcfg.aux_weight * estimation_loss(model.cnn, X, w["x_exact"])) if tcfg.aux_weight else None
    return bptt_loss(model, w["images"], w["S"], w["u_star"], w["valid"], also)


def joint_round(model: VGAIModel, opt: torch.optim.Optimizer, cfg: FlockConfig, tcfg: VGAITrainConfig,
                store: EpisodeStore, gen: torch.Generator, desc: str, progress: bool = True, camera=None,
                seconds: Optional[dict] = None) -> list:
    """``tcfg.joint_steps`` steps of joint K-step BPTT on the stored flights, each window seen through
    cameras drawn from ``tcfg.camera`` (or through ``camera(frame, lag)`` when given); each step's windows
    from one group of flights (``pick``, ``per_team``). Returns the losses; ``seconds`` gains the phases' times (``timed``)."""
    flights = store.groups()
    model.train()
    losses = []
    bar = tqdm(range(tcfg.joint_steps), desc=desc, disable=not progress)
    for _ in bar:
        f = pick(flights, gen)
        M = per_team(tcfg.windows, cfg, f.cfg)
        e, t_end = sample_windows(f.r.shape[0], f.r.shape[1], tcfg, gen, M)
        seen = camera
        if seen is None:
            cam = draw_camera(tcfg.camera, tcfg.vision.render, M, f.cfg.N, gen)
            seen = cam.repeat(tcfg.K).at(0) if cam is not None else None
        with timed(seconds, "stage 3: rendering the windows"):
            w = window_batch(f.cfg, tcfg, f.r, f.v, f.u, e, t_end, seen)
        with timed(seconds, "stage 3: forward (CNN, aggregation, MLP)"):
            loss = joint_loss(model, tcfg, w)
        with timed(seconds, "stage 3: backward and Adam step"):
            opt.zero_grad(set_to_none=True)
            loss.backward()  # through the MLP once and the CNN K times (K-step BPTT)
            opt.step()
        losses.append(loss.item())
        bar.set_postfix(loss=f"{loss.item():.2f}")
    model.eval()
    return losses


def dagger_round(learner: VGAIController, store: EpisodeStore, cfg: FlockConfig, tcfg: VGAITrainConfig,
                 gen: torch.Generator) -> None:
    """One DAgger round's flights, added to ``store``: ``tcfg.episodes_per_round`` swarms (in the groups of
    ``flight_groups``), a ``tcfg.learner_swarms`` share of them flown by the learner alone (p = 1), the
    others under the paper's mixture (the learner followed with probability ``tcfg.p_learner`` at each
    step). The learner sees through cameras drawn from ``tcfg.camera``, one per swarm for its whole flight."""
    learner.model.eval()
    try:
        for flight, swarms in flight_groups(cfg, tcfg, tcfg.episodes_per_round, gen):
            p = tcfg.p_learner
            if tcfg.learner_swarms:
                alone = torch.rand(swarms, generator=gen) < tcfg.learner_swarms
                p = torch.where(alone, 1.0, tcfg.p_learner)
            learner.cfg = flight  # the GSO of this group's radius
            learner.camera = draw_camera(tcfg.camera, tcfg.vision.render, swarms, flight.N, gen)
            store.fly(learner, flight, *sample_initial_state(flight, swarms, gen), p, gen)
    finally:
        learner.cfg, learner.camera = cfg, None  # the controller a training returns sees the renderer's frames


# ---------------------------------------------------------------------------------------------
# The three stages together


def train_vgai(cfg: FlockConfig, tcfg: VGAITrainConfig = VGAITrainConfig(),
               checkpoint: Optional[Union[str, Path]] = None, progress: bool = True,
               check_episodes: int = 10, stage1: Callable = fit_stage1) -> tuple[VGAIController, dict]:
    """Train VGAI in the three stages of the module docstring; save to ``checkpoint`` as it goes. ``stage1``
    runs stage 1 (``fit_stage1``'s signature; ``lab.stage1_cache`` reads one trained before). Returns the
    controller and its history: each stage's losses, the round checks (``imitation.round_check`` on
    ``check_episodes``) and ``seconds_by_phase``. The global torch RNG is left as it was."""
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(tcfg.seed)  # the weights' initialisation
        gen = torch.Generator().manual_seed(tcfg.seed)  # every draw of the training
        model = tcfg.new_model()
        learner = VGAIController(model, cfg, tcfg.vision, tcfg.gso)
        seconds = {}  # where the minutes go (``timed``)
        history = {"warm_loss": [], "mlp_loss": [], "joint_loss": [], "rounds": [], "seconds_by_phase": seconds}
        start = time.perf_counter()

        def save(finished: bool = False) -> None:
            history["seconds"] = time.perf_counter() - start
            learner.meta = {"train_config": tcfg.to_dict(), "history": history, "finished": finished}
            if checkpoint is not None:
                save_controller(checkpoint, learner, meta=learner.meta)

        def check(stage: str) -> None:
            model.eval()
            with timed(seconds, "round checks (flights of the learner)"):
                result = round_check(learner, cfg, check_episodes, tcfg.seed)
            history["rounds"].append({"stage": stage, "episodes": store.episodes, **result, "seconds": time.perf_counter() - start})
            log.info("%s: round-check relative cost %.2f after %.0f s", stage,
                     history["rounds"][-1]["check_relative_cost"], time.perf_counter() - start)
            save()

        # Round 0: the expert flies alone; the warm starts (stages 1 and 2) learn from its flights,
        # or, as in the paper, joint K-step BPTT from random weights.
        store = EpisodeStore()
        with timed(seconds, "round 0: the expert's flights"):
            for flight, swarms in flight_groups(cfg, tcfg, tcfg.expert_episodes, gen):
                store.fly(None, flight, *sample_initial_state(flight, swarms, gen), 0.0, gen)
        opt = torch.optim.Adam(model.parameters() if tcfg.joint_mlp else model.cnn.parameters(), lr=tcfg.lr)
        if tcfg.warm_starts:
            with timed(seconds, "stage 1: state estimation"):
                history.update(stage1(model.cnn, cfg, tcfg, store.groups(), gen, progress))
            with timed(seconds, "stage 2: the MLP on the CNN's features"):
                history["mlp_loss"] = (fit_mlp(model, tcfg, store.groups(), gen, progress) if tcfg.mlp_start == "fit"
                                       else mlp_from_dagnn(model, tcfg))
            check("after stages 1-2")
        else:
            history["joint_loss"] += joint_round(model, opt, cfg, tcfg, store, gen, progress=progress,
                                                 desc="stage 3: joint BPTT on the expert's flights", seconds=seconds)
            check("after joint training on the expert's flights")

        # Stage 3: each DAgger round adds the learner's own flights, then joint K-step BPTT on all.
        for rnd in range(tcfg.dagger_rounds):
            with timed(seconds, "DAgger flights (rendering, CNN, physics)"):
                dagger_round(learner, store, cfg, tcfg, gen)
            history["joint_loss"] += joint_round(model, opt, cfg, tcfg, store, gen, progress=progress, seconds=seconds,
                                                 desc=f"stage 3: joint BPTT, round {rnd + 1}/{tcfg.dagger_rounds}")
            check(f"DAgger round {rnd + 1}")
        save(finished=True)
        return learner, history

"""Training VGAI: the CNN and the aggregation MLP together, by imitation with DAgger and K-step BPTT.

Introduced in notebook 06. Images are rendered on the fly from stored swarm states (no image dataset
on disk). The paper trains CNN_Psi and NN_Theta jointly end to end, by K-step backpropagation through
time (its figure 3): for a window of K consecutive steps, every agent's K images go through the CNN,
the features travel through the delayed aggregation (eq. 6), the MLP acts once at the last step, and
the L1 loss against the expert's action flows back through all K CNN passes.

The paper is silent on how long to train and on warm starts. Ours, in three stages, to train in
minutes on two CPU cores:
  1. visual state estimation: the CNN (through a linear head) regresses the DAGNN's 6 exact local
     features from single agents' images;
  2. the MLP is fitted on Z(t) built from the (frozen) CNN's features, like the DAGNN;
  3. joint K-step BPTT of both on windows, with DAgger rounds (learner followed with probability
     0.33) adding the learner's own states.
Loss L1 (eq. 11) and Adam at learning rate 1e-3 (the paper's) in every stage.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Union

import torch
import torch.nn.functional as nnf
from tqdm.auto import tqdm

from .aggregation import aggregation_sequence
from .checkpoints import save_controller
from .config import FlockConfig
from .controllers import expert_control
from .evaluate import relative_cost
from .features import local_features
from .flocking import sample_initial_state, saturate, step
from .graphs import DEFAULT_GSO, adjacency, gso
from .imitation import VALIDATION_SEED_OFFSET
from .models import AggregationMLP, VGAIController, VGAIModel, VisionConfig, VisualCNN


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

    def to_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["hidden"], d["cnn_widths"] = list(self.hidden), list(self.cnn_widths)
        d["vision"] = self.vision.to_dict()
        return d


@dataclass
class EpisodeStore:
    """Stored swarm trajectories: r, v, u* (the expert's action), each (T, E, N, 2)."""

    r: list = field(default_factory=list)
    v: list = field(default_factory=list)
    u: list = field(default_factory=list)

    def add(self, r, v, u):
        self.r.append(r), self.v.append(v), self.u.append(u)

    def tensors(self):
        return torch.cat(self.r, 1), torch.cat(self.v, 1), torch.cat(self.u, 1)

    @property
    def episodes(self) -> int:
        return sum(x.shape[1] for x in self.r)


@torch.no_grad()
def collect_episodes(learner: Optional[VGAIController], cfg: FlockConfig, r0, v0, p_learner: float,
                     generator: torch.Generator):
    """Fly (r0, v0) under the DAgger mixture (learner with probability p_learner per swarm and step,
    else the expert) and return r, v, u* of every step, (T, B, N, 2) each."""
    if learner is not None:
        learner.reset()
    r, v = r0, v0
    rs, vs, us = [], [], []
    for _ in range(cfg.T):
        u_star = expert_control(r, v, cfg)
        u = u_star
        if learner is not None and p_learner > 0:
            u_l = learner(r, v)  # the learner must act every step to keep its buffers current
            follow = torch.rand(r.shape[0], generator=generator) < p_learner
            u = torch.where(follow[:, None, None], u_l, u_star)
        rs.append(r), vs.append(v), us.append(u_star)
        r, v = step(r, v, saturate(u, cfg), cfg)
    return torch.stack(rs), torch.stack(vs), torch.stack(us)


def _sample_times(n: int, T: int, tcfg: VGAITrainConfig, g: torch.Generator) -> torch.Tensor:
    early = torch.rand(n, generator=g) < tcfg.early_share
    t_early = torch.randint(0, min(tcfg.early_steps, T), (n,), generator=g)
    t_any = torch.randint(0, T, (n,), generator=g)
    return torch.where(early, t_early, t_any)


def _images(vision: VisionConfig, cfg: FlockConfig, r: torch.Tensor, v: torch.Tensor, e: torch.Tensor,
            t: torch.Tensor) -> torch.Tensor:
    """CNN inputs of every agent at stored states (e, t): (M, N, C, H, W), motion frame at t - g
    (before t = 0: the initial state flown backwards, if vision.prehistory; else the first frame)."""
    now = vision.frame(r[t, e], cfg)
    if vision.motion_gap == 0:
        return now
    t_prev = t - vision.motion_gap
    r_prev = r[t_prev.clamp(min=0), e]
    if vision.prehistory:
        back = (t_prev.clamp(max=0) * cfg.Ts).to(r.dtype)[:, None, None]  # <= 0: seconds before t = 0
        r_prev = torch.where((t_prev < 0)[:, None, None], r[0, e] + back * v[0, e], r_prev)
    return vision.combine(now, vision.frame(r_prev, cfg))


def feature_scale(cfg: FlockConfig, r: torch.Tensor, v: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Mean and spread of the 6 exact local features over stored states r, v (T, E, N, 2)."""
    X = local_features(r.flatten(0, 1), v.flatten(0, 1), cfg.R)
    return X.mean((0, 1)), X.std((0, 1)).clamp(min=1e-6)


def fit_state_estimator(cnn: VisualCNN, vision: VisionConfig, cfg: FlockConfig, r: torch.Tensor,
                        v: torch.Tensor, steps: int, states: int, tcfg: VGAITrainConfig,
                        gen: torch.Generator, progress: bool = True) -> list:
    """Visual state estimation: train the CNN (through its ``aux`` head) to regress the standardised
    exact local features of every agent from its own images, on stored states r, v (T, E, N, 2).
    Each step draws ``states`` swarm states (all N agents' images). Returns the L1 loss per step."""
    T, E = r.shape[:2]
    x_mean, x_std = feature_scale(cfg, r, v)
    cnn.aux_mean.copy_(x_mean), cnn.aux_std.copy_(x_std)
    opt = torch.optim.Adam(cnn.parameters(), lr=tcfg.lr)
    cnn.train()
    losses = []
    for _ in tqdm(range(steps), desc="visual state estimation", disable=not progress):
        e = torch.randint(0, E, (states,), generator=gen)
        t = _sample_times(states, T, tcfg, gen)
        img = _images(vision, cfg, r, v, e, t)
        target = (local_features(r[t, e], v[t, e], cfg.R) - x_mean) / x_std
        loss = nnf.l1_loss(cnn.aux(cnn(img.flatten(0, 1))), target.flatten(0, 1))
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        losses.append(loss.item())
    cnn.eval()
    return losses


@torch.no_grad()
def estimator_quality(cnn: VisualCNN, vision: VisionConfig, cfg: FlockConfig, episodes: int = 8,
                      times=(2, 8, 20, 60), seed: int = 2020) -> dict:
    """Correlation between the CNN's estimate (aux head) and the exact local features, per feature,
    at a few time steps of expert flights from held-out initial conditions: {t: [6 values]}."""
    from .controllers import ExpertController
    from .flocking import rollout

    r0, v0 = sample_initial_state(cfg, episodes, torch.Generator().manual_seed(seed))
    traj = rollout(ExpertController(cfg), cfg, r0, v0)
    out = {}
    for t in times:
        e, tt = torch.arange(episodes), torch.full((episodes,), t)
        pred = cnn.aux(cnn(_images(vision, cfg, traj.r, traj.v, e, tt).flatten(0, 1)))
        X = local_features(traj.r[t], traj.v[t], cfg.R).flatten(0, 1)
        out[t] = [torch.corrcoef(torch.stack((pred[:, k], X[:, k])))[0, 1].item() for k in range(6)]
    return out


def window_loss(model: VGAIModel, vision: VisionConfig, cfg: FlockConfig, tcfg: VGAITrainConfig,
                r: torch.Tensor, v: torch.Tensor, u: torch.Tensor, gen: torch.Generator) -> torch.Tensor:
    """The L1 loss of one joint step: ``tcfg.windows`` windows of K steps drawn from stored flights
    r, v, u* (T, E, N, 2). Every agent's K images of a window go through the CNN, the features
    through the unrolled aggregation (eq. 6), the MLP acts once at the window's last step; calling
    ``backward`` on the result is K-step BPTT."""
    T, E = r.shape[:2]
    K = tcfg.K
    e = torch.randint(0, E, (tcfg.windows,), generator=gen)
    t_end = _sample_times(tcfg.windows, T, tcfg, gen)
    tau = t_end[:, None] - (K - 1) + torch.arange(K)  # (windows, K) times of the window
    valid = (tau >= 0).float()
    tau_c = tau.clamp(min=0)
    ee = e[:, None].expand_as(tau)
    img = _images(vision, cfg, r, v, ee.flatten(), tau_c.flatten())  # (windows K, N, C, H, W)
    Xw = model.cnn(img.flatten(0, 1)).view(tcfg.windows, K, cfg.N, tcfg.F) * valid[:, :, None, None]
    Sw = gso(adjacency(r[tau_c.flatten(), ee.flatten()], cfg.R), tcfg.gso).view(tcfg.windows, K, cfg.N, cfg.N)
    Sw = Sw * valid[:, :, None, None]
    Zw = aggregation_sequence(Xw, Sw, K)[:, -1]  # Z at the window's last step, (windows, N, K, F)
    return nnf.l1_loss(model.mlp(Zw), u[t_end, e])


STAGE1_FORMAT = "vgai-lite-stage1/1"

STAGE1_FIELDS = ("F", "cnn_widths", "cnn_hidden", "vision", "expert_episodes", "warm_steps", "warm_states",
                 "lr", "early_steps", "early_share", "seed")
"""The fields of VGAITrainConfig that stage 1 depends on (K, the MLP and the DAgger schedule do not
enter it): runs that agree on these and on the FlockConfig train the very same stage-1 CNN."""


def stage1_identity(cfg: FlockConfig, tcfg: VGAITrainConfig) -> dict:
    t = tcfg.to_dict()
    return {"format": STAGE1_FORMAT, "config": cfg.to_dict(), "train": {k: t[k] for k in STAGE1_FIELDS}}


def stage1_cache_file(folder: Union[str, Path], cfg: FlockConfig, tcfg: VGAITrainConfig) -> Path:
    """Where stage 1 of (cfg, tcfg) is cached in ``folder``: a hash of :func:`stage1_identity`."""
    key = hashlib.sha1(json.dumps(stage1_identity(cfg, tcfg), sort_keys=True).encode()).hexdigest()[:12]
    return Path(folder) / f"stage1_F{tcfg.F}_{key}.pt"


def _save_stage1(path: Path, cnn: VisualCNN, gen: torch.Generator, history: dict, cfg, tcfg) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    payload = {"identity_json": json.dumps(stage1_identity(cfg, tcfg), sort_keys=True),
               "state_dict": {k: t.detach().cpu() for k, t in cnn.state_dict().items()},
               "generator": gen.get_state(), "warm_loss": history["warm_loss"],
               "seconds": history["stage1_seconds"]}
    tmp = path.with_suffix(".tmp")
    torch.save(payload, tmp)
    tmp.replace(path)


def _load_stage1(path: Path, cnn: VisualCNN, gen: torch.Generator, history: dict) -> None:
    """Restore a cached stage 1: the CNN's weights and the sampling generator's state at its end,
    so that the rest of the training is the same as if stage 1 had run here."""
    payload = torch.load(path, map_location="cpu", weights_only=True)
    cnn.load_state_dict(payload["state_dict"])
    cnn.eval()
    gen.set_state(payload["generator"])
    history["warm_loss"] = list(payload["warm_loss"])
    history["stage1_seconds"] = float(payload["seconds"])
    history["stage1_cached"] = path.name


def train_vgai(cfg: FlockConfig, tcfg: VGAITrainConfig = VGAITrainConfig(),
               checkpoint: Optional[Union[str, Path]] = None, progress: bool = True,
               validation_episodes: int = 10, stage1_cache: Optional[Union[str, Path]] = None
               ) -> tuple[VGAIController, dict]:
    """Train VGAI in the three stages of the module docstring; save to ``checkpoint`` as it goes.

    ``stage1_cache``: a folder where the CNN at the end of stage 1 is kept, keyed by what stage 1
    depends on (:data:`STAGE1_FIELDS`); a run that finds its stage 1 there skips it and continues
    exactly as if it had trained it (the K = 2, 3, 4 runs of Table 1b share one). The history then
    says ``stage1_cached`` and keeps the seconds the cached stage 1 took when it was trained.

    Returns the controller and its history: per stage the losses, and per DAgger round the
    validation relative cost (seed + 1000) with the seconds elapsed.
    """
    torch.manual_seed(tcfg.seed)
    gen = torch.Generator().manual_seed(tcfg.seed)
    vision = tcfg.vision
    C, H, W = vision.image_shape(cfg)
    cnn = VisualCNN(C, H, W, tcfg.F, tcfg.cnn_widths, tcfg.cnn_hidden)
    model = VGAIModel(cnn, AggregationMLP(tcfg.K, tcfg.F, tcfg.hidden))
    learner = VGAIController(model, cfg, vision, tcfg.gso)
    history = {"warm_loss": [], "mlp_loss": [], "joint_loss": [], "rounds": []}
    start = time.perf_counter()

    def save(finished=False):
        if checkpoint is not None:
            history["seconds"] = time.perf_counter() - start
            save_controller(checkpoint, learner, meta={"train_config": tcfg.to_dict(), "history": history,
                                                       "finished": finished})

    def validate(stage):
        model.eval()
        val = relative_cost(learner, cfg, episodes=validation_episodes, seed=tcfg.seed + VALIDATION_SEED_OFFSET)
        history["rounds"].append({"stage": stage, "episodes": store.episodes,
                                  "val_relative_cost": val.mean_ratio,
                                  "val_share_below_0.05m": val.safety.share_below(0.05),
                                  "seconds": time.perf_counter() - start})
        save()
        return val.mean_ratio

    # Round 0: the expert flies alone.
    store = EpisodeStore()
    r0, v0 = sample_initial_state(cfg, tcfg.expert_episodes, gen)
    store.add(*collect_episodes(None, cfg, r0, v0, 0.0, gen))

    # Stage 1: visual state estimation (the CNN regresses the exact local features).
    r, v, u = store.tensors()
    T, E = r.shape[:2]
    stage1_start = time.perf_counter()
    cached = stage1_cache_file(stage1_cache, cfg, tcfg) if stage1_cache is not None else None
    if cached is not None and cached.is_file():
        _load_stage1(cached, cnn, gen, history)
    else:
        history["warm_loss"] = fit_state_estimator(cnn, vision, cfg, r, v, tcfg.warm_steps, tcfg.warm_states,
                                                   tcfg, gen, progress)
        history["stage1_seconds"] = time.perf_counter() - stage1_start
        if cached is not None:
            _save_stage1(cached, cnn, gen, history, cfg, tcfg)

    # Stage 2: the MLP on Z(t) built from the frozen CNN's features, like the DAGNN.
    model.eval()
    with torch.no_grad():
        S = gso(adjacency(r.flatten(0, 1), cfg.R), tcfg.gso).view(T, E, cfg.N, cfg.N)
        X = torch.stack([cnn(_images(vision, cfg, r, v, torch.arange(E), torch.full((E,), t)).flatten(0, 1))
                         .view(E, cfg.N, -1) for t in range(T)])  # (T, E, N, F)
        Z = aggregation_sequence(X.transpose(0, 1), S.transpose(0, 1), tcfg.K)  # (E, T, N, K, F)
    early = min(tcfg.early_steps, T)
    keep_t = torch.cat((torch.arange(early), torch.arange(early, T, 4)))  # every early step, 1 in 4 later
    Zr = Z[:, keep_t].reshape(-1, tcfg.K, tcfg.F)
    Ur = u.transpose(0, 1)[:, keep_t].reshape(-1, 2)
    model.mlp.set_normalization(Zr)
    opt_mlp = torch.optim.Adam(model.mlp.parameters(), lr=tcfg.lr)
    model.train()
    for _ in tqdm(range(tcfg.mlp_epochs), desc="stage 2: MLP on CNN features", disable=not progress):
        perm = torch.randperm(len(Ur), generator=gen)
        total = 0.0
        for i in range(0, len(perm), 1024):
            idx = perm[i:i + 1024]
            loss = nnf.l1_loss(model.mlp(Zr[idx]), Ur[idx])
            opt_mlp.zero_grad(set_to_none=True)
            loss.backward()
            opt_mlp.step()
            total += loss.item() * len(idx)
        history["mlp_loss"].append(total / len(perm))
    del Z, Zr, X, S
    validate("after stages 1-2")

    # Stage 3: joint K-step BPTT, with DAgger rounds.
    opt = torch.optim.Adam(model.parameters(), lr=tcfg.lr)
    for rnd in range(tcfg.dagger_rounds):
        model.eval()
        r0, v0 = sample_initial_state(cfg, tcfg.episodes_per_round, gen)
        store.add(*collect_episodes(learner, cfg, r0, v0, tcfg.p_learner, gen))
        r, v, u = store.tensors()
        T, E = r.shape[:2]
        model.train()
        bar = tqdm(range(tcfg.joint_steps), desc=f"stage 3: joint BPTT, round {rnd + 1}/{tcfg.dagger_rounds}",
                   disable=not progress)
        for _ in bar:
            loss = window_loss(model, vision, cfg, tcfg, r, v, u, gen)
            opt.zero_grad(set_to_none=True)
            loss.backward()  # through the MLP once and the CNN K times (K-step BPTT)
            opt.step()
            history["joint_loss"].append(loss.item())
            bar.set_postfix(loss=f"{loss.item():.2f}")
        cost = validate(f"DAgger round {rnd + 1}")
        if progress:
            print(f"round {rnd + 1}: validation relative cost {cost:.2f} after {time.perf_counter() - start:.0f} s")
    model.eval()
    history["seconds"] = time.perf_counter() - start
    save(finished=True)
    learner.meta = {"train_config": tcfg.to_dict(), "history": history, "finished": True}
    return learner, history


# ---------------------------------------------------------------------------------------------
# Stand-alone visual state estimators (notebook 05): single frame versus two frames

ESTIMATOR_FORMAT = "vgai-lite-estimator/1"

ESTIMATOR_RUNS: dict[str, VisionConfig] = {
    "estimator_motion": VisionConfig(),                 # [I(t), 5 (I(t) - I(t-5))]
    "estimator_single": VisionConfig(motion_gap=0),     # I(t) only
}
"""The state estimators the book ships in data/vgai/, by name."""


def train_state_estimator(cfg: FlockConfig, vision: VisionConfig, steps: int = 3000, states: int = 8,
                          F: int = 24, episodes: int = 40, seed: int = 0, progress: bool = True):
    """Fly ``episodes`` expert episodes, then train a fresh VisualCNN to estimate the exact local
    features from images (stage 1 of VGAI's training, on its own). Returns (cnn, losses, seconds)."""
    tcfg = VGAITrainConfig(F=F, vision=vision, seed=seed)
    torch.manual_seed(seed)
    gen = torch.Generator().manual_seed(seed)
    start = time.perf_counter()
    r0, v0 = sample_initial_state(cfg, episodes, gen)
    r, v, _ = collect_episodes(None, cfg, r0, v0, 0.0, gen)
    C, H, W = vision.image_shape(cfg)
    cnn = VisualCNN(C, H, W, F, tcfg.cnn_widths, tcfg.cnn_hidden)
    losses = fit_state_estimator(cnn, vision, cfg, r, v, steps, states, tcfg, gen, progress)
    return cnn, losses, time.perf_counter() - start


def save_estimator(path: Union[str, Path], cnn: VisualCNN, vision: VisionConfig, meta: dict) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    payload = {"format": ESTIMATOR_FORMAT, "vision": vision.to_dict(),
               "cnn": {"in_channels": cnn.in_channels, "height": cnn.height, "width": cnn.width, "F": cnn.F,
                       "widths": list(cnn.widths), "hidden": cnn.hidden},
               "state_dict": {k: t.detach().cpu() for k, t in cnn.state_dict().items()}, "meta": meta}
    torch.save(payload, path)
    return path


def load_estimator(path: Union[str, Path]) -> tuple[VisualCNN, VisionConfig, dict]:
    """(cnn, vision, meta) from an estimator file (weights_only: no code runs)."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no estimator at {path}: run `python -m vgai_lite train-vgai --estimators`")
    payload = torch.load(path, map_location="cpu", weights_only=True)
    if not isinstance(payload, dict) or payload.get("format") != ESTIMATOR_FORMAT:
        raise ValueError(f"{path} is not a vgai-lite state estimator (format {ESTIMATOR_FORMAT!r})")
    c = payload["cnn"]
    cnn = VisualCNN(c["in_channels"], c["height"], c["width"], c["F"], c["widths"], c["hidden"])
    cnn.load_state_dict(payload["state_dict"])
    return cnn.eval(), VisionConfig.from_dict(payload["vision"]), payload["meta"]


def book_estimator(name: str, retrain: bool = False, steps: int = 3000, progress: bool = True):
    """Load (or train and save) the book's state estimator ``name`` in data/vgai/."""
    from .book import DATA_DIR

    if name not in ESTIMATOR_RUNS:
        raise ValueError(f"unknown estimator {name!r}; the book's are {sorted(ESTIMATOR_RUNS)}")
    path = DATA_DIR / "vgai" / f"{name}.pt"
    vision = ESTIMATOR_RUNS[name]
    if path.is_file() and not retrain:
        cnn, stored_vision, meta = load_estimator(path)
        if stored_vision == vision and meta.get("steps") == steps:
            return cnn, vision, meta
    cfg = FlockConfig()
    cnn, losses, seconds = train_state_estimator(cfg, vision, steps=steps, progress=progress)
    quality = estimator_quality(cnn, vision, cfg)
    meta = {"steps": steps, "losses": losses, "seconds": seconds,
            "quality": {str(t): q for t, q in quality.items()}}
    save_estimator(path, cnn, vision, meta)
    return cnn, vision, meta


def load_or_train_vgai(path: Union[str, Path], cfg: FlockConfig, tcfg: VGAITrainConfig, retrain: bool = False,
                       progress: bool = True, stage1_cache: Optional[Union[str, Path]] = None
                       ) -> tuple[VGAIController, bool]:
    """Load the VGAI at ``path`` if it was trained, to the end, with exactly ``cfg`` and ``tcfg``;
    otherwise train it (about 11 minutes at the defaults on two CPU cores) and save it there. Returns
    (controller, whether it was trained now)."""
    from .checkpoints import is_finished_with, load_controller

    path = Path(path)
    if not retrain and is_finished_with(path, cfg, tcfg.to_dict()):
        return load_controller(path), False
    controller, _ = train_vgai(cfg, tcfg, checkpoint=path, progress=progress, stage1_cache=stage1_cache)
    return controller, True


VGAI_RUNS: dict[str, VGAITrainConfig] = {
    "vgai_F24": VGAITrainConfig(),   # the paper's default: F = 24, K - 1 = 3, egocentric, two frames
    "vgai_F6": VGAITrainConfig(F=6),     # Table 1a: as many features as the DAGNN's exact ones
    "vgai_F12": VGAITrainConfig(F=12),   # Table 1a
    "vgai_K2": VGAITrainConfig(K=2),     # Table 1b: K - 1 = 1 exchange
    "vgai_K3": VGAITrainConfig(K=3),     # Table 1b: K - 1 = 2 exchanges
}
"""The VGAI controllers the book ships in data/vgai/, by name."""


def book_vgai(name: str, retrain: bool = False, episodes: int = 50, progress: bool = True,
              write_json: bool = False):
    """Load (or train, about 11 minutes) the book's VGAI ``name`` and evaluate it on ``episodes``
    held-out episodes. Writes data/vgai/NAME.json with the evaluation when it trained the model or
    when ``write_json`` (the command line's train-vgai does), so that a notebook run in quick mode
    never overwrites the shipped record. Returns (controller, RelativeCost)."""
    from .book import DATA_DIR, EVAL_SEED
    from .imitation import write_evaluation

    if name not in VGAI_RUNS:
        raise ValueError(f"unknown run {name!r}; the book's VGAI runs are {sorted(VGAI_RUNS)}")
    cfg, tcfg = FlockConfig(), VGAI_RUNS[name]
    path = DATA_DIR / "vgai" / f"{name}.pt"
    controller, trained = load_or_train_vgai(path, cfg, tcfg, retrain=retrain, progress=progress)
    write_json = write_json or trained
    result = relative_cost(controller, cfg, episodes=episodes, seed=EVAL_SEED, name=name)
    hist = controller.meta["history"]
    if write_json:
        write_evaluation(path.with_suffix(".json"), result, cfg,
                         extra={"train_config": tcfg.to_dict(), "train_seconds": round(hist["seconds"], 1),
                                "stage1_seconds": round(hist.get("stage1_seconds", 0.0), 1),
                                "stage1_cached": hist.get("stage1_cached"),  # then not in train_seconds
                                "validation": hist["rounds"]})
    return controller, result

"""Training the DAGNN baseline by imitation with DAgger (section 3.2, eqs. 9-10, "Implementation Details").

Introduced in notebook 03. Each round flies new episodes under the DAgger mixture
(``imitation.fly_dagger``), records every agent-step's Z(t) with the expert's action U*(t), adds
them to the aggregated dataset, and fits the MLP on all of it (``imitation.fit_l1``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar, Optional, Union

import torch
from tqdm.auto import tqdm

from .checkpoints import save_controller
from .config import FlockConfig, config_dict
from .flocking import sample_initial_state
from .features import N_LOCAL_FEATURES
from .graphs import DEFAULT_GSO, GSO_KINDS
from .imitation import check_flight_mix, fit_l1, flight_groups, fly_dagger, round_check
from .learned_controllers import FEATURE_TRANSFORMS, DAGNNController
from .models import AggregationMLP


@dataclass(frozen=True)
class DAGNNTrainConfig:
    """Everything that defines a DAGNN training run (the paper gives only the loss, optimiser,
    learning rate and DAgger probability; the rest is ours, sized for two CPU cores).

    Attributes:
        K: taps (K - 1 exchanges; the paper's default K - 1 = 3).
        hidden: MLP hidden widths.
        gso: graph shift operator (see graphs.gso).
        feature_transform: "none" (default) feeds the features as they are (standardised by the
            MLP's first step); "signed_log" compresses the 1/r^3-sized repulsion features first
            (it imitates worse: notebook 03 compares both); "per_neighbour" divides each sum by the degree.
        rounds: DAgger rounds. Round 0 follows the expert only (the learner is untrained).
        episodes_per_round: new episodes collected per round.
        p_learner: probability of following the learner at each step, rounds >= 1 (paper: 0.33).
            0 gives plain behaviour cloning on expert trajectories (for the comparison in notebook 03).
        epochs_per_round: passes over the aggregated dataset after each round.
        batch_size: rows (agent-steps) per gradient step.
        lr: Adam's learning rate (paper: 1e-3).
        keep_late: share of the agent-steps after ``early_steps`` kept in the dataset. The expert's
            action is large only early (most of eq. 1 accrues in the first 20 steps); keeping every
            early row and a quarter of the late ones spends the updates where the labels live.
        early_steps: see ``keep_late``.
        seed: seed of the training initial conditions, the DAgger coin flips and the weights.
        teams, radii: team sizes N and the range (low, high) of communication radii R (m) the
            training's swarms fly with (``flight_groups``): each round's swarms fly in groups of
            ``group_swarms``, each group with its N drawn from ``teams`` and its R uniform in
            ``radii``. Empty (the paper's): every swarm flies the training's configuration. The
            features (the rows of eq. 4) and the GSO follow each group's R, the expert's action does not
            depend on R; the authors' released code draws R from U(1.0, 3.5) m per sample.
        group_swarms: swarms per group of ``teams`` and ``radii``.
    """

    K: int = 4
    hidden: tuple = (64, 64)
    gso: str = DEFAULT_GSO
    feature_transform: str = "none"
    rounds: int = 8
    episodes_per_round: int = 40
    p_learner: float = 0.33
    epochs_per_round: int = 3
    batch_size: int = 1024
    lr: float = 1e-3
    keep_late: float = 0.25
    early_steps: int = 50
    seed: int = 0
    teams: tuple = ()
    radii: tuple = ()
    group_swarms: int = 10

    LEGACY_FIELDS: ClassVar[dict] = {"teams": [], "radii": [], "group_swarms": 10}
    """Fields added after checkpoints were written, with the value (as stored) that every checkpoint
    written before them was trained with: no randomisation of N and R (before 2026-12-04)."""

    def __post_init__(self) -> None:
        check_flight_mix("DAGNNTrainConfig", self.teams, self.radii, self.group_swarms)
        for name in ("K", "rounds", "episodes_per_round", "epochs_per_round", "batch_size"):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise ValueError(f"DAGNNTrainConfig: {name} must be a whole number >= 1, got {value!r}")
        if not isinstance(self.early_steps, int) or self.early_steps < 0 or not isinstance(self.seed, int) or self.seed < 0:
            raise ValueError(f"DAGNNTrainConfig: early_steps and seed must be whole numbers >= 0, "
                             f"got {self.early_steps!r}, {self.seed!r}")
        for name in ("p_learner", "keep_late"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"DAGNNTrainConfig: {name} is a probability, in [0, 1]; got {getattr(self, name)!r}")
        if not self.lr > 0:
            raise ValueError(f"DAGNNTrainConfig: lr must be > 0, got {self.lr!r}")
        if self.gso not in GSO_KINDS:
            raise ValueError(f"DAGNNTrainConfig: gso must be one of {GSO_KINDS}, got {self.gso!r}")
        if self.feature_transform not in FEATURE_TRANSFORMS:
            raise ValueError(f"DAGNNTrainConfig: feature_transform must be one of {FEATURE_TRANSFORMS}, "
                             f"got {self.feature_transform!r}")

    def to_dict(self) -> dict:
        return config_dict(self)

    @classmethod
    def read_stored(cls, d: dict) -> dict:
        """A configuration as a checkpoint stored it, in today's form (``LEGACY_FIELDS`` filled in)."""
        return {**cls.LEGACY_FIELDS, **d}


@dataclass
class Dataset:
    """Aggregated imitation data, one row per agent-step: Z (M, K, F) and the expert's U* (M, 2)."""

    Z: list = field(default_factory=list)
    U: list = field(default_factory=list)

    def add(self, Z: torch.Tensor, U: torch.Tensor) -> None:
        self.Z.append(Z), self.U.append(U)

    def tensors(self) -> tuple[torch.Tensor, torch.Tensor]:
        return torch.cat(self.Z), torch.cat(self.U)

    def __len__(self) -> int:
        return sum(len(u) for u in self.U)


def collect(learner: DAGNNController, cfg: FlockConfig, r0: torch.Tensor, v0: torch.Tensor,
            p_learner: float, generator: torch.Generator, keep_late: float = 1.0,
            early_steps: int = 0) -> tuple[torch.Tensor, torch.Tensor]:
    """Fly the swarms (r0, v0) under the DAgger mixture and record (Z(t), U*(t)) for the agent-steps
    kept: every one before ``early_steps``, a random ``keep_late`` share after. The learner's buffer
    builds Z(t) along the trajectory actually flown. Returns Z (M, K, F), U* (M, 2)."""
    Zs, Us = [], []

    def record(t, r, v, u_star, Z):
        B, N = r.shape[:2]
        keep = 1.0 if t < early_steps else keep_late
        rows = torch.ones(B, N, dtype=torch.bool) if keep >= 1.0 else torch.rand(B, N, generator=generator) < keep
        rows = rows.to(r.device)
        Zs.append(Z[rows].cpu()), Us.append(u_star[rows].cpu())

    fly_dagger(learner, cfg, r0, v0, p_learner, generator, record)
    return torch.cat(Zs), torch.cat(Us)


def train_dagnn(cfg: FlockConfig, tcfg: DAGNNTrainConfig = DAGNNTrainConfig(),
                checkpoint: Optional[Union[str, Path]] = None, device=None, progress: bool = True,
                check_episodes: int = 10) -> tuple[DAGNNController, dict]:
    """Train a DAGNN by DAgger. Returns the controller and its history.

    history: "loss" (one value per epoch: mean L1 over the epoch), "rounds" (per round: rows in the
    dataset, relative cost on ``check_episodes`` episodes of the round check (``imitation.round_check``),
    seconds since start). If ``checkpoint`` is given, the controller is saved
    there after every round (with the history so far in its meta). The global torch RNG is left as
    it was (the weights are drawn inside ``torch.random.fork_rng``).
    """
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(tcfg.seed)  # the weights' initialisation
        return _train_dagnn(cfg, tcfg, checkpoint, device, progress, check_episodes)


def _train_dagnn(cfg, tcfg, checkpoint, device, progress, check_episodes):
    gen = torch.Generator().manual_seed(tcfg.seed)
    model = AggregationMLP(tcfg.K, N_LOCAL_FEATURES, tcfg.hidden).to(device)
    learner = DAGNNController(model, cfg, tcfg.gso, tcfg.feature_transform)
    opt = torch.optim.Adam(model.parameters(), lr=tcfg.lr)
    data = Dataset()
    history = {"loss": [], "rounds": []}
    start = time.perf_counter()

    def save(finished: bool) -> None:
        learner.meta = {"train_config": tcfg.to_dict(), "history": history, "finished": finished}
        if checkpoint is not None:
            save_controller(checkpoint, learner, meta=learner.meta)

    bar = tqdm(total=tcfg.rounds, desc="DAgger rounds", disable=not progress)
    for rnd in range(tcfg.rounds):
        model.eval()
        for flight, swarms in flight_groups(cfg, tcfg, tcfg.episodes_per_round, gen):
            learner.cfg = flight  # the features and the GSO of this group's radius
            r0, v0 = sample_initial_state(flight, swarms, gen, device=device)
            data.add(*collect(learner, flight, r0, v0, p_learner=0.0 if rnd == 0 else tcfg.p_learner,
                              generator=gen, keep_late=tcfg.keep_late, early_steps=tcfg.early_steps))
        learner.cfg = cfg
        Zall, Uall = data.tensors()
        if rnd == 0:
            model.set_normalization(Zall)
        history["loss"] += fit_l1(model, Zall, Uall, opt, tcfg.epochs_per_round, tcfg.batch_size, gen, device)
        model.eval()
        history["rounds"].append({"round": rnd, "rows": len(Uall), "loss": history["loss"][-1],
                                  **round_check(learner, cfg, check_episodes, tcfg.seed, device),
                                  "seconds": time.perf_counter() - start})
        bar.set_postfix(loss=f"{history['loss'][-1]:.3f}", check=f"{history['rounds'][-1]['check_relative_cost']:.2f}")
        bar.update()
        save(finished=rnd == tcfg.rounds - 1)
    bar.close()
    history["seconds"] = time.perf_counter() - start
    save(finished=True)
    return learner, history

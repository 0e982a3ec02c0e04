"""Imitation learning of the expert with DAgger (paper: eqs. 10-11 and "Implementation Details").

Introduced in notebook 03. The learner is trained to output the expert's action U*(t) (eq. 10) at
the states it visits, with an L1 loss (eq. 11) and Adam at learning rate 1e-3 (the paper's). DAgger:
data are collected in rounds; during collection each swarm follows the learner's action instead of
the expert's with probability 0.33 at every step (the paper's), every visited state is labelled
with the expert's action, and the datasets of all rounds are aggregated.
"""

from __future__ import annotations

import dataclasses
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Union

import torch
import torch.nn.functional as nnf
from tqdm.auto import tqdm

from .checkpoints import is_finished_with, load_controller, save_controller
from .config import FlockConfig
from .controllers import expert_control
from .evaluate import relative_cost
from .flocking import sample_initial_state, saturate, step
from .graphs import DEFAULT_GSO
from .models import AggregationMLP, DAGNNController

VALIDATION_SEED_OFFSET = 1000  # validation episodes: seed + 1000 (training uses seed, evaluation EVAL_SEED)


@dataclass(frozen=True)
class DAGNNTrainConfig:
    """Everything that defines a DAGNN training run (the paper gives only the loss, optimiser,
    learning rate and DAgger probability; the rest is ours, chosen to train in minutes on 2 cores).

    Attributes:
        K: taps (K - 1 exchanges; the paper's default K - 1 = 3).
        hidden: MLP hidden widths.
        gso: graph shift operator (see graphs.gso).
        feature_transform: "none" (default) feeds the features as they are (standardised by the
            MLP's first step); "signed_log" compresses the 1/r^3-sized repulsion features first
            (it imitates worse: notebook 03 compares both).
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

    def to_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["hidden"] = list(self.hidden)
        return d


@dataclass
class Dataset:
    """Aggregated imitation data: one row per agent-step. Z (M, K, F), U (M, 2) expert actions,
    t (M,) time step, round (M,) DAgger round."""

    Z: list = field(default_factory=list)
    U: list = field(default_factory=list)
    t: list = field(default_factory=list)
    round: list = field(default_factory=list)

    def add(self, Z, U, t, rnd):
        self.Z.append(Z), self.U.append(U), self.t.append(t), self.round.append(rnd)

    def tensors(self):
        return torch.cat(self.Z), torch.cat(self.U), torch.cat(self.t), torch.cat(self.round)

    def __len__(self):
        return sum(len(u) for u in self.U)


@torch.no_grad()
def collect(learner: DAGNNController, cfg: FlockConfig, r0: torch.Tensor, v0: torch.Tensor,
            p_learner: float, generator: torch.Generator, keep_late: float = 1.0,
            early_steps: int = 0) -> tuple[torch.Tensor, ...]:
    """Fly the swarms (r0, v0) under the DAgger mixture and record (Z(t), U*(t)) for every agent-step.

    At every step each swarm applies the learner's action with probability ``p_learner``, else the
    expert's (both saturated). The learner's buffer builds Z(t) along the trajectory actually flown.
    Returns Z (M, K, F), U* (M, 2), t (M,) for the kept rows (all rows before ``early_steps``, a
    random ``keep_late`` share after).
    """
    learner.reset()
    r, v = r0, v0
    B, N = r.shape[:2]
    Zs, Us, ts = [], [], []
    for t in range(cfg.T):
        Z = learner.observe(r, v)
        u_star = expert_control(r, v, cfg)
        if p_learner > 0:
            follow = torch.rand(B, generator=generator) < p_learner
            u = torch.where(follow.to(r.device)[:, None, None], learner.act(Z), u_star)
        else:
            u = u_star
        keep = 1.0 if t < early_steps else keep_late
        if keep >= 1.0:
            rows = torch.ones(B, N, dtype=torch.bool)
        else:
            rows = torch.rand(B, N, generator=generator) < keep
        rows = rows.to(r.device)
        Zs.append(Z[rows].cpu()), Us.append(u_star[rows].cpu())
        ts.append(torch.full((int(rows.sum()),), t, dtype=torch.int16))
        r, v = step(r, v, saturate(u, cfg), cfg)
    return torch.cat(Zs), torch.cat(Us), torch.cat(ts)


def train_dagnn(cfg: FlockConfig, tcfg: DAGNNTrainConfig = DAGNNTrainConfig(),
                checkpoint: Optional[Union[str, Path]] = None, device=None, progress: bool = True,
                validation_episodes: int = 10) -> tuple[DAGNNController, dict]:
    """Train a DAGNN by DAgger. Returns the controller and its history.

    history: "loss" (one value per epoch: mean L1 over the epoch), "rounds" (per round: rows in the
    dataset, validation relative cost on ``validation_episodes`` episodes of seed
    ``tcfg.seed + 1000``, seconds since start). If ``checkpoint`` is given, the controller is saved
    there after every round (with the history so far in its meta).
    """
    torch.manual_seed(tcfg.seed)
    gen = torch.Generator().manual_seed(tcfg.seed)
    model = AggregationMLP(tcfg.K, 6, tcfg.hidden).to(device)
    learner = DAGNNController(model, cfg, tcfg.gso, tcfg.feature_transform)
    opt = torch.optim.Adam(model.parameters(), lr=tcfg.lr)
    data = Dataset()
    history = {"loss": [], "rounds": []}
    start = time.perf_counter()
    bar = tqdm(total=tcfg.rounds, desc="DAgger rounds", disable=not progress)
    for rnd in range(tcfg.rounds):
        model.eval()
        r0, v0 = sample_initial_state(cfg, tcfg.episodes_per_round, gen, device=device)
        Z, U, t = collect(learner, cfg, r0, v0, p_learner=0.0 if rnd == 0 else tcfg.p_learner,
                          generator=gen, keep_late=tcfg.keep_late, early_steps=tcfg.early_steps)
        data.add(Z, U, t, torch.full((len(U),), rnd, dtype=torch.int16))
        Zall, Uall, _, _ = data.tensors()
        if rnd == 0:
            model.set_normalization(Zall)
        model.train()
        for _ in range(tcfg.epochs_per_round):
            perm = torch.randperm(len(Uall), generator=gen)
            total, count = 0.0, 0
            for i in range(0, len(perm), tcfg.batch_size):
                idx = perm[i:i + tcfg.batch_size]
                zb, ub = Zall[idx].to(device), Uall[idx].to(device)
                loss = nnf.l1_loss(model(zb), ub)  # eq. 11: L1 between the learner's and the expert's actions
                opt.zero_grad(set_to_none=True)
                loss.backward()
                opt.step()
                total += loss.item() * len(idx)
                count += len(idx)
            history["loss"].append(total / count)
        model.eval()
        val = relative_cost(learner, cfg, episodes=validation_episodes,
                            seed=tcfg.seed + VALIDATION_SEED_OFFSET, device=device)
        history["rounds"].append({"round": rnd, "rows": len(Uall), "loss": history["loss"][-1],
                                  "val_relative_cost": val.mean_ratio,
                                  "val_share_below_0.05m": val.safety.share_below(0.05),
                                  "seconds": time.perf_counter() - start})
        bar.set_postfix(loss=f"{history['loss'][-1]:.3f}", val=f"{val.mean_ratio:.2f}")
        bar.update()
        if checkpoint is not None:
            save_controller(checkpoint, learner, meta={"train_config": tcfg.to_dict(), "history": history,
                                                       "finished": rnd == tcfg.rounds - 1})
    bar.close()
    history["seconds"] = time.perf_counter() - start
    if checkpoint is not None:
        save_controller(checkpoint, learner, meta={"train_config": tcfg.to_dict(), "history": history,
                                                   "finished": True})
    return learner, history


def load_or_train(path: Union[str, Path], cfg: FlockConfig, tcfg: DAGNNTrainConfig = DAGNNTrainConfig(),
                  retrain: bool = False, device=None, progress: bool = True) -> DAGNNController:
    """Load the DAGNN at ``path`` if it was trained, to the end, with exactly ``cfg`` and ``tcfg``;
    otherwise train it (minutes) and save it there. The training history is in ``controller.meta``."""
    path = Path(path)
    if path.is_file() and not retrain:
        if is_finished_with(path, cfg, tcfg.to_dict()):
            return load_controller(path, device=device)
        print(f"{path.name} was trained with another configuration (or did not finish): training again")
    controller, history = train_dagnn(cfg, tcfg, checkpoint=path, device=device, progress=progress)
    controller.meta = {"train_config": tcfg.to_dict(), "history": history, "finished": True}
    return controller


def write_evaluation(path: Union[str, Path], result, cfg: FlockConfig, extra: Optional[dict] = None) -> Path:
    """Save a RelativeCost's summary with its configuration as JSON (what the notebooks display)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    out = {"config": dataclasses.asdict(cfg), **result.summary(), **(extra or {})}
    path.write_text(json.dumps(out, indent=2) + "\n")
    return path


BOOK_RUNS: dict[str, DAGNNTrainConfig] = {
    "dagnn_K4": DAGNNTrainConfig(),                          # the default: K - 1 = 3 exchanges
    "dagnn_K3": DAGNNTrainConfig(K=3),                       # Table 1b: K - 1 = 2
    "dagnn_K2": DAGNNTrainConfig(K=2),                       # Table 1b: K - 1 = 1
    "dagnn_K1": DAGNNTrainConfig(K=1),                       # no exchange at all
    "dagnn_K4_no_dagger": DAGNNTrainConfig(p_learner=0.0),   # behaviour cloning on expert data only
    "dagnn_K4_mean": DAGNNTrainConfig(gso="row_normalized"), # GSO comparison (notebook 03)
    "dagnn_K4_sum": DAGNNTrainConfig(gso="adjacency"),
    "dagnn_K4_signed_log": DAGNNTrainConfig(feature_transform="signed_log"),
}
"""The DAGNNs the book ships in data/dagnn/ (FlockConfig() defaults), by name."""


def book_run(name: str, retrain: bool = False, episodes: int = 50, progress: bool = True):
    """Load (or train) the book's DAGNN ``name``, evaluate it on ``episodes`` held-out episodes
    (seed EVAL_SEED) and write data/dagnn/NAME.pt and NAME.json. Returns (controller, RelativeCost)."""
    from .book import DATA_DIR, EVAL_SEED

    if name not in BOOK_RUNS:
        raise ValueError(f"unknown run {name!r}; the book's runs are {sorted(BOOK_RUNS)}")
    cfg = FlockConfig()
    path = DATA_DIR / "dagnn" / f"{name}.pt"
    controller = load_or_train(path, cfg, BOOK_RUNS[name], retrain=retrain, progress=progress)
    result = relative_cost(controller, cfg, episodes=episodes, seed=EVAL_SEED, name=name)
    hist = controller.meta["history"]
    write_evaluation(path.with_suffix(".json"), result, cfg,
                     extra={"train_config": BOOK_RUNS[name].to_dict(),
                            "train_seconds": round(hist["seconds"], 1),
                            "validation_by_round": hist["rounds"]})
    return controller, result

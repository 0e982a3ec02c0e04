"""Imitation learning of the expert with DAgger: what the DAGNN's and VGAI's trainings share.

Introduced in notebook 03 (used again in notebook 06). The paper trains the learner to output the
expert's action U*(t) at the states it visits (eq. 9), with the L1 loss of eq. 10 and Adam at
learning rate 1e-3. DAgger: data are collected in rounds; during collection each swarm follows the
learner's action instead of the expert's with probability p = 0.33 at every step (``dagger_mix``,
exercise 06.1), every visited state is labelled with the expert's action, and the data of all
rounds are aggregated.

Here: the mixing rule, one DAgger flight (``fly_dagger``), the team sizes and radii a training's swarms
fly with (``flight_groups``), the stored flights (``EpisodeStore``),
one minibatch L1 fit loop (``fit_l1``), the check a training logs after each round (``round_check``),
and one load-or-train contract (``load_or_train``). The trainings themselves are ``dagnn_training`` and ``vgai_training``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, NamedTuple, Optional, Union

import torch
import torch.nn.functional as nnf
from tqdm.auto import tqdm

from .checkpoints import is_finished_with, load_controller
from .config import FlockConfig
from .controllers import expert_control
from .evaluate import relative_cost
from .flocking import saturate, step

log = logging.getLogger(__name__)

ROUND_CHECK_SEED_OFFSET = 1000
"""A training's round checks fly the episodes of its seed + 1000 (its flights draw from the seed itself;
the book's validation, test and working episodes from ``book``'s seeds, all above)."""


def dagger_mix(u_learner: torch.Tensor, u_expert: torch.Tensor, p: float,
               generator: torch.Generator) -> torch.Tensor:
    """DAgger's mixing rule: each swarm (first axis) applies the learner's actions with probability
    p, else the expert's; one coin per swarm and step. u_learner, u_expert (B, N, 2) -> (B, N, 2);
    p a number, or one per swarm (B,).
    The library twin of exercise 06.1."""
    follow = torch.rand(u_expert.shape[0], generator=generator) < torch.as_tensor(p)
    return torch.where(follow.to(u_expert.device)[:, None, None], u_learner, u_expert)


@torch.no_grad()
def fly_dagger(learner, cfg: FlockConfig, r0: torch.Tensor, v0: torch.Tensor, p_learner: float,
               generator: torch.Generator, record: Callable, steps: Optional[int] = None) -> None:
    """Fly the swarms (r0, v0) (B, N, 2) for ``steps`` steps (default cfg.T) under the DAgger mixture, calling
    ``record(t, r, v, u_star, Z)`` at every step with the state, the expert's label U*(t) (eq. 9) and Z(t)
    (None without a learner).

    ``learner`` (or None: the expert flies alone) observes every step, so that its buffers follow
    the trajectory actually flown, and acts where ``dagger_mix`` picks it (p_learner > 0)."""
    if learner is not None:
        learner.reset()
    r, v = r0, v0
    for t in range(cfg.T if steps is None else steps):
        Z = learner.observe(r, v) if learner is not None else None
        u_star = expert_control(r, v, cfg)
        u = u_star
        if learner is not None and bool((torch.as_tensor(p_learner) > 0).any()):
            u = dagger_mix(learner.act(Z), u_star, p_learner, generator)
        record(t, r, v, u_star, Z)
        r, v = step(r, v, saturate(u, cfg), cfg)


LARGE_TEAM = 75
"""From this team size on, a group's initial states are drawn with ``init_method="repair"`` (rejection
of whole swarms rarely succeeds there), as the book's evaluation draws them."""


def check_flight_mix(owner: str, teams: tuple, radii: tuple, group_swarms: int) -> None:
    """A training configuration's ``teams``, ``radii`` and ``group_swarms`` (``flight_groups``), or a clear error."""
    if any(not isinstance(n, int) or isinstance(n, bool) or n < 2 for n in teams):
        raise ValueError(f"{owner}: teams must be whole numbers of drones >= 2, got {teams!r}")
    if radii and (len(radii) != 2 or not 0 < radii[0] <= radii[1]):
        raise ValueError(f"{owner}: radii must be (low, high) in m with 0 < low <= high, got {radii!r}")
    if not isinstance(group_swarms, int) or isinstance(group_swarms, bool) or group_swarms < 1:
        raise ValueError(f"{owner}: group_swarms must be a whole number >= 1, got {group_swarms!r}")


def flight_groups(cfg: FlockConfig, tcfg, swarms: int, gen: torch.Generator) -> list:
    """The configurations ``swarms`` swarms fly in, as (FlockConfig, count) pairs: all of them in ``cfg``
    without ``tcfg.teams`` and ``tcfg.radii`` (no draw), else groups of ``tcfg.group_swarms``, each with
    N drawn from ``teams`` and R uniform in ``radii`` (``gen``)."""
    if not tcfg.teams and not tcfg.radii:
        return [(cfg, swarms)]
    groups = []
    for start in range(0, swarms, tcfg.group_swarms):
        changes = {}
        if tcfg.teams:
            n = tcfg.teams[int(torch.randint(len(tcfg.teams), (1,), generator=gen))]
            changes.update(N=n, init_method="repair" if n >= LARGE_TEAM else cfg.init_method)
        if tcfg.radii:
            lo, hi = tcfg.radii
            changes["R"] = lo + (hi - lo) * float(torch.rand((), generator=gen, dtype=torch.float64))
        groups.append((cfg.replace(**changes), min(tcfg.group_swarms, swarms - start)))
    return groups


class Flights(NamedTuple):
    """Stored flights of one flight configuration ``cfg``: r, v, u* (the expert's action), (T, E, N, 2) each."""
    cfg: FlockConfig
    r: torch.Tensor
    v: torch.Tensor
    u: torch.Tensor


@dataclass
class EpisodeStore:
    """Stored flights, aggregated over DAgger rounds: r, v, u* (the expert's action), each a list of
    (T, E, N, 2) tensors, flown in the configurations ``cfgs``; ``groups()`` joins them along the episodes
    per configuration, ``tensors()`` when they all flew one."""

    r: list = field(default_factory=list)
    v: list = field(default_factory=list)
    u: list = field(default_factory=list)
    cfgs: list = field(default_factory=list)

    def fly(self, learner, cfg: FlockConfig, r0: torch.Tensor, v0: torch.Tensor, p_learner: float,
            generator: torch.Generator, steps: Optional[int] = None) -> None:
        """Add the flights of (r0, v0), ``steps`` steps long (default cfg.T), under the DAgger
        mixture (``fly_dagger``)."""
        rs, vs, us = [], [], []
        fly_dagger(learner, cfg, r0, v0, p_learner, generator,
                   lambda t, r, v, u_star, Z: (rs.append(r), vs.append(v), us.append(u_star)), steps)
        self.r.append(torch.stack(rs)), self.v.append(torch.stack(vs)), self.u.append(torch.stack(us))
        self.cfgs.append(cfg)

    def groups(self) -> list:
        """The flights joined per flight configuration, in the order first flown: a list of ``Flights``."""
        joined = {}
        for c, *flown in zip(self.cfgs, self.r, self.v, self.u):
            joined.setdefault(c, []).append(flown)
        return [Flights(c, *(torch.cat(x, 1) for x in zip(*flown))) for c, flown in joined.items()]

    def tensors(self) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """r, v, u* of every flight, (T, E, N, 2) each: the flights must share one configuration."""
        if len(set(self.cfgs)) > 1:
            raise ValueError(f"EpisodeStore.tensors: the flights flew {len(set(self.cfgs))} configurations; "
                             "use groups() for flights of several team sizes or radii")
        return torch.cat(self.r, 1), torch.cat(self.v, 1), torch.cat(self.u, 1)

    @property
    def episodes(self) -> int:
        return sum(x.shape[1] for x in self.r)


def fit_l1(model: torch.nn.Module, inputs: torch.Tensor, targets: torch.Tensor, opt: torch.optim.Optimizer,
           epochs: int, batch_size: int, generator: torch.Generator, device=None, desc: Optional[str] = None,
           progress: bool = False) -> list:
    """Minibatch imitation: ``epochs`` passes in random order over (inputs, targets) rows, each step
    the L1 loss of eq. 10 between model(inputs) and the expert's actions. Returns the mean loss of
    every epoch."""
    model.train()
    losses = []
    for _ in tqdm(range(epochs), desc=desc, disable=not progress):
        perm = torch.randperm(len(targets), generator=generator)
        total = 0.0
        for i in range(0, len(perm), batch_size):
            idx = perm[i:i + batch_size]
            loss = nnf.l1_loss(model(inputs[idx].to(device)), targets[idx].to(device))
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            total += loss.item() * len(idx)
        losses.append(total / len(perm))
    return losses


def round_check(learner, cfg: FlockConfig, episodes: int, seed: int, device=None) -> dict:
    """What a training logs after each DAgger round: the learner's relative cost (and close calls) on
    ``episodes`` episodes of ``seed + ROUND_CHECK_SEED_OFFSET`` (paper-length episodes only: no
    flocking figures, which would cost 2.5 times the flying). Nothing is chosen on them."""
    res = relative_cost(learner, cfg, episodes=episodes, seed=seed + ROUND_CHECK_SEED_OFFSET, device=device,
                        flock_times=())
    return {"check_relative_cost": res.mean_ratio, "check_share_below_0.05m": res.safety.share_below(0.05)}


def load_or_train(path: Union[str, Path], cfg: FlockConfig, tcfg, train: Callable, retrain: bool = False,
                  **train_kwargs):
    """Load the controller at ``path`` if it was trained, to the end, with exactly ``cfg`` and
    ``tcfg``; otherwise ``train(cfg, tcfg, checkpoint=path, **train_kwargs)``, which saves it there
    (how long a training takes: its record in ``data/``, ``lab.runs.training_minutes``).

    Returns (controller, whether it was trained now); the training record is in ``controller.meta``.
    """
    path = Path(path)
    if not retrain and is_finished_with(path, cfg, tcfg.to_dict(), read=tcfg.read_stored):
        return load_controller(path, device=train_kwargs.get("device")), False
    if path.is_file() and not retrain:
        log.info("%s was trained with another configuration (or did not finish): training again", path.name)
    controller, _ = train(cfg, tcfg, checkpoint=path, **train_kwargs)
    return controller, True

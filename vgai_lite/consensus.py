"""Did it flock? Velocity consensus late in a flight and the swarm's cohesion, beside the cost.

Introduced in notebook 01. Eq. 1 sums the velocity variance over an episode, and most of it accrues in the first
steps, where every controller brakes hard; a controller whose drones never quite align can still score well. So,
beside every relative cost, the book reports:

  * the velocity variance (1/N) sum_i ||v_i(t) - vbar(t)||^2 (the summand of eq. 1) at t = 0.5, 1, 2 and 5 s of
    flights longer than the training episodes (500 steps), median over episodes;
  * whether the communication graph (radius R) is connected at the end (into how many groups it fell apart), and
    whether it was at the start (``connected_at_start``).

Shapes: trajectories (T, B, N, 2).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from .config import FlockConfig
from .flocking import rollout, sample_initial_state, velocity_variance
from .graphs import adjacency, k_hop_reach

CONSENSUS_TIMES = (0.5, 1.0, 2.0, 5.0)
"""Seconds at which the velocity variance is read (5 s = 500 steps of 0.01 s)."""


def groups(r: torch.Tensor, R: float) -> torch.Tensor:
    """Connected components of the communication graph of radius R, r (B, N, 2) -> (B,) counts."""
    reach = k_hop_reach(adjacency(r, R), r.shape[1] - 1)  # (B, N, N): same component
    first = reach.to(torch.int64).argmax(dim=-1)  # each agent's lowest-numbered companion
    return torch.tensor([len(torch.unique(f)) for f in first])


def connected_at_start(cfg: FlockConfig, episodes: int, *, seed: int) -> torch.Tensor:
    """(episodes,) bool: the graph of radius cfg.R connected at t = 0 in the episodes of ``seed``? Every drone starts
    with two neighbours, not one connected graph; pieces rejoin only if their motions bring them within cfg.R."""
    r0, _ = sample_initial_state(cfg, episodes, torch.Generator().manual_seed(seed))
    return groups(r0, cfg.R) == 1


@dataclass
class Consensus:
    """A controller's flocking figures on ``episodes`` flights of ``steps`` steps. Attributes: ``times``, seconds at
    which ``variance`` (E, len(times)) in m^2/s^2 is read; ``groups_at_end`` (E,), the graph's components at the end."""

    name: str
    times: tuple
    variance: torch.Tensor
    groups_at_end: torch.Tensor

    def median_variance(self) -> dict:
        """{t: median over episodes of the velocity variance at t seconds}."""
        return {t: float(self.variance[:, k].median()) for k, t in enumerate(self.times)}

    @property
    def share_connected(self) -> float:
        return float((self.groups_at_end == 1).double().mean())

    def summary(self) -> dict:
        return {"name": self.name, "episodes": len(self.groups_at_end),
                "median_velocity_variance": {f"{t:g}s": round(x, 8) for t, x in self.median_variance().items()},
                "share_connected_at_end": round(self.share_connected, 3),
                "groups_at_end": [int(g) for g in self.groups_at_end]}

    def __str__(self) -> str:
        var = "  ".join(f"{t:g} s: {x:.2e}" for t, x in self.median_variance().items())
        return (f"{self.name}: median velocity variance [m²/s²]  {var};  communication graph connected at the end "
                f"in {int((self.groups_at_end == 1).sum())} of {len(self.groups_at_end)} episodes")


def consensus(controller, cfg: FlockConfig, episodes: int = 10, *, seed: int,
              times: tuple = CONSENSUS_TIMES, name: str = "") -> Consensus:
    """Fly ``controller`` from ``episodes`` initial conditions of ``seed`` (no default: say which episodes, as for
    ``evaluate.relative_cost``) for as long as the last of ``times`` needs, and read its flocking figures."""
    steps = int(round(max(times) / cfg.Ts)) + 1
    if any(t < 0 for t in times):
        raise ValueError(f"times must be >= 0 seconds, got {times}")
    r0, v0 = sample_initial_state(cfg, episodes, torch.Generator().manual_seed(seed))
    traj = rollout(controller, cfg, r0, v0, steps=steps)
    var = velocity_variance(traj.v)[[int(round(t / cfg.Ts)) for t in times]].T  # (E, len(times))
    return Consensus(name or getattr(controller, "name", type(controller).__name__), tuple(times), var,
                     groups(traj.r[-1], cfg.R))

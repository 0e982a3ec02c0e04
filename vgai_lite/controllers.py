"""The centralized expert (eq. 2), its collision potential (eq. 3) and the local heuristic.

Introduced in notebook 01. Shapes: r, v, u are (B, N, 2); offsets r_ij are (..., 2).
"""

from __future__ import annotations

import torch

from .config import DISTANCE_FLOOR, FlockConfig
from .flocking import check_state, pairwise_offsets, saturate


def log_sign(cfg: FlockConfig) -> float:
    """The sign of the log term of U: -1 in the paper's eq. 3, +1 in its public reference code."""
    return -1.0 if cfg.potential == "paper" else 1.0


def repulsion_weight(inv_d2: torch.Tensor, cfg: FlockConfig) -> torch.Tensor:
    """w with -grad_{r_i} U = w r_ij, from 1/d2 (d2 = ||r_ij||^2): w = 2 (1/d2^2 - sign/d2), since
    grad (1/d2) = -2 r_ij / d2^2 and grad log d2 = 2 r_ij / d2."""
    return 2.0 * inv_d2 * (inv_d2 - log_sign(cfg))


def potential(d2: torch.Tensor, cfg: FlockConfig) -> torch.Tensor:
    """The collision-avoidance potential U of eq. 3 as a function of d2 = ||r_ij||^2.

    paper:      U = 1/d2 - log d2  if ||r_ij|| <= rho, else 1/rho^2 - log rho^2 (constant)
    reference:  U = 1/d2 + log d2  (the public reference code's sign), same cut-off.
    d2 is floored at DISTANCE_FLOOR^2 (config.DISTANCE_FLOOR: finite at d2 = 0).
    """
    d2 = d2.clamp(min=DISTANCE_FLOOR ** 2)
    sign = log_sign(cfg)
    rho2 = torch.as_tensor(cfg.rho ** 2, dtype=d2.dtype, device=d2.device)
    inside = 1.0 / d2 + sign * torch.log(d2)
    outside = 1.0 / rho2 + sign * torch.log(rho2)
    return torch.where(d2 <= rho2, inside, outside)


def potential_gradient(r_ij: torch.Tensor, cfg: FlockConfig) -> torch.Tensor:
    """grad_{r_i} U(r_i, r_j) for offsets r_ij = r_i - r_j, shape (..., 2) -> (..., 2).

    With d2 = ||r_ij||^2 (``repulsion_weight``):
    paper:      grad U = -2 r_ij (1/d2^2 + 1/d2)   (always pushes i away from j)
    reference:  grad U = -2 r_ij (1/d2^2 - 1/d2)
    and grad U = 0 beyond rho, where U is constant. d2 is floored at DISTANCE_FLOOR^2 (zero at r_ij = 0).
    """
    d2 = r_ij.square().sum(dim=-1, keepdim=True).clamp(min=DISTANCE_FLOOR ** 2)
    grad = -repulsion_weight(1.0 / d2, cfg) * r_ij
    return torch.where(d2 <= cfg.rho ** 2, grad, torch.zeros_like(grad))


def _repulsion(dx, dy, d2, mask, cfg: FlockConfig) -> torch.Tensor:
    """-sum_j grad_{r_i} U over the pairs in ``mask`` (B, N, N), from pairwise offsets: (B, N, 2).

    -grad_{r_i} U = w_ij r_ij (``repulsion_weight``); w_ij = 0 outside ``mask``; d2 floored
    at DISTANCE_FLOOR^2, so that coincident agents (r_ij = 0) push each other with 0, not NaN.
    """
    inv = torch.where(mask, d2.clamp(min=DISTANCE_FLOOR ** 2), torch.inf).reciprocal_()  # 1/d2 on the masked pairs, else 0
    w = repulsion_weight(inv, cfg)
    return torch.stack(((w * dx).sum(dim=-1), (w * dy).sum(dim=-1)), dim=-1)


def expert_control(r: torch.Tensor, v: torch.Tensor, cfg: FlockConfig) -> torch.Tensor:
    """The centralized expert of eq. 2, saturated per axis to +-u_max.

    u*_i = -sum_{j=1}^{N} (v_i - v_j) - sum_{j=1}^{N} grad_{r_i} U(r_i, r_j)

    Every agent uses every other agent's velocity: the alignment term equals N (vbar - v_i), which
    needs the whole swarm's mean velocity. The potential only acts within rho.
    Args: r, v: (B, N, 2). Returns: u*, (B, N, 2).
    """
    check_state(r, v)
    N = r.shape[1]
    align = v.sum(dim=1, keepdim=True) - N * v
    dx, dy, d2 = pairwise_offsets(r)
    return saturate(align + _repulsion(dx, dy, d2, d2 <= cfg.rho ** 2, cfg), cfg)


def local_control(r: torch.Tensor, v: torch.Tensor, cfg: FlockConfig,
                  alignment_gain: float = 1.0, repulsion_gain: float = 1.0) -> torch.Tensor:
    """The local heuristic (the equation after eq. 3): eq. 2 with both sums over N_i(t) only.

    u~_i = -sum_{j in N_i} (v_i - v_j) - sum_{j in N_i} grad_{r_i} U(r_i, r_j),
    N_i(t) = { j != i : ||r_i - r_j|| <= R }: present, one-hop information only.
    ``alignment_gain`` and ``repulsion_gain`` multiply the two sums (1 and 1 in the paper; notebook
    03 shows what other gains do to the cost and to collisions).
    Args: r, v: (B, N, 2). Returns: (B, N, 2), saturated per axis.
    """
    check_state(r, v)
    dx, dy, d2 = pairwise_offsets(r)
    A = (d2 <= cfg.R ** 2).to(v.dtype)  # (B, N, N) adjacency, no self-loops
    align = alignment_gain * (A @ v - A.sum(dim=-1, keepdim=True) * v)
    near = (d2 <= min(cfg.rho, cfg.R) ** 2)
    return saturate(align + repulsion_gain * _repulsion(dx, dy, d2, near, cfg), cfg)


class ExpertController:
    """The centralized expert as a controller: ``ExpertController(cfg)(r, v) -> u``."""

    name = "Centralized"

    def __init__(self, cfg: FlockConfig):
        self.cfg = cfg

    def __call__(self, r: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
        return expert_control(r, v, self.cfg)

    def __repr__(self) -> str:
        return f"ExpertController(N any, rho={self.cfg.rho}, potential={self.cfg.potential!r})"


class LocalController:
    """The local heuristic as a controller: ``LocalController(cfg)(r, v) -> u``."""

    def __init__(self, cfg: FlockConfig, alignment_gain: float = 1.0, repulsion_gain: float = 1.0):
        self.cfg, self.alignment_gain, self.repulsion_gain = cfg, alignment_gain, repulsion_gain
        gains = (alignment_gain, repulsion_gain)
        self.name = "Local" if gains == (1.0, 1.0) else f"Local (gains {alignment_gain:g}, {repulsion_gain:g})"

    def __call__(self, r: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
        return local_control(r, v, self.cfg, self.alignment_gain, self.repulsion_gain)

    def __repr__(self) -> str:
        return (f"LocalController(R={self.cfg.R}, rho={self.cfg.rho}, alignment_gain={self.alignment_gain}, "
                f"repulsion_gain={self.repulsion_gain})")

"""The flocking problem of section 3.1: double-integrator dynamics, initial conditions, cost, rollouts.

Introduced in notebook 01. Everything is batched: positions ``r`` and velocities ``v`` have shape
``(B, N, 2)`` (swarms, agents, x/y); trajectories are time-first, ``(T, B, N, 2)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Optional, Protocol

import torch

from .config import FlockConfig


class NonFiniteStateError(ValueError):
    """A state or an acceleration holds NaN or inf. ``swarm`` and ``agent`` locate the first bad
    entry; ``step`` is the rollout step at which it appeared (None outside a rollout)."""

    def __init__(self, message: str, swarm: int, agent: int, step: Optional[int] = None):
        super().__init__(message)
        self.swarm, self.agent, self.step = swarm, agent, step


def first_nonfinite(x: torch.Tensor) -> Optional[tuple[int, int]]:
    """(swarm, agent) of the first agent of x (B, N, ...) with a NaN or inf entry, or None."""
    bad = ~torch.isfinite(x)
    if not bad.any():
        return None
    b, i = torch.nonzero(bad.flatten(2).any(dim=-1))[0].tolist()
    return b, i


def check_finite(x: torch.Tensor, label: str, step: Optional[int] = None) -> None:
    """Raise a NonFiniteStateError naming the first swarm and agent of x (B, N, ...) that holds
    NaN or inf (and the rollout ``step``, when given)."""
    where = first_nonfinite(x)
    if where is not None:
        b, i = where
        at = f" at step {step}" if step is not None else ""
        raise NonFiniteStateError(
            f"{label} is not finite{at}: swarm {b}, agent {i} has {x[b, i].flatten().tolist()}. "
            f"States and accelerations must be finite numbers (no NaN, no inf).", b, i, step)


def check_state(r: torch.Tensor, v: Optional[torch.Tensor] = None, name: str = "r") -> None:
    """Raise a ValueError unless ``r`` (and ``v``) are finite floating tensors of shape (B, N, 2)
    (a NonFiniteStateError, a ValueError, naming the first bad swarm and agent, for NaN or inf)."""
    for label, x in ((name, r), ("v", v)):
        if x is None:
            continue
        if not isinstance(x, torch.Tensor):
            raise ValueError(f"{label} must be a torch.Tensor of shape (B, N, 2), got {type(x).__name__}")
        if x.ndim != 3 or x.shape[-1] != 2 or x.shape[1] < 1:
            hint = " (add a batch axis with x.unsqueeze(0))" if x.ndim == 2 else ""
            raise ValueError(f"{label} must have shape (B, N, 2) = (swarms, agents, xy), "
                             f"got {tuple(x.shape)}{hint}")
        if not x.is_floating_point():
            raise ValueError(f"{label} must be a floating tensor (float32 or float64), got {x.dtype}")
        check_finite(x, label)
    if v is not None and v.shape != r.shape:
        raise ValueError(f"{name} and v must have the same shape (B, N, 2), got {tuple(r.shape)} "
                         f"and {tuple(v.shape)}")


def pairwise_offsets(r: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Pairwise offsets r_ij = r_i - r_j and squared distances.

    Args:
        r: positions, (B, N, 2).
    Returns:
        dx, dy: components of r_ij, each (B, N, N); d2 = ||r_ij||^2, (B, N, N), with +inf on the
        diagonal so that an agent is never its own neighbour.
    """
    dx = r[..., :, None, 0] - r[..., None, :, 0]
    dy = r[..., :, None, 1] - r[..., None, :, 1]
    d2 = dx * dx + dy * dy
    d2.diagonal(dim1=-2, dim2=-1).fill_(math.inf)
    return dx, dy, d2


def min_pair_distance(r: torch.Tensor) -> torch.Tensor:
    """Smallest distance between two distinct agents of each swarm: (B, N, 2) -> (B,)."""
    _, _, d2 = pairwise_offsets(r)
    return d2.flatten(1).min(dim=1).values.sqrt()


def sample_initial_state(cfg: FlockConfig, batch: int, generator: Optional[torch.Generator] = None,
                         dtype: torch.dtype = torch.float32, device=None,
                         chunk: int = 2048) -> tuple[torch.Tensor, torch.Tensor]:
    """Draw ``batch`` initial swarms as the paper's "Implementation Details" describe.

    Positions are uniform on a disc of radius ``cfg.init_radius`` (N**0.25 by default, see
    FlockConfig); each agent's velocity is uniform in [-v_init, v_init]^2 plus one flock-wide bias
    uniform in [-0.3 v_init, 0.3 v_init]^2. A candidate is rejected (and redrawn) while any agent
    has fewer than ``cfg.min_neighbours`` neighbours within R or any pair is closer than
    ``cfg.min_init_distance`` (with ``cfg.init_method == "repair"`` the too-close agents are
    redrawn first, see FlockConfig). Candidates are drawn ``chunk`` at a time, in float64 on the CPU from
    ``generator``, so the result depends only on the generator's seed, not on device or dtype.

    Returns:
        r, v: (batch, N, 2) each, of ``dtype`` on ``device``.
    Raises:
        RuntimeError: after more than ``cfg.max_init_tries`` candidates per accepted state.
    """
    if not isinstance(batch, int) or batch < 1:
        raise ValueError(f"batch must be a positive integer, got {batch!r}")
    if generator is None:
        generator = torch.Generator().manual_seed(0)
    N, R2, dmin2 = cfg.N, cfg.R ** 2, cfg.min_init_distance ** 2
    rs, vs = [], []
    accepted = tried = 0
    while accepted < batch:
        if tried > cfg.max_init_tries * (accepted + 1):
            raise RuntimeError(
                f"sample_initial_state ({cfg.init_method!r}): {tried} candidate swarms drawn, {accepted} of {batch} met the "
                f"constraints (every agent >= {cfg.min_neighbours} neighbours within R = {cfg.R} m, "
                f"no pair closer than {cfg.min_init_distance} m on a disc of radius "
                f"{cfg.init_radius:.2f} m). Make R larger, the disc smaller (init_radius_exponent), "
                f"the constraints looser, or use init_method='repair' for large teams.")
        count = chunk if cfg.init_method == "reject" else min(chunk, 2 * (batch - accepted) + 2)
        pos = _disc(cfg, count, generator)
        if cfg.init_method == "repair":
            pos = _repair(pos, cfg, generator)
        # Screen cheaply in float32 with a small margin, then check the few survivors exactly.
        pos32 = pos.float()
        dist = torch.cdist(pos32, pos32)
        dist.diagonal(dim1=-2, dim2=-1).fill_(math.inf)
        maybe = (dist.flatten(1).min(dim=1).values >= cfg.min_init_distance - 1e-3) & \
                ((dist <= cfg.R + 1e-3).sum(dim=-1).min(dim=-1).values >= cfg.min_neighbours)
        pos = pos[maybe]
        _, _, d2 = pairwise_offsets(pos)
        ok = (d2.flatten(1).min(dim=1).values >= dmin2) & \
             ((d2 <= R2).sum(dim=-1).min(dim=-1).values >= cfg.min_neighbours)
        tried += count
        good = pos[ok][: batch - accepted]
        if len(good):
            k = len(good)
            vel = cfg.v_init * (2 * torch.rand(k, N, 2, generator=generator, dtype=torch.float64) - 1)
            bias = cfg.bias_fraction * cfg.v_init * (
                2 * torch.rand(k, 1, 2, generator=generator, dtype=torch.float64) - 1)
            rs.append(good)
            vs.append(vel + bias)
            accepted += k
    return torch.cat(rs).to(dtype=dtype, device=device), torch.cat(vs).to(dtype=dtype, device=device)


def _disc(cfg: FlockConfig, count: int, generator: torch.Generator) -> torch.Tensor:
    """``count`` swarms of N positions uniform on the disc of radius cfg.init_radius (float64)."""
    radius = cfg.init_radius * torch.rand(count, cfg.N, generator=generator, dtype=torch.float64).sqrt()
    angle = 2 * math.pi * torch.rand(count, cfg.N, generator=generator, dtype=torch.float64)
    return torch.stack((radius * angle.cos(), radius * angle.sin()), dim=-1)


def _repair(pos: torch.Tensor, cfg: FlockConfig, generator: torch.Generator, max_rounds: int = 1000
            ) -> torch.Tensor:
    """Redraw, uniformly on the disc, every agent closer than min_init_distance to a lower-numbered
    agent, until no pair is too close (init_method="repair")."""
    dmin2 = cfg.min_init_distance ** 2
    for _ in range(max_rounds):
        _, _, d2 = pairwise_offsets(pos)
        bad = torch.tril(d2 < dmin2, diagonal=-1).any(dim=-1)  # (C, N): too close to an earlier agent
        if not bad.any():
            break
        fresh = _disc(cfg, pos.shape[0], generator)
        pos = torch.where(bad.unsqueeze(-1), fresh, pos)
    return pos


def saturate(u: torch.Tensor, cfg: FlockConfig) -> torch.Tensor:
    """The actuators' limit: each axis of the acceleration clamped to [-u_max, u_max] (30 m/s^2)."""
    return u.clamp(-cfg.u_max, cfg.u_max)


def step(r: torch.Tensor, v: torch.Tensor, u: torch.Tensor, cfg: FlockConfig
         ) -> tuple[torch.Tensor, torch.Tensor]:
    """One step of the double integrator with sampling period Ts (exact for constant u).

    r(t+1) = r(t) + v(t) Ts + u(t) Ts^2 / 2,    v(t+1) = v(t) + u(t) Ts.

    Args: r, v, u: (B, N, 2). ``u`` is applied as given (``rollout`` saturates it first).
    Returns: r(t+1), v(t+1), (B, N, 2) each.
    """
    check_state(r, v)
    if u.shape != r.shape:
        raise ValueError(f"u must have the shape of r, (B, N, 2) = {tuple(r.shape)}, got {tuple(u.shape)}")
    Ts = cfg.Ts
    return r + v * Ts + u * (0.5 * Ts * Ts), v + u * Ts


def velocity_variance(v: torch.Tensor) -> torch.Tensor:
    """The summand of eq. 1 at each step: (1/N) sum_i ||v_i(t) - vbar(t)||^2, (T, B, N, 2) -> (T, B)."""
    return (v - v.mean(dim=2, keepdim=True)).square().sum(-1).mean(-1)


def flocking_cost(v: torch.Tensor) -> torch.Tensor:
    """The flocking cost of eq. 1 for a velocity trajectory.

    cost = sum_t (1/N) sum_i || v_i(t) - (1/N) sum_j v_j(t) ||^2, summed over t = 0 ... T-1.

    Args: v: (T, B, N, 2). Returns: (B,).
    """
    if not isinstance(v, torch.Tensor) or v.ndim != 4 or v.shape[-1] != 2:
        shape = tuple(v.shape) if isinstance(v, torch.Tensor) else type(v).__name__
        raise ValueError(f"flocking_cost expects velocities of shape (T, B, N, 2), got {shape}")
    return velocity_variance(v).sum(dim=0)


class Controller(Protocol):
    """Anything that maps the swarm's state to accelerations: ``u = controller(r, v)``.

    r, v, u have shape (B, N, 2). A controller may define ``reset()``; ``rollout`` calls it before
    the first step (learned controllers clear their delayed-communication buffers there).
    """

    def __call__(self, r: torch.Tensor, v: torch.Tensor) -> torch.Tensor: ...


@dataclass
class Trajectory:
    """A batch of rollouts. States and actions at t = 0 ... T-1 (time first).

    Attributes:
        r, v, u: (T, B, N, 2): positions, velocities and the (saturated) accelerations applied.
        cost: (B,) flocking cost of eq. 1 over the T states.
        min_distance: (T, B) smallest pair distance at each step.
    """

    r: torch.Tensor
    v: torch.Tensor
    u: torch.Tensor
    cost: torch.Tensor
    min_distance: torch.Tensor


@torch.no_grad()
def rollout(controller: Callable, cfg: FlockConfig, r0: torch.Tensor, v0: torch.Tensor,
            steps: Optional[int] = None) -> Trajectory:
    """Fly the swarms from (r0, v0) for ``steps`` steps (default ``cfg.T``) under ``controller``.

    At every step: u = saturate(controller(r, v)), then (r, v) = step(r, v, u). Gradients are off.
    Args: r0, v0: (B, N, 2). Returns: a Trajectory with T = steps.
    Raises: NonFiniteStateError, naming the step, swarm and agent, as soon as the controller returns
    a NaN or inf acceleration or the state stops being finite (nothing is clipped or carried on).
    """
    check_state(r0, v0, name="r0")
    steps = cfg.T if steps is None else steps
    if not isinstance(steps, int) or steps < 1:
        raise ValueError(f"steps must be a positive integer, got {steps!r}")
    if hasattr(controller, "reset"):
        controller.reset()
    r, v = r0, v0
    rs, vs, us, dmin = [], [], [], []
    for t in range(steps):
        u = controller(r, v)
        if not isinstance(u, torch.Tensor) or u.shape != r.shape:
            got = tuple(u.shape) if isinstance(u, torch.Tensor) else type(u).__name__
            raise ValueError(f"the controller must return accelerations of shape {tuple(r.shape)}, got {got}")
        check_finite(u, f"the acceleration {getattr(controller, 'name', type(controller).__name__)} returned", t)
        u = saturate(u, cfg)
        rs.append(r), vs.append(v), us.append(u), dmin.append(min_pair_distance(r))
        r, v = step(r, v, u, cfg)
        check_finite(torch.cat((r, v), dim=-1), "the state (r, v)", t + 1)
    vt = torch.stack(vs)
    return Trajectory(r=torch.stack(rs), v=vt, u=torch.stack(us), cost=flocking_cost(vt),
                      min_distance=torch.stack(dmin))

"""pymunk, the independent reference: ray-cast depth strips and rollouts with physical contacts.

Introduced in notebook 04. pymunk (Chipmunk2D) knows nothing of our renderer or simulator, so it
checks both: its ray caster measures, for every agent and panorama column, the distance to the first
drone body along the column's centre ray, which ``render.egocentric_depth`` must reproduce; and its
rigid-body world flies a controller with real contacts between the drones' bodies, which must
match ``flocking.step`` whenever no contact happens.

Everything here is per swarm and in float64 numpy/pymunk: slow and simple on purpose.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pymunk
import torch

from .config import FlockConfig
from .flocking import saturate
from .render import RenderConfig

RAY_RANGE = 1000.0  # m: far beyond any swarm


def column_bearings(rcfg: RenderConfig) -> np.ndarray:
    """World bearing (radians, CCW from +x) of every panorama column's centre ray, (4W,).

    Written out from the camera model on its own (not through render.py): camera c in (front,
    right, back, left) looks along bearing -c 90°; its column k sees the angle
    phi = atan((k + 0.5 - W/2) / f) to the right of its axis, f = W/2.
    """
    W = rcfg.view_width
    f = W / 2.0
    out = []
    for c in range(4):
        for k in range(W):
            phi = math.atan((k + 0.5 - W / 2) / f)
            out.append(-c * math.pi / 2 - phi)
    return np.array(out)


def _space_with_bodies(r: np.ndarray, radius: float, dynamic: bool):
    space = pymunk.Space()
    space.collision_slop = 1e-4  # m: pymunk's default (0.1) is meant for pixels, not metres
    bodies = []
    for i, (x, y) in enumerate(r):
        if dynamic:
            body = pymunk.Body(mass=1.0, moment=float("inf"))  # point masses that do not spin
        else:
            body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        body.position = (float(x), float(y))
        shape = pymunk.Circle(body, radius)
        shape.filter = pymunk.ShapeFilter(group=i + 1)  # agent i's rays ignore its own body
        shape.collision_type = 1
        shape.elasticity, shape.friction = 0.0, 0.0
        space.add(body, shape)
        bodies.append(body)
    return space, bodies


def raycast_depth(r, rcfg: RenderConfig = RenderConfig()) -> np.ndarray:
    """Depth strip of every agent of one swarm by ray casting: r (N, 2) -> (N, 4W) metres, inf on a miss.

    One ``segment_query_first`` per agent and column, with the agent's own ShapeFilter group so that
    its rays start inside its own body without hitting it.
    """
    r = np.asarray(r.detach().cpu().double() if isinstance(r, torch.Tensor) else r, dtype=float)
    if r.ndim != 2 or r.shape[1] != 2:
        raise ValueError(f"raycast_depth takes one swarm's positions (N, 2), got shape {r.shape}")
    space, _ = _space_with_bodies(r, rcfg.body_radius, dynamic=False)
    bearings = column_bearings(rcfg)
    dirs = np.stack((np.cos(bearings), np.sin(bearings)), axis=1)
    out = np.full((len(r), len(bearings)), np.inf)
    for i, start in enumerate(r):
        filt = pymunk.ShapeFilter(group=i + 1)
        for k, dvec in enumerate(dirs):
            end = start + RAY_RANGE * dvec
            hit = space.segment_query_first(tuple(start), tuple(end), 0.0, filt)
            if hit is not None:
                out[i, k] = hit.alpha * RAY_RANGE
    return out


@dataclass
class PymunkRollout:
    """One swarm flown in pymunk. r, v, u: (T, N, 2) numpy; contacts: pairs that began touching."""

    r: np.ndarray
    v: np.ndarray
    u: np.ndarray
    contacts: int


def rollout_pymunk(controller, cfg: FlockConfig, r0, v0, steps=None,
                   rcfg: RenderConfig = RenderConfig()) -> PymunkRollout:
    """Fly one swarm (r0, v0: (N, 2)) in pymunk under ``controller`` (called on (1, N, 2) tensors).

    Each drone is a unit-mass disc of radius ``rcfg.body_radius``; the commanded acceleration is
    saturated like ``rollout``'s and applied as a force (mass x acceleration) for one step of Ts.
    A pymunk step moves each body with the velocity it had at the step's start (r += v(t) Ts) and
    then updates the velocity (v += u Ts), which leaves a body u Ts^2 / 2 short of the exact double
    integrator of ``flocking.step``; we shift each body by that amount after every step so that,
    without contacts, both integrate the same dynamics. Contacts between
    bodies are resolved by pymunk (inelastic, frictionless) and counted.
    """
    steps = cfg.T if steps is None else steps
    r0 = np.asarray(r0, dtype=float)
    v0 = np.asarray(v0, dtype=float)
    space, bodies = _space_with_bodies(r0, rcfg.body_radius, dynamic=True)
    for body, vel in zip(bodies, v0):
        body.velocity = (float(vel[0]), float(vel[1]))
    contacts = [0]

    def begin(arbiter, space, data):
        contacts[0] += 1

    space.on_collision(1, 1, begin=begin)
    if hasattr(controller, "reset"):
        controller.reset()
    rs, vs, us = [], [], []
    for _ in range(steps):
        r = np.array([tuple(b.position) for b in bodies])
        v = np.array([tuple(b.velocity) for b in bodies])
        with torch.no_grad():
            u_t = controller(torch.tensor(r[None], dtype=torch.float64), torch.tensor(v[None], dtype=torch.float64))
        u = saturate(u_t, cfg)[0].cpu().double().numpy()
        rs.append(r), vs.append(v), us.append(u)
        for body, acc in zip(bodies, u):
            body.force = (float(acc[0]) * body.mass, float(acc[1]) * body.mass)
        space.step(cfg.Ts)
        for body, acc in zip(bodies, u):  # exact double integrator: r + v Ts + u Ts^2/2
            x, y = body.position
            body.position = (x + 0.5 * acc[0] * cfg.Ts ** 2, y + 0.5 * acc[1] * cfg.Ts ** 2)
    return PymunkRollout(np.array(rs), np.array(vs), np.array(us), contacts[0])

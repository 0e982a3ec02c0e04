"""The flocking problem of section 3.1: dynamics, initial conditions, cost, rollouts."""

import math

import pytest
import torch

from vgai_lite import (ExpertController, FlockConfig, flocking_cost, min_pair_distance, rollout,
                       sample_initial_state, step)
from vgai_lite.flocking import pairwise_offsets


def test_sampled_initial_states_satisfy_every_constraint():
    cfg = FlockConfig()
    r, v = sample_initial_state(cfg, 32, torch.Generator().manual_seed(3), dtype=torch.float64)
    assert r.shape == v.shape == (32, cfg.N, 2)
    _, _, d2 = pairwise_offsets(r)
    assert d2.min().sqrt() >= cfg.min_init_distance                      # nobody closer than 0.2 m
    assert (d2 <= cfg.R ** 2).sum(-1).min() >= cfg.min_neighbours        # everyone has 2 neighbours
    assert r.norm(dim=-1).max() <= cfg.init_radius                       # inside the N**0.25 disc
    assert math.isclose(cfg.init_radius, 50 ** 0.25)
    # velocities: uniform in [-v_init, v_init]^2 plus a flock bias in [-0.3 v_init, 0.3 v_init]^2
    assert v.abs().max() <= 1.3 * cfg.v_init
    spread = v.amax(dim=1) - v.amin(dim=1)                                 # per swarm and axis
    assert spread.max() <= 2 * cfg.v_init and spread.min() > 1.5 * cfg.v_init


def test_initial_positions_fill_the_disc_uniformly():
    cfg = FlockConfig(N=30, min_neighbours=0, min_init_distance=0.0)
    r, _ = sample_initial_state(cfg, 200, torch.Generator().manual_seed(0), dtype=torch.float64)
    rad = r.norm(dim=-1) / cfg.init_radius
    # uniform on a disc: P(radius <= a) = a^2
    assert abs((rad <= 0.5).double().mean().item() - 0.25) < 0.02


def test_sampling_is_reproducible_from_a_seed_and_independent_of_dtype():
    cfg = FlockConfig(N=20)
    a = sample_initial_state(cfg, 4, torch.Generator().manual_seed(7))
    b = sample_initial_state(cfg, 4, torch.Generator().manual_seed(7))
    c = sample_initial_state(cfg, 4, torch.Generator().manual_seed(8))
    d = sample_initial_state(cfg, 4, torch.Generator().manual_seed(7), dtype=torch.float64)
    assert torch.equal(a[0], b[0]) and torch.equal(a[1], b[1])
    assert not torch.equal(a[0], c[0])
    assert d[0].dtype == torch.float64 and torch.allclose(d[0].float(), a[0])


def test_impossible_initial_conditions_raise_instead_of_looping_forever():
    # the paper's text: a disc of radius sqrt(N); with R = 1.5 it never gives everyone 2 neighbours
    cfg = FlockConfig(init_radius_exponent=0.5, max_init_tries=20_000)
    with pytest.raises(RuntimeError, match="neighbours within R"):
        sample_initial_state(cfg, 2, torch.Generator().manual_seed(0))


def test_step_is_the_exact_double_integrator():
    cfg = FlockConfig(Ts=0.01)
    g = torch.Generator().manual_seed(0)
    r0, v0, u = (torch.randn(3, 5, 2, generator=g, dtype=torch.float64) for _ in range(3))
    r, v = r0, v0
    for _ in range(100):
        r, v = step(r, v, u, cfg)
    t = 100 * cfg.Ts
    torch.testing.assert_close(v, v0 + u * t)
    torch.testing.assert_close(r, r0 + v0 * t + 0.5 * u * t * t)


def test_flocking_cost_is_eq1():
    g = torch.Generator().manual_seed(0)
    v = torch.randn(7, 3, 5, 2, generator=g, dtype=torch.float64)
    manual = torch.zeros(3, dtype=torch.float64)
    for t in range(7):
        for b in range(3):
            vbar = v[t, b].mean(0)
            manual[b] += sum(((v[t, b, i] - vbar) ** 2).sum() for i in range(5)) / 5
    torch.testing.assert_close(flocking_cost(v), manual)
    # zero for a flock moving as one; blind to the flock's common velocity
    assert flocking_cost(torch.ones(4, 2, 6, 2)).abs().max() == 0
    torch.testing.assert_close(flocking_cost(v + torch.tensor([3.0, -1.0], dtype=torch.float64)), manual)


def test_the_expert_drives_velocity_variance_down():
    cfg = FlockConfig()
    r0, v0 = sample_initial_state(cfg, 8, torch.Generator().manual_seed(1))
    traj = rollout(ExpertController(cfg), cfg, r0, v0)
    var = (traj.v - traj.v.mean(2, keepdim=True)).square().sum(-1).mean(-1)  # (T, B)
    assert (var[-1] < 1e-3 * var[0]).all()
    assert traj.u.abs().max() <= cfg.u_max


def test_a_seed_gives_identical_rollouts():
    cfg = FlockConfig(N=20, T=50)
    runs = []
    for _ in range(2):
        r0, v0 = sample_initial_state(cfg, 3, torch.Generator().manual_seed(11))
        runs.append(rollout(ExpertController(cfg), cfg, r0, v0))
    assert torch.equal(runs[0].r, runs[1].r) and torch.equal(runs[0].cost, runs[1].cost)


def test_rollout_records_states_actions_cost_and_distances():
    cfg = FlockConfig(N=10, T=30)
    r0, v0 = sample_initial_state(cfg, 2, torch.Generator().manual_seed(0))
    traj = rollout(ExpertController(cfg), cfg, r0, v0)
    assert traj.r.shape == traj.v.shape == traj.u.shape == (30, 2, 10, 2)
    assert torch.equal(traj.r[0], r0) and torch.equal(traj.v[0], v0)
    torch.testing.assert_close(traj.cost, flocking_cost(traj.v))
    torch.testing.assert_close(traj.min_distance[5], min_pair_distance(traj.r[5]))
    r1, v1 = step(r0, v0, traj.u[0], cfg)
    torch.testing.assert_close(traj.r[1], r1)


def test_rollout_calls_reset_and_rejects_wrong_action_shapes():
    cfg = FlockConfig(N=10, T=5)
    r0, v0 = sample_initial_state(cfg, 2, torch.Generator().manual_seed(0))

    class Counting:
        resets = calls = 0

        def reset(self):
            self.resets += 1

        def __call__(self, r, v):
            self.calls += 1
            return torch.zeros_like(r)

    c = Counting()
    rollout(c, cfg, r0, v0)
    assert (c.resets, c.calls) == (1, 5)
    with pytest.raises(ValueError, match=r"shape \(2, 10, 2\)"):
        rollout(lambda r, v: torch.zeros(2, 10), cfg, r0, v0)


@pytest.mark.parametrize("bad, message", [
    (dict(N=1), "N must be"), (dict(R=0.0), "R must be"), (dict(Ts=-0.01), "Ts must be"),
    (dict(u_max=float("inf")), "u_max must be"), (dict(potential="quadratic"), "potential must be"),
    (dict(T=0), "T must be"), (dict(min_init_distance=2.0), "min_init_distance"),
    (dict(N=2, min_neighbours=2), "min_neighbours"),
])
def test_bad_configs_raise_clear_errors(bad, message):
    with pytest.raises(ValueError, match=message):
        FlockConfig(**bad)


def test_wrong_shapes_raise_clear_errors():
    cfg = FlockConfig()
    r = torch.zeros(50, 2)
    with pytest.raises(ValueError, match=r"\(B, N, 2\).*unsqueeze"):
        step(r, r, r, cfg)
    with pytest.raises(ValueError, match=r"\(T, B, N, 2\)"):
        flocking_cost(torch.zeros(3, 50, 2))
    with pytest.raises(ValueError, match="batch must be"):
        sample_initial_state(cfg, 0)
    with pytest.raises(ValueError, match="floating"):
        step(torch.zeros(1, 3, 2, dtype=torch.long), torch.zeros(1, 3, 2, dtype=torch.long),
             torch.zeros(1, 3, 2, dtype=torch.long), cfg)

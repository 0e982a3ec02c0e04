"""The centralized expert (eq. 2), the potential (eq. 3) and the local heuristic."""

import pytest
import torch

from vgai_lite import (FlockConfig, expert_control, local_control, potential, potential_gradient,
                       sample_initial_state)

NO_SAT = dict(u_max=1e12)  # turn saturation off to test the equations themselves


def close_swarm(cfg, B=4, seed=0):
    """Random swarms dense enough that many pairs sit inside rho (float64)."""
    g = torch.Generator().manual_seed(seed)
    r = 1.2 * torch.rand(B, cfg.N, 2, generator=g, dtype=torch.float64)
    v = torch.randn(B, cfg.N, 2, generator=g, dtype=torch.float64)
    return r, v


@pytest.mark.parametrize("which", ["paper", "reference"])
def test_expert_repulsion_is_minus_the_finite_difference_gradient_of_U(which):
    cfg = FlockConfig(N=12, potential=which, rho=0.7, **NO_SAT)
    r, _ = close_swarm(cfg)
    v = torch.zeros_like(r)  # no alignment term: u = -sum_j grad_{r_i} U(r_i, r_j)

    def total_U_of_agent(r, b, i):
        d2 = (r[b, i] - r[b]).square().sum(-1)
        d2 = torch.cat((d2[:i], d2[i + 1:]))
        return potential(d2, cfg).sum()

    u = expert_control(r, v, cfg)
    h = 1e-6
    for b in range(2):
        for i in range(cfg.N):
            grad = torch.zeros(2, dtype=torch.float64)
            for a in range(2):
                rp, rm = r.clone(), r.clone()
                rp[b, i, a] += h
                rm[b, i, a] -= h
                grad[a] = (total_U_of_agent(rp, b, i) - total_U_of_agent(rm, b, i)) / (2 * h)
            torch.testing.assert_close(u[b, i], -grad, rtol=1e-5, atol=1e-4)


def test_paper_potential_is_purely_repulsive_and_flat_beyond_rho():
    cfg = FlockConfig(rho=0.5)
    d = torch.linspace(0.05, 1.5, 300, dtype=torch.float64)
    U = potential(d ** 2, cfg)
    assert (U[d < 0.5].diff() < 0).all()                    # decreasing inside rho: repulsive
    assert torch.all(U[d > 0.5] == U[-1])                   # constant beyond rho
    r_ij = torch.stack((d, torch.zeros_like(d)), -1)
    g = potential_gradient(r_ij, cfg)
    assert torch.all(g[d > 0.5] == 0)                       # gradient vanishes beyond rho
    assert (g[d <= 0.5, 0] < 0).all()                       # -grad points away from j


def test_reference_potential_attracts_between_1m_and_rho():
    cfg = FlockConfig(rho=1.5, potential="reference")
    r_ij = torch.tensor([[0.5, 0.0], [1.2, 0.0]], dtype=torch.float64)
    g = potential_gradient(r_ij, cfg)
    assert g[0, 0] < 0 < g[1, 0]   # pushed away at 0.5 m, pulled in at 1.2 m


def test_expert_with_every_pair_beyond_rho_only_aligns():
    cfg = FlockConfig(N=5, **NO_SAT)
    r = torch.tensor([[[0.0, 0], [1, 0], [2, 0], [0, 1], [1, 1]]], dtype=torch.float64)
    v = torch.randn(1, 5, 2, dtype=torch.float64)
    torch.testing.assert_close(expert_control(r, v, cfg), 5 * (v.mean(1, keepdim=True) - v))


def test_without_saturation_the_expert_conserves_momentum():
    cfg = FlockConfig(N=20, **NO_SAT)
    r, v = close_swarm(cfg)
    u = expert_control(r, v, cfg)  # alignment and repulsion both cancel pairwise
    torch.testing.assert_close(u.sum(1), torch.zeros(4, 2, dtype=torch.float64), atol=1e-6, rtol=0)
    u = local_control(r, v, cfg)
    torch.testing.assert_close(u.sum(1), torch.zeros(4, 2, dtype=torch.float64), atol=1e-6, rtol=0)


def test_actions_are_saturated_per_axis():
    cfg = FlockConfig(N=20)
    r, v = close_swarm(cfg)
    for u in (expert_control(r, 10 * v, cfg), local_control(r, 10 * v, cfg)):
        assert u.abs().max() == cfg.u_max


@pytest.mark.parametrize("control", [expert_control, local_control])
def test_controllers_are_permutation_equivariant(control):
    cfg = FlockConfig()
    r, v = sample_initial_state(cfg, 3, torch.Generator().manual_seed(2), dtype=torch.float64)
    perm = torch.randperm(cfg.N, generator=torch.Generator().manual_seed(5))
    torch.testing.assert_close(control(r[:, perm], v[:, perm], cfg), control(r, v, cfg)[:, perm])


def test_local_equals_expert_when_R_covers_everyone():
    cfg = FlockConfig(N=20, R=100.0)
    r, v = close_swarm(cfg)
    torch.testing.assert_close(local_control(r, v, cfg), expert_control(r, v, cfg))


def test_local_uses_only_neighbours_within_R():
    cfg = FlockConfig(N=3, R=1.5, **NO_SAT)
    r = torch.tensor([[[0.0, 0.0], [1.0, 0.0], [3.0, 0.0]]], dtype=torch.float64)
    v = torch.tensor([[[0.0, 0.0], [1.0, 0.0], [0.0, 5.0]]], dtype=torch.float64)
    u = local_control(r, v, cfg)
    # agent 0 hears only agent 1: -(v0 - v1) = [1, 0]; agent 2 hears nobody
    torch.testing.assert_close(u[0, 0], torch.tensor([1.0, 0.0], dtype=torch.float64))
    torch.testing.assert_close(u[0, 2], torch.zeros(2, dtype=torch.float64))


def test_float32_and_float64_agree():
    cfg = FlockConfig()
    r, v = sample_initial_state(cfg, 4, torch.Generator().manual_seed(0), dtype=torch.float64)
    torch.testing.assert_close(expert_control(r.float(), v.float(), cfg).double(),
                               expert_control(r, v, cfg), atol=1e-3, rtol=1e-4)

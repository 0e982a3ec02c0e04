"""Section 3.2: the communication graph, GSOs (eq. 5) and the delayed aggregation sequence (eq. 6)."""

import pytest
import torch

from vgai_lite import FlockConfig, sample_initial_state
from vgai_lite.aggregation import AggregationBuffer, aggregation_sequence
from vgai_lite.controllers import ExpertController
from vgai_lite.flocking import rollout
from vgai_lite.graphs import GSO_KINDS, adjacency, gso, k_hop_reach


def swarm_traj(T=12, B=2, N=15, seed=0):
    cfg = FlockConfig(N=N, T=T)
    r0, v0 = sample_initial_state(cfg, B, torch.Generator().manual_seed(seed), dtype=torch.float64)
    return cfg, rollout(ExpertController(cfg), cfg, r0, v0)


def test_adjacency_is_symmetric_without_self_loops_and_respects_R():
    cfg, traj = swarm_traj()
    r = traj.r[0]
    A = adjacency(r, cfg.R)
    assert torch.equal(A, A.transpose(1, 2))
    assert A.diagonal(dim1=1, dim2=2).abs().sum() == 0
    d = torch.cdist(r, r)
    off = ~torch.eye(cfg.N, dtype=torch.bool)
    assert torch.equal(A.bool()[:, off], (d <= cfg.R)[:, off])
    with pytest.raises(ValueError, match="R must be > 0"):
        adjacency(r, 0.0)


@pytest.mark.parametrize("kind", GSO_KINDS)
def test_every_gso_respects_the_graph_so_SX_needs_one_hop_only(kind):
    cfg, traj = swarm_traj()
    A = adjacency(traj.r[0], cfg.R)
    S = gso(A, kind)
    off = ~torch.eye(cfg.N, dtype=torch.bool)
    assert (S[:, off][A[:, off] == 0] == 0).all()
    # moving the features of a non-neighbour j of i leaves [S X]_i unchanged
    X = torch.randn(2, cfg.N, 3, dtype=torch.float64)
    i = 0
    non = [j for j in range(cfg.N) if j != i and A[0, i, j] == 0]
    X2 = X.clone()
    X2[0, non] += 10.0
    torch.testing.assert_close((S @ X)[0, i], (S @ X2)[0, i])


@pytest.mark.parametrize("kind, lo, hi", [("row_normalized", -1, 1), ("sym_normalized", -1, 1),
                                          ("spectral_normalized", -1, 1), ("laplacian", 0, None)])
def test_gso_spectra_lie_where_the_docstring_says(kind, lo, hi):
    cfg, traj = swarm_traj()
    A = adjacency(traj.r[0], cfg.R)
    eig = torch.linalg.eigvals(gso(A, kind)).real
    assert eig.min() >= lo - 1e-9
    assert eig.max() <= (hi if hi is not None else 2 * A.sum(-1).max()) + 1e-9


def test_unknown_gso_is_refused():
    with pytest.raises(ValueError, match="unknown GSO kind"):
        gso(torch.zeros(1, 3, 3), "magic")


def test_step_by_step_buffer_equals_the_unrolled_sequence():
    cfg, traj = swarm_traj(T=10)
    K = 4
    X = torch.randn(10, 2, cfg.N, 5, dtype=torch.float64)
    S = torch.stack([gso(adjacency(traj.r[t], cfg.R)) for t in range(10)])
    buf = AggregationBuffer(K)
    stepwise = torch.stack([buf.push(X[t], S[t]) for t in range(10)], dim=1)  # (B, T, N, K, F)
    unrolled = aggregation_sequence(X.transpose(0, 1), S.transpose(0, 1), K)
    torch.testing.assert_close(stepwise, unrolled)
    # block k at time t is S(t) ... S(t-k+1) X(t-k), written out for t = 6, k = 3
    t = 6
    torch.testing.assert_close(unrolled[:, t, :, 3], S[6] @ S[5] @ S[4] @ X[3])
    assert unrolled[:, 1, :, 2].abs().sum() == 0  # nothing from before the episode


def test_message_passing_with_only_received_messages_gives_the_same_Z():
    """Each agent keeps only what it computed or received from a neighbour in the previous exchange."""
    cfg, traj = swarm_traj(T=8, B=1, N=10)
    K, F, T = 3, 2, 8
    X = torch.randn(T, 1, cfg.N, F, dtype=torch.float64)
    S = [gso(adjacency(traj.r[t], cfg.R))[0] for t in range(T)]
    held = [[torch.zeros(F, dtype=torch.float64) for _ in range(K)] for _ in range(cfg.N)]
    buf = AggregationBuffer(K)
    for t in range(T):
        inbox = [[] for _ in range(cfg.N)]  # messages: (weight s_ij, the K-1 blocks agent j held)
        for j in range(cfg.N):
            for i in range(cfg.N):
                if i != j and S[t][i, j] != 0:
                    inbox[i].append((S[t][i, j], held[j][: K - 1]))
        new = []
        for i in range(cfg.N):
            blocks = [X[t, 0, i]]
            for k in range(1, K):
                blocks.append(sum((w * msg[k - 1] for w, msg in inbox[i]), torch.zeros(F, dtype=torch.float64)))
            new.append(blocks)
        held = new
        Z = buf.push(X[t], S[t].unsqueeze(0))
        for i in range(cfg.N):
            torch.testing.assert_close(Z[0, i], torch.stack(held[i]))


def test_block_k_only_hears_agents_within_k_hops():
    cfg, traj = swarm_traj(T=6, B=1, N=20, seed=3)
    K = 4
    S = torch.stack([gso(adjacency(traj.r[t], cfg.R)) for t in range(6)], dim=1)  # (1, T, N, N)
    X = torch.randn(1, 6, cfg.N, 1, dtype=torch.float64, requires_grad=True)
    Z = aggregation_sequence(X, S, K)
    A_union = (adjacency(traj.r[:, 0], cfg.R).sum(0) > 0).double()  # any link during the window
    for k in range(K):
        grad, = torch.autograd.grad(Z[0, -1, 0, k].sum(), X, retain_graph=True)
        influencers = grad[0].abs().sum(dim=(0, 2)) > 0
        reach = k_hop_reach(A_union.unsqueeze(0), k)[0, 0]
        assert not (influencers & ~reach).any()

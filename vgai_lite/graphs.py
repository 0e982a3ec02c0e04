"""Who hears whom: the communication graph G(t) and its graph shift operators S(t).

Introduced in notebook 02. Paper, section 3.2: agents i and j communicate at time t iff
||r_i(t) - r_j(t)|| <= R; a graph shift operator (GSO) S(t) is any N x N matrix with
[S(t)]_ij != 0 only if j is a neighbour of i, so that [S X]_i = sum_{j in N_i} s_ij x_j needs
only one exchange with one-hop neighbours (eq. 5).

Shapes: positions r (B, N, 2); adjacency and GSOs (B, N, N); features X (B, N, F).
"""

from __future__ import annotations

import torch

from .flocking import check_state, pairwise_offsets

GSO_KINDS = ("adjacency", "row_normalized", "sym_normalized", "laplacian", "spectral_normalized")
DEFAULT_GSO = "sym_normalized"


def adjacency(r: torch.Tensor, R: float) -> torch.Tensor:
    """Binary adjacency A(t): A_ij = 1 iff j != i and ||r_i - r_j|| <= R. (B, N, 2) -> (B, N, N)."""
    check_state(r)
    if not R > 0:
        raise ValueError(f"the communication radius R must be > 0, got {R!r}")
    _, _, d2 = pairwise_offsets(r)
    return (d2 <= R * R).to(r.dtype)


def gso(A: torch.Tensor, kind: str = DEFAULT_GSO) -> torch.Tensor:
    """The graph shift operator S(t) of eq. 5, built from the binary adjacency A, (B, N, N) -> (B, N, N).

    kind (spectrum for an undirected graph; D = diag(degrees)):
      "adjacency"            S = A                     eigenvalues in [-d_max, d_max]
      "row_normalized"       S = D^-1 A (mean of the neighbours' values; rows of isolated agents
                             are zero)                 eigenvalues in [-1, 1]
      "sym_normalized"       S = D^-1/2 A D^-1/2       eigenvalues in [-1, 1], symmetric
      "laplacian"            S = D - A                 eigenvalues in [0, 2 d_max], symmetric
      "spectral_normalized"  S = A / lambda_max(A)     eigenvalues in [-1, 1], symmetric

    The DAGNN uses "sym_normalized" by default (the paper does not say which it uses; the public
    reference code averages, "row_normalized"). Measured in notebook 03: summing ("adjacency")
    imitates best at the training size N = 50 but its features grow with density and the
    controller fails at N' = 100; averaging ("row_normalized") transfers perfectly but imitates
    worse at N = 50; the symmetric normalisation does both. Every kind is local: S_ij = 0 unless j is a neighbour of i, or j = i (the
    Laplacian's diagonal, which an agent knows without communicating); the spectral
    normalisation's lambda_max is a global number that no agent can compute alone.
    """
    if A.ndim != 3 or A.shape[-1] != A.shape[-2]:
        raise ValueError(f"A must be a batch of square adjacency matrices (B, N, N), got {tuple(A.shape)}")
    deg = A.sum(dim=-1)
    if kind == "adjacency":
        return A
    if kind == "row_normalized":
        return A / deg.clamp(min=1).unsqueeze(-1)
    if kind == "sym_normalized":
        s = deg.clamp(min=1).rsqrt()
        return s.unsqueeze(-1) * A * s.unsqueeze(-2)
    if kind == "laplacian":
        return torch.diag_embed(deg) - A
    if kind == "spectral_normalized":
        lam = torch.linalg.eigvalsh(A.double()).amax(dim=-1).to(A.dtype).clamp(min=1e-12)
        return A / lam[:, None, None]
    raise ValueError(f"unknown GSO kind {kind!r}; expected one of {GSO_KINDS}")


def k_hop_reach(A: torch.Tensor, k: int) -> torch.Tensor:
    """Boolean (B, N, N): j can reach i in at most k hops (i itself included) on the graph A."""
    N = A.shape[-1]
    reach = torch.eye(N, dtype=torch.bool, device=A.device).expand_as(A).clone()
    step = (A > 0) | reach
    for _ in range(k):
        reach = (step.to(A.dtype) @ reach.to(A.dtype)) > 0
    return reach

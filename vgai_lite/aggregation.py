"""The delayed aggregation sequence Z(t) of eq. 6, in two equivalent forms.

Introduced in notebook 02. With K taps,

    Z(t) = [ X(t), S(t) X(t-1), S(t) S(t-1) X(t-2), ..., S(t) ... S(t-K+2) X(t-K+1) ],

one (N, F) block per tap, so Z_k(t) = S(t) Z_{k-1}(t-1): at each time step every agent receives,
from each neighbour, the blocks that neighbour held one step earlier, and adds them up (weighted by
S). Block k therefore holds information from k hops away, k steps old. Nothing is known before the
episode starts: X(t) = 0 for t < 0.

Shapes: X (B, N, F), S (B, N, N), Z (B, N, K, F); flatten the last two axes to get the paper's
z_i(t) in R^{KF}.
"""

from __future__ import annotations

from typing import Optional

import torch


def _check_K(K: int) -> None:
    if not isinstance(K, int) or K < 1:
        raise ValueError(f"K (number of taps, K-1 exchanges) must be an integer >= 1, got {K!r}")


class AggregationBuffer:
    """Step-by-step Z(t), as each agent builds it during a rollout.

    The buffer keeps the last Z; ``push(X, S)`` returns Z(t) = [X(t), S(t) Z_0(t-1), ..., S(t) Z_{K-2}(t-1)]
    and keeps it for the next step (zero before the episode's first). ``reset()`` forgets it (call it
    when an episode starts).
    """

    def __init__(self, K: int):
        _check_K(K)
        self.K = K
        self.Z: Optional[torch.Tensor] = None  # Z(t-1): the messages the neighbours sent last step

    def reset(self) -> None:
        self.Z = None

    def push(self, X: torch.Tensor, S: torch.Tensor) -> torch.Tensor:
        """X (B, N, F), S (B, N, N) at time t -> Z(t) (B, N, K, F)."""
        if X.ndim != 3 or S.shape != (X.shape[0], X.shape[1], X.shape[1]):
            raise ValueError(f"expected X (B, N, F) and S (B, N, N), got {tuple(X.shape)} and {tuple(S.shape)}")
        if self.Z is not None and self.Z.shape[:2] != X.shape[:2]:
            raise ValueError(f"the buffer holds {tuple(self.Z.shape[:2])} (B, N) but X is "
                             f"{tuple(X.shape[:2])}: call reset() between episodes of other sizes")
        blocks = [X]
        if self.K > 1:
            prev = self.Z[:, :, : self.K - 1] if self.Z is not None else X.new_zeros(
                X.shape[0], X.shape[1], self.K - 1, X.shape[2])
            # [S prev_k]_i = sum_j S_ij prev_k[j]: one exchange with the neighbours for every k
            shifted = torch.einsum("bij,bjkf->bikf", S, prev)
            blocks.append(shifted)
        self.Z = torch.cat([blocks[0].unsqueeze(2)] + blocks[1:], dim=2)
        return self.Z


def aggregation_sequence(X: torch.Tensor, S: torch.Tensor, K: int) -> torch.Tensor:
    """Unrolled Z(t) for every t of a window of consecutive steps (zero history before it).

    Args:
        X: (B, W, N, F) features at times 0 ... W-1 of the window.
        S: (B, W, N, N) GSOs at the same times.
        K: taps.
    Returns:
        Z: (B, W, N, K, F), Z[:, t, :, k] = S(t) S(t-1) ... S(t-k+1) X(t-k) (zero when t-k < 0).
    If the window starts at the episode's start, this equals ``AggregationBuffer`` step by step;
    otherwise Z(t) is exact from the window's K-th step on. Differentiable in X (and S).
    """
    _check_K(K)
    if X.ndim != 4 or S.shape != (X.shape[0], X.shape[1], X.shape[2], X.shape[2]):
        raise ValueError(f"expected X (B, W, N, F) and S (B, W, N, N), got {tuple(X.shape)} and {tuple(S.shape)}")
    W = X.shape[1]
    blocks = [X]  # block k at every time: (B, W, N, F)
    for _ in range(1, K):
        prev = blocks[-1]
        shifted = torch.zeros_like(prev)
        if W > 1:
            # block_k(t) = S(t) block_{k-1}(t-1)
            shifted = torch.cat((torch.zeros_like(prev[:, :1]),
                                 torch.einsum("bwij,bwjf->bwif", S[:, 1:], prev[:, :-1])), dim=1)
        blocks.append(shifted)
    return torch.stack(blocks, dim=3)

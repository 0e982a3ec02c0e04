"""The exact local features of the DAGNN baseline (Tolstaya et al. 2019; VGAI paper, section 3.2).

Introduced in notebook 03. For agent i with neighbours N_i(t) = {j != i : ||r_ij|| <= R}:

    x_i(t) = [ sum_{j in N_i} (v_i - v_j),  sum_{j in N_i} r_ij / ||r_ij||^4,  sum_{j in N_i} r_ij / ||r_ij||^2 ]

(x and y of each: F = 6). Every term uses one-hop information only: a neighbour's relative
position and relative velocity, which a drone can measure or be told by that neighbour. The first
term is the local heuristic's alignment, the other two carry the repulsion of eq. 3.
"""

from __future__ import annotations

import torch

from .config import DISTANCE_FLOOR
from .flocking import check_state, pairwise_offsets

N_LOCAL_FEATURES = 6
"""F of the DAGNN: the x and y of the three sums above."""
FEATURE_NAMES = ("sum dv_x", "sum dv_y", "sum r_x/r^4", "sum r_y/r^4", "sum r_x/r^2", "sum r_y/r^2")


def local_features(r: torch.Tensor, v: torch.Tensor, R: float, per_neighbour: bool = False) -> torch.Tensor:
    """The 6 exact local features of every agent: the state matrix X(t) of eq. 4, one row x_i(t)
    per agent. r, v: (B, N, 2) -> X: (B, N, 6). ``per_neighbour``: each sum divided by the agent's
    number of neighbours |N_i| (at least 1), a mean that does not grow with the density of the team.

    Order: [sum (v_i - v_j) (x, y), sum r_ij/||r_ij||^4 (x, y), sum r_ij/||r_ij||^2 (x, y)].
    ||r_ij|| is floored at config.DISTANCE_FLOOR (1 mm), as in the expert's potential: coincident
    agents add 0 to the repulsion features instead of NaN.
    """
    check_state(r, v)
    dx, dy, d2 = pairwise_offsets(r)
    A = (d2 <= R * R).to(r.dtype)
    inv2 = torch.where(d2 <= R * R, d2.clamp(min=DISTANCE_FLOOR ** 2), torch.inf).reciprocal()  # 1/||r_ij||^2 on edges, else 0
    inv4 = inv2 * inv2
    dv = A.sum(-1, keepdim=True) * v - A @ v
    rep4 = torch.stack(((inv4 * dx).sum(-1), (inv4 * dy).sum(-1)), dim=-1)
    rep2 = torch.stack(((inv2 * dx).sum(-1), (inv2 * dy).sum(-1)), dim=-1)
    X = torch.cat((dv, rep4, rep2), dim=-1)
    return X / A.sum(-1, keepdim=True).clamp(min=1.0) if per_neighbour else X


def signed_log(x: torch.Tensor) -> torch.Tensor:
    """sign(x) log(1 + |x|): keeps small values, compresses the 1/r^3-sized repulsion features."""
    return torch.sign(x) * torch.log1p(x.abs())

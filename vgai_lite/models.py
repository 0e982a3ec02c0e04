"""The learned parts: the aggregation MLP (eqs. 7-8) and the DAGNN controller built on it.

Introduced in notebook 03. Shapes: Z (..., K, F) -> u (..., 2); a controller maps the swarm's state
r, v (B, N, 2) to accelerations (B, N, 2).
"""

from __future__ import annotations

from typing import Sequence

import torch
from torch import nn

from .aggregation import AggregationBuffer
from .config import FlockConfig
from .features import local_features, signed_log
from .flocking import saturate
from .graphs import DEFAULT_GSO, GSO_KINDS, adjacency, gso

FEATURE_TRANSFORMS = ("signed_log", "none")


class AggregationMLP(nn.Module):
    """NN_Theta of eqs. 7-8: the same MLP on every agent's row z_i(t) in R^{KF}, at every time.

    z_0 = (z_i(t) - mean) / std   (fixed normalisation, estimated once from training data)
    z_l = sigma(theta_l z_{l-1}),  l = 1 ... L-1;   u_i(t) = theta_L z_{L-1}  (F_L = 2, no activation)

    Args:
        K: taps of the aggregation sequence; F: features per tap; hidden: hidden layer widths.
    The output is not saturated here (the loss sees the raw output); controllers saturate it.
    """

    def __init__(self, K: int, F: int, hidden: Sequence[int] = (64, 64)):
        super().__init__()
        if K < 1 or F < 1 or any(h < 1 for h in hidden):
            raise ValueError(f"K, F and hidden widths must be >= 1, got K={K}, F={F}, hidden={hidden}")
        self.K, self.F, self.hidden = K, F, tuple(int(h) for h in hidden)
        self.register_buffer("z_mean", torch.zeros(K * F))
        self.register_buffer("z_std", torch.ones(K * F))
        layers, width = [], K * F
        for h in self.hidden:
            layers += [nn.Linear(width, h), nn.Tanh()]
            width = h
        layers.append(nn.Linear(width, 2))
        self.net = nn.Sequential(*layers)

    @torch.no_grad()
    def set_normalization(self, Z: torch.Tensor) -> None:
        """Estimate the input normalisation from samples Z (M, K, F)."""
        z = Z.reshape(-1, self.K * self.F).to(self.z_mean)
        self.z_mean.copy_(z.mean(0))
        self.z_std.copy_(z.std(0).clamp(min=1e-6))

    def forward(self, Z: torch.Tensor) -> torch.Tensor:
        if Z.shape[-2:] != (self.K, self.F):
            raise ValueError(f"expected Z of shape (..., K, F) = (..., {self.K}, {self.F}), got {tuple(Z.shape)}")
        z = (Z.flatten(-2) - self.z_mean) / self.z_std
        return self.net(z)


class DAGNNController:
    """The paper's DAGNN baseline as a controller: exact local features -> Z(t) -> MLP -> u.

    At each call: X(t) = transform(local_features(r, v)) (B, N, 6); S(t) = GSO of the graph of
    radius R; Z(t) from the agents' delayed-exchange buffer; u = saturate(MLP(Z(t))). The buffer
    holds the previous exchange's messages, so call ``reset()`` when an episode starts (``rollout``
    does). Works for any number of agents N.
    """

    name = "DAGNN"

    def __init__(self, model: AggregationMLP, cfg: FlockConfig, gso_kind: str = DEFAULT_GSO,
                 feature_transform: str = "none"):
        if gso_kind not in GSO_KINDS:
            raise ValueError(f"unknown GSO kind {gso_kind!r}; expected one of {GSO_KINDS}")
        if feature_transform not in FEATURE_TRANSFORMS:
            raise ValueError(f"feature_transform must be one of {FEATURE_TRANSFORMS}, got {feature_transform!r}")
        if model.F != 6:
            raise ValueError(f"the DAGNN uses the 6 exact local features, but the model expects F={model.F}")
        self.model, self.cfg = model, cfg
        self.gso_kind, self.feature_transform = gso_kind, feature_transform
        self.buffer = AggregationBuffer(model.K)

    @property
    def K(self) -> int:
        return self.model.K

    def reset(self) -> None:
        self.buffer.reset()

    def features(self, r: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
        """X(t), (B, N, 6): the exact local features (optionally signed-log transformed)."""
        X = local_features(r, v, self.cfg.R)
        return signed_log(X) if self.feature_transform == "signed_log" else X

    def observe(self, r: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
        """One exchange: push X(t), S(t) into the buffer and return Z(t), (B, N, K, 6)."""
        S = gso(adjacency(r, self.cfg.R), self.gso_kind)
        return self.buffer.push(self.features(r, v), S)

    def act(self, Z: torch.Tensor) -> torch.Tensor:
        return saturate(self.model(Z), self.cfg)

    def __call__(self, r: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
        return self.act(self.observe(r, v))

    def spec(self) -> dict:
        """What ``load_controller`` needs to rebuild this controller (plain values only)."""
        return {"kind": "dagnn", "K": self.model.K, "F": self.model.F, "hidden": list(self.model.hidden),
                "gso": self.gso_kind, "feature_transform": self.feature_transform}

    def __repr__(self) -> str:
        return (f"DAGNNController(K={self.K} taps = {self.K - 1} exchanges, hidden={self.model.hidden}, "
                f"gso={self.gso_kind!r}, R={self.cfg.R})")

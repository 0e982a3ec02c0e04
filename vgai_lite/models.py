"""The learned parts as torch modules: the aggregation MLP NN_Theta (eqs. 7-8, notebook 03) and the
visual CNN CNN_Psi (section 3.3, figure 2, notebook 05), and VGAI's pair of them (section 3.4).

Only the networks live here (flown by ``learned_controllers``, fed by ``vision``, trained by ``*_training``). Shapes: Z (..., K, F) -> u (..., 2); images (M, C, H, W) -> x (M, F).
"""

from __future__ import annotations

from typing import Sequence

import torch
import torch.nn.functional as nnf
from torch import nn

from .features import N_LOCAL_FEATURES


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


# ---------------------------------------------------------------------------------------------
# The visual state estimator CNN_Psi (section 3.3, figure 2) and VGAI's two networks (section 3.4)

class ResidualBlock(nn.Module):
    """Two convolutions with a skip connection, then average pooling along the vertical axis only.

    y = pool_rows( relu( conv2(relu(conv1(x))) + skip(x) ) ),  pool_rows averages ``pool`` rows into
    one and never touches the columns: every column keeps its bearing.
    Shapes: (M, c_in, H, W) -> (M, c_out, H / pool, W).
    """

    def __init__(self, c_in: int, c_out: int, kernel=(3, 3), pool: int = 1):
        super().__init__()
        pad = (kernel[0] // 2, kernel[1] // 2)
        self.conv1 = nn.Conv2d(c_in, c_out, kernel, padding=pad)
        self.conv2 = nn.Conv2d(c_out, c_out, kernel, padding=pad)
        self.skip = nn.Conv2d(c_in, c_out, 1) if c_in != c_out else nn.Identity()
        self.pool = nn.AvgPool2d((pool, 1)) if pool > 1 else nn.Identity()

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = self.conv2(torch.relu(self.conv1(x)))
        return self.pool(torch.relu(y + self.skip(x)))


class VisualCNN(nn.Module):
    """CNN_Psi: one agent's image H_i(t) -> F visual features x_i(t) (paper: four residual blocks and
    two fully connected layers, average pooling along the vertical axis only).

    Layout (input (M, C, H, W); the panorama's W columns survive to the first fully connected layer):
      stem      conv 3x3, C -> w1, stride 2 along rows only        -> (w1, H/2, W)
      block 1   residual 3x3, w1 -> w1, pool all H/2 rows into one -> (w1, 1, W)
      block 2-4 residual 1x3, w1 -> w2 -> w2 -> w2 (along the columns, i.e. bearings)
      fc        (w2 W) -> hidden -> F
    ``aux`` is an extra linear head F -> 6 used only to warm-start the CNN on the exact local
    features (visual state estimation); the controller never uses it.
    """

    motion_features = 0
    """F_m, the features odd in the motion channels: none in the paper's CNN (see ``OddMotionCNN``)."""

    def __init__(self, in_channels: int, height: int, width: int, F: int = 24,
                 widths: Sequence[int] = (8, 16), hidden: int = 64):
        super().__init__()
        if height % 2 or height < 2:
            raise ValueError(f"VisualCNN needs an even image height >= 2, got {height}")
        w1, w2 = widths
        self.in_channels, self.height, self.width, self.F = in_channels, height, width, F
        self.widths, self.hidden = (int(w1), int(w2)), int(hidden)
        self.stem = nn.Conv2d(in_channels, w1, 3, stride=(2, 1), padding=1)
        self.blocks = nn.Sequential(ResidualBlock(w1, w1, (3, 3), pool=height // 2),
                                    ResidualBlock(w1, w2, (1, 3)), ResidualBlock(w2, w2, (1, 3)),
                                    ResidualBlock(w2, w2, (1, 3)))
        self.fc = nn.Sequential(nn.Flatten(), nn.Linear(w2 * width, hidden), nn.ReLU(), nn.Linear(hidden, F))
        self.aux = nn.Linear(F, N_LOCAL_FEATURES)
        self.register_buffer("aux_mean", torch.zeros(N_LOCAL_FEATURES))  # scale of the exact features aux estimates
        self.register_buffer("aux_std", torch.ones(N_LOCAL_FEATURES))

    def spec(self) -> dict:
        """The architecture as plain values (F aside), as checkpoint files store it (``cnn_from_spec``)."""
        return {"in_channels": self.in_channels, "height": self.height, "width": self.width,
                "widths": list(self.widths), "hidden": self.hidden}

    def aux_standardized(self, x: torch.Tensor) -> torch.Tensor:
        """The aux head on features x (M, F): the standardised estimate of the 6 local features, (M, 6)."""
        return self.aux(x)

    def estimate_local_features(self, images: torch.Tensor) -> torch.Tensor:
        """The warm-start head's estimate of the 6 exact local features, (M, C, H, W) -> (M, 6)."""
        return self.aux_standardized(self(images)) * self.aux_std + self.aux_mean

    def trunk(self, images: torch.Tensor) -> torch.Tensor:
        """psi: stem, residual blocks and fully connected layers, (M, C, H, W) -> (M, F)."""
        # channels-last: the same numbers, a backward pass twice as fast on CPU (0.097 -> 0.048 s per 400 images)
        images = images.contiguous(memory_format=torch.channels_last)
        return self.fc(self.blocks(torch.relu(self.stem(images))))

    def _check(self, images: torch.Tensor) -> None:
        if images.shape[1:] != (self.in_channels, self.height, self.width):
            raise ValueError(f"VisualCNN expects images (M, {self.in_channels}, {self.height}, {self.width}), "
                             f"got {tuple(images.shape)}")

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        """(M, C, H, W) -> (M, F)."""
        self._check(images)
        return self.trunk(images)

    def flops_per_image(self) -> int:
        """Multiply-adds x 2 of one forward pass (convolutions and linear layers)."""
        total, h, w = 0, self.height, self.width
        w1, w2 = self.widths
        h2 = h // 2
        total += 2 * 9 * self.stem.in_channels * w1 * h2 * w                    # stem
        total += 2 * 2 * 9 * w1 * w1 * h2 * w                                   # block 1
        total += 2 * 3 * (w1 * w2 + w2 * w2) * w + 2 * w1 * w2 * w              # block 2 (+ 1x1 skip)
        total += 2 * 2 * 2 * 3 * w2 * w2 * w                                    # blocks 3-4
        total += 2 * (w2 * w * self.hidden + self.hidden * self.F)              # fc
        return total * (2 if self.motion_features else 1)                       # two passes of the trunk


class OddMotionCNN(VisualCNN):
    """The CNN of the book's recipe: ``VisualCNN`` whose last ``motion_features`` F_m features are odd
    in the motion channels (the second half of the input's channels, D = 5 (I(t) - I(t-g))) and the
    first F - F_m even, by running the trunk psi on [I, D] and on [I, -D]:

        x_even = (psi(I, D) + psi(I, -D)) / 2,     x_odd = (psi(I, D) - psi(I, -D)) / 2

    A swarm whose drones all move alike shows every drone D = 0, so its odd features are exactly 0,
    and for small motions linear in D: a drone's estimate of its neighbours' relative velocities
    vanishes when they do, instead of a bias that depends on where they stand (the plain CNN's,
    notebook 11). The aux head reads the 2 velocity features from the odd features only (no bias),
    the 4 position features from the even ones. It costs a second pass of the trunk. With ``pairing``
    "stack" (images [I(t), I(t-g)]) the trunk reads one frame at a time and motion is the change of its
    reading, x_odd = s (psi(I(t)) - psi(I(t-g))), s = ``motion_scale``: to first order s dpsi/dI (I(t) -
    I(t-g)), as the difference mode's odd features are s dpsi/dD (I(t) - I(t-g)).
    """

    def __init__(self, in_channels: int, height: int, width: int, F: int = 24,
                 widths: Sequence[int] = (8, 16), hidden: int = 64, motion_features: int = 8,
                 pairing: str = "difference", motion_scale: float = 5.0):
        if not isinstance(motion_features, int) or not 0 < motion_features <= F:
            raise ValueError(f"motion_features must be an integer in [1, F] = [1, {F}], got {motion_features!r}")
        if in_channels % 2 or pairing not in ("difference", "stack"):
            raise ValueError(f"motion_features needs images whose second half of channels is the motion difference or "
                             f"the earlier frame (pairing 'difference' or 'stack'), got {in_channels} channels, pairing {pairing!r}")
        super().__init__(in_channels, height, width, F, widths, hidden)
        self.motion_features, self.pairing, self.motion_scale = motion_features, pairing, float(motion_scale)
        self.odd_gain = self.motion_scale if pairing == "stack" else 0.5  # x_odd = gain (y_plus - y_minus)
        if pairing == "stack":  # the trunk reads one frame: half the channels
            self.stem = nn.Conv2d(in_channels // 2, self.widths[0], 3, stride=(2, 1), padding=1)

    def spec(self) -> dict:
        return {**super().spec(), "motion_features": self.motion_features, "pairing": self.pairing, "motion_scale": self.motion_scale}

    def aux_standardized(self, x: torch.Tensor) -> torch.Tensor:
        """The aux head on features x (M, F), (M, 6): the velocity outputs read only the odd features
        (no bias), the position outputs only the even ones."""
        odd = torch.arange(self.F, device=x.device) >= self.F - self.motion_features
        vel = torch.arange(N_LOCAL_FEATURES, device=x.device) < 2
        mask = (vel[:, None] == odd[None, :]).to(x.dtype)  # (6, F)
        return nnf.linear(x, self.aux.weight * mask, self.aux.bias * (~vel).to(x.dtype))

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        """(M, C, H, W) -> (M, F): the first F - F_m features even in D, the last F_m odd."""
        self._check(images)
        c = self.in_channels // 2
        if self.pairing == "stack":  # I(t) and I(t-g)
            y_plus, y_minus = self.trunk(torch.cat((images[:, :c], images[:, c:]))).chunk(2)
        else:  # [I, D] and [I, -D]
            y_plus, y_minus = self.trunk(torch.cat((images, torch.cat((images[:, :c], -images[:, c:]), 1)))).chunk(2)
        even, odd = (y_plus + y_minus) / 2, (y_plus - y_minus) * self.odd_gain
        split = self.F - self.motion_features
        return torch.cat((even[:, :split], odd[:, split:]), dim=1)


def visual_cnn(in_channels: int, height: int, width: int, F: int = 24, widths: Sequence[int] = (8, 16),
               hidden: int = 64, motion_features: int = 0, pairing: str = "difference",
               motion_scale: float = 5.0) -> VisualCNN:
    """The paper's ``VisualCNN`` (motion_features 0) or the book's ``OddMotionCNN``."""
    args = (in_channels, height, width, F, widths, hidden)
    return OddMotionCNN(*args, motion_features, pairing, motion_scale) if motion_features else VisualCNN(*args)


def cnn_from_spec(spec: dict, F: int) -> VisualCNN:
    """The CNN a checkpoint's ``spec`` (``VisualCNN.spec``) describes, with F features."""
    return visual_cnn(spec["in_channels"], spec["height"], spec["width"], F, spec["widths"], spec["hidden"],
                      spec.get("motion_features", 0), spec.get("pairing", "difference"), spec.get("motion_scale", 5.0))


READOUTS = ("features", "local")  # what NN_Theta reads of each image: ``VGAIModel.read``


def read_width(readout: str, F: int):
    """Features per tap NN_Theta reads under ``readout`` from a CNN of F features (None for an unknown readout)."""
    return {"features": F, "local": N_LOCAL_FEATURES}.get(readout)


class VGAIModel(nn.Module):
    """The two learned parts of VGAI, trained jointly: CNN_Psi and NN_Theta.

    ``features`` is every agent's x_i(t) = CNN_Psi(H_i(t)) as the MLP reads it (``read``); between the two
    networks sits the delayed aggregation Z(t) (eq. 6), step by step in the controller and unrolled over a
    window in training, and ``mlp`` maps Z(t) to the action (eqs. 7-8).
    """

    def __init__(self, cnn: VisualCNN, mlp: AggregationMLP, readout: str = "features"):
        super().__init__()
        width = read_width(readout, cnn.F)
        if mlp.F != width:
            raise ValueError(f"the MLP expects F={mlp.F} features per tap but the CNN gives F={width} "
                             f"(readout {readout!r}, one of {READOUTS})")
        self.cnn, self.mlp, self.readout = cnn, mlp, readout

    def read(self, X: torch.Tensor) -> torch.Tensor:
        """What NN_Theta reads of the CNN's features X (..., F): X ("features"), or the aux head's estimate of
        the 6 local features in their units ("local"), what the DAGNN's MLP reads exactly."""
        return X if self.readout == "features" else self.cnn.aux_standardized(X) * self.cnn.aux_std + self.cnn.aux_mean

    def features(self, images: torch.Tensor) -> torch.Tensor:
        """x_i(t) as the MLP reads it, for every agent: images (..., N, C, H, W) -> (..., N, mlp.F)."""
        lead = images.shape[:-3]
        return self.read(self.cnn(images.reshape(-1, *images.shape[-3:]))).view(*lead, self.mlp.F)

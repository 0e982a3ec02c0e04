"""The learned parts: the aggregation MLP (eqs. 7-8) and the DAGNN controller built on it.

Introduced in notebook 03. Shapes: Z (..., K, F) -> u (..., 2); a controller maps the swarm's state
r, v (B, N, 2) to accelerations (B, N, 2).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Sequence

import torch
from torch import nn

from .aggregation import AggregationBuffer
from .config import FlockConfig
from .features import local_features, signed_log
from .flocking import saturate
from .graphs import DEFAULT_GSO, GSO_KINDS, adjacency, gso
from .render import RenderConfig, render_egocentric, render_topdown, with_motion

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


# ---------------------------------------------------------------------------------------------
# The visual state estimator (section 3.3, figure 2) and the VGAI controller (section 3.4)

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
        self.aux = nn.Linear(F, 6)
        self.register_buffer("aux_mean", torch.zeros(6))  # scale of the exact features aux estimates
        self.register_buffer("aux_std", torch.ones(6))

    def estimate_local_features(self, images: torch.Tensor) -> torch.Tensor:
        """The warm-start head's estimate of the 6 exact local features, (M, C, H, W) -> (M, 6)."""
        return self.aux(self(images)) * self.aux_std + self.aux_mean

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        """(M, C, H, W) -> (M, F)."""
        if images.shape[1:] != (self.in_channels, self.height, self.width):
            raise ValueError(f"VisualCNN expects images (M, {self.in_channels}, {self.height}, {self.width}), "
                             f"got {tuple(images.shape)}")
        # channels-last layout: the same numbers, and on CPU the convolutions' backward pass runs
        # about twice as fast with it (measured: 0.097 s -> 0.048 s per 400-image step, 2 threads)
        images = images.contiguous(memory_format=torch.channels_last)
        return self.fc(self.blocks(torch.relu(self.stem(images))))

    def flops_per_image(self) -> int:
        """Multiply-adds x 2 of one forward pass (convolutions and linear layers)."""
        total, h, w = 0, self.height, self.width
        w1, w2 = self.widths
        h2 = h // 2
        total += 2 * 9 * self.in_channels * w1 * h2 * w                         # stem
        total += 2 * 2 * 9 * w1 * w1 * h2 * w                                   # block 1
        total += 2 * 3 * (w1 * w2 + w2 * w2) * w + 2 * w1 * w2 * w              # block 2 (+ 1x1 skip)
        total += 2 * 2 * 2 * 3 * w2 * w2 * w                                    # blocks 3-4
        total += 2 * (w2 * w * self.hidden + self.hidden * self.F)              # fc
        return total


class VGAIModel(nn.Module):
    """The two learned parts of VGAI, trained jointly: CNN_Psi and NN_Theta."""

    def __init__(self, cnn: VisualCNN, mlp: AggregationMLP):
        super().__init__()
        if mlp.F != cnn.F:
            raise ValueError(f"the MLP expects F={mlp.F} features per tap but the CNN gives F={cnn.F}")
        self.cnn, self.mlp = cnn, mlp


VIEWS = ("egocentric", "topdown")


@dataclass(frozen=True)
class VisionConfig:
    """How a VGAI agent turns the world into the CNN's input (our choices; the paper renders one
    AirSim frame per step).

    Attributes:
        view: "egocentric" (the 360° panorama, default) or "topdown".
        render: RenderConfig of the views. Default: 4 cameras of 12 x 32 (a 12 x 128 panorama, gray and
            depth channels): half the rows of the renderer's default, as the bodies sit on the
            horizon and the depth channel already gives their distance; it halves the CNN's cost.
        motion_gap: g, the frame the current one is paired with is g steps old (0: a single frame).
            A single frame shows positions only; the expert's action is dominated by velocity
            alignment, visible only across frames.
        motion_mode: "difference" ([I(t), 5 (I(t) - I(t-g))]) or "stack" ([I(t), I(t-g)]).
        prehistory: the episode starts mid-flight, with the cameras already running: the frames
            before t = 0 are rendered from the initial state flown backwards at its constant initial
            velocity, r(-k) = r(0) - k Ts v(0). Without it an agent is blind to motion for its first
            g steps, exactly when the expert acts hardest (80 % of eq. 1 accrues in the first 10
            steps). The velocities serve only the camera model, once, to draw those frames: they never
            reach the CNN except as pixels. False: the first frame stands in for the missing ones.
    """

    view: str = "egocentric"
    render: RenderConfig = RenderConfig(view_height=12, view_width=32)
    motion_gap: int = 5
    motion_mode: str = "difference"
    prehistory: bool = True

    def __post_init__(self) -> None:
        if self.view not in VIEWS:
            raise ValueError(f"VisionConfig: view must be one of {VIEWS}, got {self.view!r}")
        if not isinstance(self.motion_gap, int) or self.motion_gap < 0:
            raise ValueError(f"VisionConfig: motion_gap must be an integer >= 0, got {self.motion_gap!r}")
        if self.motion_mode not in ("difference", "stack"):
            raise ValueError(f"VisionConfig: motion_mode must be 'difference' or 'stack', got {self.motion_mode!r}")

    def image_shape(self, cfg: FlockConfig) -> tuple:
        """(C, H, W) of the CNN's input."""
        c = len(self.render.channels) if self.view == "egocentric" else 1
        c *= 2 if self.motion_gap > 0 else 1
        if self.view == "egocentric":
            return (c, self.render.view_height, self.render.panorama_width)
        return (c, self.render.topdown_size, self.render.topdown_size)

    def frame(self, r: torch.Tensor, cfg: FlockConfig) -> torch.Tensor:
        """Every agent's raw view at one instant, (B, N, C0, H, W)."""
        if self.view == "egocentric":
            return render_egocentric(r, cfg, self.render)
        return render_topdown(r, cfg, self.render)

    def combine(self, now: torch.Tensor, earlier: torch.Tensor) -> torch.Tensor:
        """The CNN's input from the current frame and the one g steps earlier."""
        if self.motion_gap == 0:
            return now
        return with_motion(now, earlier, self.motion_mode)

    def to_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["render"]["channels"] = list(self.render.channels)
        return d

    @staticmethod
    def from_dict(d: dict) -> "VisionConfig":
        rd = dict(d["render"])
        rd["channels"] = tuple(rd["channels"])
        return VisionConfig(view=d["view"], render=RenderConfig(**rd), motion_gap=d["motion_gap"],
                            motion_mode=d["motion_mode"], prehistory=d.get("prehistory", False))


class VGAIController:
    """VGAI as a controller: images -> CNN -> delayed aggregation -> MLP -> u, for any N.

    At each call every agent renders its own view of the positions r (its camera), pairs it with
    its frame of g steps ago, the CNN gives x_i(t), the buffer builds Z(t) from the neighbours' past
    messages, and the MLP gives u_i(t), saturated. Pure vision: the velocities ``v`` are ignored,
    except at an episode's first call, where the camera model uses them to draw the frames recorded
    before t = 0 (``VisionConfig.prehistory``). ``reset()`` clears the buffer and the frame memory.
    """

    name = "VGAI"

    def __init__(self, model: VGAIModel, cfg: FlockConfig, vision: VisionConfig = VisionConfig(),
                 gso_kind: str = DEFAULT_GSO):
        expected = vision.image_shape(cfg)
        got = (model.cnn.in_channels, model.cnn.height, model.cnn.width)
        if expected != got:
            raise ValueError(f"the CNN takes images {got} but the vision config produces {expected}")
        if gso_kind not in GSO_KINDS:
            raise ValueError(f"unknown GSO kind {gso_kind!r}; expected one of {GSO_KINDS}")
        self.model, self.cfg, self.vision, self.gso_kind = model, cfg, vision, gso_kind
        self.buffer = AggregationBuffer(model.mlp.K)
        self.frames: list = []

    @property
    def K(self) -> int:
        return self.model.mlp.K

    def reset(self) -> None:
        self.buffer.reset()
        self.frames = []

    def features(self, r: torch.Tensor, v: torch.Tensor = None) -> torch.Tensor:
        """X(t) from the agents' images, (B, N, F); keeps the frames needed for motion."""
        now = self.vision.frame(r, self.cfg)
        g = self.vision.motion_gap
        if not self.frames and g > 0 and self.vision.prehistory:
            if v is None:
                raise ValueError("the first call of an episode needs v to draw the frames before t = 0 "
                                 "(VisionConfig.prehistory); pass it, or use prehistory=False")
            self.frames = [self.vision.frame(r - k * self.cfg.Ts * v, self.cfg) for k in range(g, 0, -1)]
        self.frames.append(now)
        if len(self.frames) > g + 1:
            self.frames.pop(0)
        images = self.vision.combine(now, self.frames[0])
        B, N = images.shape[:2]
        return self.model.cnn(images.flatten(0, 1)).view(B, N, -1)

    def __call__(self, r: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
        S = gso(adjacency(r, self.cfg.R), self.gso_kind)
        Z = self.buffer.push(self.features(r, v), S)
        return saturate(self.model.mlp(Z), self.cfg)

    def spec(self) -> dict:
        cnn, mlp = self.model.cnn, self.model.mlp
        return {"kind": "vgai", "K": mlp.K, "F": mlp.F, "hidden": list(mlp.hidden), "gso": self.gso_kind,
                "cnn": {"in_channels": cnn.in_channels, "height": cnn.height, "width": cnn.width,
                        "widths": list(cnn.widths), "hidden": cnn.hidden},
                "vision": self.vision.to_dict()}

    def __repr__(self) -> str:
        return (f"VGAIController(F={self.model.cnn.F}, K={self.K} taps, view={self.vision.view!r}, "
                f"motion_gap={self.vision.motion_gap}, gso={self.gso_kind!r})")

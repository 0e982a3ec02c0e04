"""The learned controllers: the DAGNN baseline (section 3.2, notebook 03) and VGAI (section 3.4,
notebook 06), each a controller in the protocol of ``flocking.Controller``: ``reset()`` when an
episode starts, then ``u = controller(r, v)`` once per step, r, v, u (B, N, 2), for any N.

Both follow the same three stages per step, and differ only in the first:

    X(t)  the agents' features   DAGNN: the 6 exact local features; VGAI: CNN_Psi of its own images
    Z(t)  delayed aggregation    eq. 6, from the neighbours' past messages (``AggregationBuffer``)
    u(t)  the action             saturate(NN_Theta(Z(t))), eqs. 7-8

``observe(r, v)`` runs the first two and returns Z(t); ``act(Z)`` the last. DAgger's data
collection (``imitation.fly_dagger``) calls them apart to record Z(t).

A call ``controller(r, v)`` runs in ``torch.inference_mode`` (its output carries no autograd graph)
unless ``controller.gradients`` is set True; training builds its graphs from the models directly.
"""

from __future__ import annotations

import torch

from .aggregation import AggregationBuffer
from .config import FlockConfig
from .features import N_LOCAL_FEATURES, local_features, signed_log
from .flocking import check_state, saturate
from .graphs import DEFAULT_GSO, GSO_KINDS, adjacency, gso
from .models import AggregationMLP, VGAIModel
from .vision import VisionConfig, camera_input, flown_backwards

FEATURE_TRANSFORMS = ("signed_log", "none", "per_neighbour")


def _check_gso(gso_kind: str) -> None:
    if gso_kind not in GSO_KINDS:
        raise ValueError(f"unknown GSO kind {gso_kind!r}; expected one of {GSO_KINDS}")


class _Learned:
    """What both learned controllers share: the protocol's ``__call__`` and ``K``."""

    gradients = False
    """Set True to differentiate through ``controller(r, v)``; by default calls run in inference mode."""

    def __call__(self, r: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
        with torch.inference_mode(not self.gradients):
            return self.act(self.observe(r, v))

    def observe(self, r: torch.Tensor, v: torch.Tensor = None) -> torch.Tensor:
        """One exchange: push X(t) (``features``) and S(t) into the buffer and return Z(t), (B, N, K, F)."""
        S = gso(adjacency(r, self.cfg.R), self.gso_kind)
        return self.buffer.push(self.features(r, v), S)


class DAGNNController(_Learned):
    """The paper's DAGNN baseline as a controller: exact local features -> Z(t) -> MLP -> u.

    At each call: X(t) = transform(local_features(r, v)) (B, N, 6); S(t) = GSO of the graph of
    radius R; Z(t) from the agents' delayed-exchange buffer; u = saturate(MLP(Z(t))). The buffer
    holds the previous exchange's messages, so call ``reset()`` when an episode starts (``rollout``
    does). Works for any number of agents N.
    """

    name = "DAGNN"

    def __init__(self, model: AggregationMLP, cfg: FlockConfig, gso_kind: str = DEFAULT_GSO,
                 feature_transform: str = "none"):
        _check_gso(gso_kind)
        if feature_transform not in FEATURE_TRANSFORMS:
            raise ValueError(f"feature_transform must be one of {FEATURE_TRANSFORMS}, got {feature_transform!r}")
        if model.F != N_LOCAL_FEATURES:
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
        """X(t), (B, N, 6): the exact local features; "signed_log" compresses them, "per_neighbour" divides each sum by
        the drone's number of neighbours (eq. 2's alignment is N (vbar - v_i), the sum n_i (v_i - vbar_i): the
        gain from sum to action depends on the degree n_i, from mean to action it does not)."""
        X = local_features(r, v, self.cfg.R, per_neighbour=self.feature_transform == "per_neighbour")
        return signed_log(X) if self.feature_transform == "signed_log" else X

    def act(self, Z: torch.Tensor) -> torch.Tensor:
        """u(t) = saturate(NN_Theta(Z(t))), (B, N, 2)."""
        return saturate(self.model(Z), self.cfg)

    def spec(self) -> dict:
        """What ``load_controller`` needs to rebuild this controller (plain values only)."""
        return {"kind": "dagnn", "K": self.model.K, "F": self.model.F, "hidden": list(self.model.hidden),
                "gso": self.gso_kind, "feature_transform": self.feature_transform}

    def __repr__(self) -> str:
        return (f"DAGNNController(K={self.K} taps = {self.K - 1} exchanges, hidden={self.model.hidden}, "
                f"gso={self.gso_kind!r}, R={self.cfg.R})")


class VGAIController(_Learned):
    """VGAI as a controller: images -> CNN -> delayed aggregation -> MLP -> u, for any N.

    At each call every agent renders its own view of the positions r (its camera), pairs it with
    its view of g steps ago (``vision.camera_input``), the CNN gives x_i(t), the buffer builds Z(t)
    from the neighbours' past messages, and the MLP gives u_i(t), saturated. Pure vision: the
    velocities ``v`` are ignored, except at an episode's first call, where the camera model uses them
    to draw the views recorded before t = 0 (``VisionConfig.prehistory``). The controller remembers
    the last g + 1 positions its cameras saw; ``reset()`` clears them and the buffer.
    """

    name = "VGAI"

    def __init__(self, model: VGAIModel, cfg: FlockConfig, vision: VisionConfig = VisionConfig(),
                 gso_kind: str = DEFAULT_GSO):
        expected = vision.image_shape()
        got = (model.cnn.in_channels, model.cnn.height, model.cnn.width)
        if expected != got:
            raise ValueError(f"the CNN takes images {got} but the vision config produces {expected}")
        _check_gso(gso_kind)
        self.model, self.cfg, self.vision, self.gso_kind = model, cfg, vision, gso_kind
        self.buffer = AggregationBuffer(model.mlp.K)
        self.seen: list = []  # positions of the last g + 1 steps, oldest first
        self.t = 0  # steps since reset
        self.camera = None
        """A ``camera.Camera`` the drones see through (training flies the learner through its drawn
        cameras); None: the renderer's frames as they are."""

    @property
    def K(self) -> int:
        return self.model.mlp.K

    def reset(self) -> None:
        self.buffer.reset()
        self.seen = []
        self.t = 0

    def remember(self, r: torch.Tensor, v: torch.Tensor = None) -> torch.Tensor:
        """Advance the frame memory by one step: store r, return the positions g steps ago (the oldest
        remembered; at an episode's first call, the initial state flown backwards, see VisionConfig).
        Call it once per step (``observe`` does)."""
        g = self.vision.motion_gap
        if not self.seen and g > 0 and self.vision.prehistory:
            if v is None:
                raise ValueError("the first call of an episode needs v to draw the frames before t = 0 "
                                 "(VisionConfig.prehistory); pass it, or use prehistory=False")
            self.seen = [flown_backwards(r, v, k, self.cfg.Ts) for k in range(g, 0, -1)]
        self.seen.append(r)
        if len(self.seen) > g + 1:
            self.seen.pop(0)
        return self.seen[0]

    def features(self, r: torch.Tensor, r_before: torch.Tensor, camera=None) -> torch.Tensor:
        """X(t), (B, N, F), from the agents' images of the positions now and g steps before (pure: the
        frame memory is not touched). ``camera(frame, lag)``: what the cameras do to each raw frame
        before the CNN sees it (``vision.camera_input``); None: the renderer's frames as they are."""
        check_state(r)
        return self.model.features(camera_input(self.vision, self.cfg, r, r_before, camera))

    def observe(self, r: torch.Tensor, v: torch.Tensor = None) -> torch.Tensor:
        """One step: advance the frame memory (``remember``), X(t) = CNN_Psi of the images, push X(t)
        and S(t) into the buffer; returns Z(t), (B, N, K, F)."""
        X = self.features(r, self.remember(r, v), self.camera.at(self.t) if self.camera is not None else None)
        self.t += 1
        return self.buffer.push(X, gso(adjacency(r, self.cfg.R), self.gso_kind))

    def act(self, Z: torch.Tensor) -> torch.Tensor:
        """u(t) = saturate(NN_Theta(Z(t))), (B, N, 2)."""
        return saturate(self.model.mlp(Z), self.cfg)

    def spec(self) -> dict:
        """What ``load_controller`` needs to rebuild this controller (plain values only)."""
        cnn, mlp = self.model.cnn, self.model.mlp
        return {"kind": "vgai", "K": mlp.K, "F": mlp.F, "hidden": list(mlp.hidden), "gso": self.gso_kind,
                "cnn": {**cnn.spec(), "F": cnn.F}, "readout": self.model.readout,
                "vision": self.vision.to_dict()}

    def __repr__(self) -> str:
        return (f"VGAIController(F={self.model.cnn.F}, K={self.K} taps, view={self.vision.view!r}, "
                f"motion_gap={self.vision.motion_gap}, gso={self.gso_kind!r})")

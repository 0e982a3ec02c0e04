"""What defines a VGAI training run: ``VGAITrainConfig``, every knob of ``vgai_training`` in one place.

Introduced in notebook 06. ``VGAITrainConfig()`` is the paper's VGAI (``PAPER``): the plain CNN of
Fig. 2, stage 1 on the expert's own states, the L1 action loss of eq. 10 alone, DAgger's mixture
(p = 0.33). The paper gives the loss, the optimiser (Adam, learning rate 1e-3) and DAgger's
probability; every other field is our choice, explained beside it. The book's VGAI (``BOOK``,
``book_recipe``) is the paper's with the four changes notebook 06's ablation measures
(``BOOK_RECIPE``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import torch

from .config import config_dict
from .graphs import DEFAULT_GSO
from .models import AggregationMLP, VGAIModel, visual_cnn
from .vision import VisionConfig


BOOK_ADDITIONS = ("synthetic_share", "motion_features", "aux_weight", "flight_steps", "mlp_on_exact",
                  "anchor_weight", "joint_early_share", "learner_swarms")
"""Fields the paper's VGAI does not have: 0 in ``PAPER``, stored by ``to_dict`` only when switched on."""

@dataclass(frozen=True)
class VGAITrainConfig:
    """Everything that defines a VGAI training run.

    Attributes:
        F, K, hidden, gso: features per agent (paper default 24), taps (K - 1 = 3 exchanges),
            MLP hidden widths, graph shift operator.
        cnn_widths, cnn_hidden: channels of the CNN's two stages, width of its hidden FC layer.
        vision: what the agents see (view, resolution, motion frames).
        expert_episodes: episodes of round 0, flown by the expert alone.
        dagger_rounds, episodes_per_round, p_learner: DAgger rounds after the warm starts, new
            episodes per round, probability of following the learner at each step (paper: 0.33).
        warm_steps, warm_states: stage 1, gradient steps and swarm states (x N agents' images) per step.
        mlp_epochs: stage 2, passes over the frozen-CNN dataset.
        joint_steps, windows: stage 3, gradient steps per DAgger round and K-step windows per step.
        lr: Adam's learning rate (paper: 1e-3).
        early_steps, early_share: sampled states and window ends fall in the first ``early_steps``
            steps with probability ``early_share`` (the expert's labels live early).
        seed: seed of the training initial conditions, sampling and weights.
        synthetic_share: stage 1 shows this share of its states with synthetic relative velocities
            (``state_estimation.synthetic_velocities``), from 0.01 to 1.5 m/s: the expert's own late
            states have almost none to learn small motions from. Paper: 0; the book's recipe: 0.5
            (notebook 06, section 6).
        motion_features: F_m, the CNN's last F_m features made odd in the motion channels
            (``VisualCNN``): exactly 0 when nothing moves relative to the drone, so a swarm moving
            as one reads as such. 0 (default): the paper's plain CNN. None (the book's recipe):
            F // 3, the share of velocities among the 6 exact features (2 of 6), when the CNN sees a
            motion frame in the "difference" mode (which an explicit F_m > 0 needs), else 0.
        aux_weight: stage 3 adds this times the state-estimation loss of stage 1 (the aux head on
            every image of the window against the exact local features), so that joint training
            keeps the CNN's features readable as the swarm's relative velocities (0: the action
            loss alone, eq. 10, the paper's). The book's recipe: 5, which makes the two terms of similar size at the
            start of stage 3 (action L1 about 3 m/s², state-estimation L1 about 0.2, standardised).

        flight_steps: steps of every stored flight (0: cfg.T, the paper's episode of 2 s). Stages 1
            and 2 read the first cfg.T steps of each; stage 3 draws its windows over the whole
            flight, so that the drifting a learner does after 2 s is labelled with the expert's
            braking (an ablation of notebook 06: it did not make VGAI flock).
        joint_early_share: stage 3's own early_share (0: early_share's), for its windows only, so that
            stages 1 and 2 (and the cached stage 1) stay as they were.
        learner_swarms: the share of each DAgger round's swarms that the learner flies alone (p = 1
            at every step), the others under the paper's mixture (p_learner): the states the
            learner's own drifting leads to, late in a flight, labelled with the expert's braking.
            The book's recipe: 0.5, the one change that made VGAI flock (notebook 06: three training
            seeds, each with velocity variance at 5 s below the book's threshold; 0: the paper's mixture alone).
        mlp_on_exact: stage 2 fits the MLP on the CNN's features corrected through the aux head
            (``exact_through_aux``) so that they read as the exact local features, as the modular
            vision pilot's MLP learned its response on exact features (an ablation of notebook 06).
        anchor_weight: stage 3 adds this times the action loss of the MLP on those corrected
            features (the CNN's features with their estimation error removed), which keeps the
            MLP's response anchored to the exact-feature fit (an ablation of notebook 06).

    ``to_dict`` stores the fields of ``BOOK_ADDITIONS`` only when switched on (not 0), so that the
    paper's VGAI is written with the paper's fields alone, and a file or table cell is named by what
    its training changed.
    """

    F: int = 24
    K: int = 4
    hidden: tuple = (64, 64)
    gso: str = DEFAULT_GSO
    cnn_widths: tuple = (8, 16)
    cnn_hidden: int = 64
    vision: VisionConfig = VisionConfig()
    expert_episodes: int = 40
    dagger_rounds: int = 4
    episodes_per_round: int = 16
    p_learner: float = 0.33
    warm_steps: int = 3000
    warm_states: int = 8
    mlp_epochs: int = 4
    joint_steps: int = 600
    windows: int = 4
    lr: float = 1e-3
    early_steps: int = 50
    early_share: float = 0.75
    seed: int = 0
    synthetic_share: float = 0.0
    motion_features: Optional[int] = 0
    aux_weight: float = 0.0
    flight_steps: int = 0
    joint_early_share: float = 0.0
    learner_swarms: float = 0.0
    mlp_on_exact: bool = False
    anchor_weight: float = 0.0

    def __post_init__(self) -> None:
        if self.motion_features is None:  # frozen dataclass: resolve the default once, here
            motion = self.vision.motion_gap > 0 and self.vision.motion_mode == "difference"
            object.__setattr__(self, "motion_features", self.F // 3 if motion else 0)
        if not 0.0 <= self.synthetic_share <= 1.0:
            raise ValueError(f"VGAITrainConfig: synthetic_share must be in [0, 1], got {self.synthetic_share!r}")
        if not isinstance(self.flight_steps, int) or self.flight_steps < 0:
            raise ValueError(f"VGAITrainConfig: flight_steps must be an integer >= 0 (0: the episode's T), "
                             f"got {self.flight_steps!r}")
        if self.anchor_weight < 0:
            raise ValueError(f"VGAITrainConfig: anchor_weight must be >= 0, got {self.anchor_weight!r}")
        if self.motion_features and (self.vision.motion_gap == 0 or self.vision.motion_mode != "difference"):
            raise ValueError("VGAITrainConfig: motion_features needs a motion frame in the 'difference' mode "
                             f"(got motion_gap={self.vision.motion_gap}, motion_mode={self.vision.motion_mode!r})")

    def to_dict(self) -> dict:
        d = config_dict(self)
        for addition in BOOK_ADDITIONS:
            if d[addition] == 0:
                del d[addition]
        return d

    @staticmethod
    def from_dict(d: dict) -> "VGAITrainConfig":
        """The inverse of ``to_dict`` (the book's additions, absent when 0, come back as 0)."""
        d = {**{k: 0 for k in BOOK_ADDITIONS}, **d}
        d["vision"] = VisionConfig.from_dict(d["vision"])
        d["hidden"], d["cnn_widths"] = tuple(d["hidden"]), tuple(d["cnn_widths"])
        return VGAITrainConfig(**d)

    def new_model(self) -> VGAIModel:
        """Freshly initialised CNN_Psi and NN_Theta of this configuration (global torch RNG)."""
        C, H, W = self.vision.image_shape()
        return VGAIModel(visual_cnn(C, H, W, self.F, self.cnn_widths, self.cnn_hidden, self.motion_features),
                         AggregationMLP(self.K, self.F, self.hidden))


PAPER = VGAITrainConfig()
"""The paper's VGAI: F = 24, K - 1 = 3, the plain CNN, the L1 action loss, DAgger's mixture."""

BOOK_RECIPE = {"motion_features": None, "synthetic_share": 0.5, "aux_weight": 5.0, "learner_swarms": 0.5}
"""The book's changes to the paper's VGAI, each measured in notebook 06's ablation: odd motion features
(F_m = F // 3), synthetic relative velocities in stage 1, the state-estimation loss kept in stage 3,
half of DAgger's swarms flown by the learner alone."""


def book_recipe(**fields) -> VGAITrainConfig:
    """The book's VGAI with ``fields`` changed (e.g. ``book_recipe(F=6)``): ``PAPER`` + ``BOOK_RECIPE``."""
    return VGAITrainConfig(**{**BOOK_RECIPE, **fields})


BOOK = book_recipe()
"""The book's VGAI at the paper's default F = 24, K - 1 = 3."""


def sample_times(n: int, T: int, tcfg: VGAITrainConfig, g: torch.Generator, share: float = 0.0) -> torch.Tensor:
    """n time steps in [0, T): in the first ``early_steps`` with probability ``share`` (0: the
    config's ``early_share``), else uniform."""
    early = torch.rand(n, generator=g) < (share or tcfg.early_share)
    t_early = torch.randint(0, min(tcfg.early_steps, T), (n,), generator=g)
    t_any = torch.randint(0, T, (n,), generator=g)
    return torch.where(early, t_early, t_any)

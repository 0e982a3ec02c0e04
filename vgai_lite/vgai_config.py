"""What defines a VGAI training run: ``VGAITrainConfig``, every knob of ``vgai_training`` in one place.

Introduced in notebook 06. ``VGAITrainConfig()`` is the paper's VGAI (``PAPER``), as the paper
describes it: one intensity frame per step and no depth (``PAPER_VISION``), the CNN of Fig. 2, no
warm start (the CNN and the MLP learn together from random weights by K-step BPTT, Fig. 3), the L1
action loss of eq. 10 alone, DAgger's mixture (p = 0.33). The paper gives the sensor, the networks,
the loss, the optimiser (Adam, learning rate 1e-3) and DAgger's probability; the training's length,
the resolution and every other field are our choice, explained beside it. The book's VGAI (``BOOK``,
``book_recipe``) is the paper's with the book's departures (``BOOK_RECIPE``), which notebook 11 adds one at a time.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import ClassVar, Optional

from .camera import CameraRanges
from .config import config_dict
from .graphs import DEFAULT_GSO
from .imitation import check_flight_mix
from .models import READOUTS, AggregationMLP, VGAIModel, read_width, visual_cnn
from .render import RenderConfig
from .vision import VisionConfig

PAPER_VISION = VisionConfig(render=RenderConfig(channels=("gray",)), motion_gap=0)
"""The paper's sensor: the four cameras' intensity at one instant (its CNN takes one frame; AirSim's colour
as one gray channel, colour in ``render.PALETTE``), no depth channel and no earlier frame."""


@dataclass(frozen=True)
class VGAITrainConfig:
    """Everything that defines a VGAI training run.

    Attributes:
        F, K, hidden, gso: features per agent (paper default 24), taps (K - 1 = 3 exchanges),
            MLP hidden widths, graph shift operator.
        cnn_widths, cnn_hidden: channels of the CNN's two stages, width of its hidden FC layer.
        vision: what the agents see (view, resolution, channels, motion frames). Default: the
            paper's sensor, ``PAPER_VISION``; the book's: ``VisionConfig()``, gray and depth with a
            motion channel from the frame g = 5 steps earlier.
        warm_starts: stages 1 and 2 before the joint training (``vgai_training``): the CNN first
            regresses the exact local features, then the MLP is fitted on its frozen features. False
            (the paper's): both networks start from random weights and learn only by joint BPTT,
            first on the expert's flights (round 0), then after each DAgger round.
        expert_episodes: episodes of round 0, flown by the expert alone.
        dagger_rounds, episodes_per_round, p_learner: DAgger rounds after the warm starts, new
            episodes per round, probability of following the learner at each step (paper: 0.33).
        warm_steps, warm_states: stage 1, gradient steps and swarm states (x N agents' images) per step.
        mlp_epochs, mlp_batch, mlp_late_stride: stage 2, passes over the frozen-CNN dataset, rows
            (agent-steps) per gradient step, and the stride of the steps kept after ``early_steps``
            (every early step, 1 in ``mlp_late_stride`` after: the expert's labels live early, as in
            the DAGNN's ``keep_late`` = 0.25 and ``batch_size``).
        joint_steps, windows: stage 3, gradient steps per DAgger round and K-step windows per step.
        lr: Adam's learning rate (paper: 1e-3).
        early_steps, early_share: sampled states and window ends fall in the first ``early_steps``
            steps with probability ``early_share`` (the expert's labels live early).
        seed: seed of the training initial conditions, sampling and weights.
        synthetic_share: stage 1 shows this share of its states with synthetic relative velocities
            (``vgai_training.synthetic_velocities``): the expert's own late states have almost none
            to learn small motions from. Paper: 0; the book's recipe: 0.5 (notebook 11, section 1).
        synthetic_speeds: the range (m/s) of those synthetic per-agent velocity deviations, from
            below the late-flight disagreements eq. 1 must remove to the early ones.
        motion_features: F_m, the CNN's last F_m features made odd in the motion channels
            (``VisualCNN``): exactly 0 when nothing moves relative to the drone, so a swarm moving
            as one reads as such. 0 (default): the paper's plain CNN. None (the book's recipe):
            F // 3, the share of velocities among the 6 exact features (2 of 6), when the CNN sees a
            motion frame in the "difference" mode, else 0. An explicit F_m > 0 needs a motion frame; in
            the "stack" mode its features are odd in the frames' order (``OddMotionCNN``'s pairing).
        aux_weight: stage 3 adds this times the state-estimation loss of stage 1 (the aux head on
            every image of the window against the exact local features), so that joint training
            keeps the CNN's features readable as the swarm's relative velocities (0: the action
            loss alone, eq. 10, the paper's). The book's recipe: 5, which makes the two terms of similar size at the
            start of stage 3 (action L1 about 3 m/s², state-estimation L1 about 0.2, standardised).

        learner_swarms: the share of each DAgger round's swarms that the learner flies alone (p = 1
            at every step), the others under the paper's mixture (p_learner): the states the
            learner's own drifting leads to, late in a flight, labelled with the expert's braking.
            The book's recipe: 0.5 (0: the paper's mixture alone). What the flock needs of it: notebook
            11's leave-one-out (``findings.needs``, the book's one sentence on what the flock needs).
        camera: what the training's cameras do to the rendered frames, drawn per flight and per
            training window (``camera.CameraRanges``: sensor noise, lens blur, exposure, a dead
            camera; domain randomisation). Every stage sees the frames through it: stage 1's states,
            stage 2's flights, stage 3's windows and the learner's own DAgger flights. Default: the
            ideal camera (the paper's clean AirSim frames); the book's: ``BOOK_CAMERA``.
        teams, radii, group_swarms: the team sizes N and the range (low, high) of radii R (m) the training's
            swarms fly, in groups of ``group_swarms`` swarms, N drawn from ``teams``, R uniform in ``radii``
            (``imitation.flight_groups``, as the DAGNN's); a step draws one group, with 1 / N-scaled batches
            (``per_team``). Empty (the paper's): every swarm flies the training's configuration.
        feature_means: the local features the CNN learns to read (stage 1, and stage 3's state-estimation
            loss) are the local features' sums divided by the number of neighbours (``local_features(per_neighbour=True)``):
            means, which do not grow with the team's density (False: the sums, the DAGNN's).
        readout: what NN_Theta reads of each image (``VGAIModel.read``): "features" (the paper's: the CNN's F features)
            or "local" (the aux head's estimate of the 6 local features, in their units: what the DAGNN's MLP reads).
        mlp_start: stage 2: "fit" (the MLP fitted on the frozen CNN's features), or a DAGNN's file or shipped name
            (e.g. "dagnn_K4", notebook 04) whose MLP NN_Theta starts as (needs readout "local"; ``mlp_from_dagnn``); with
            ``feature_means`` a DAGNN that reads the features per neighbour (e.g. "dagnn_K4_per_neighbour", notebook 03).
        joint_mlp: stage 3 trains NN_Theta with CNN_Psi (the paper's); False: only the CNN learns there, through the MLP
            that stage 2 left (needs warm_starts), so that the action loss of eq. 10 reaches the CNN but not the MLP.
    """

    F: int = 24
    K: int = 4
    hidden: tuple = (64, 64)
    gso: str = DEFAULT_GSO
    cnn_widths: tuple = (8, 16)
    cnn_hidden: int = 64
    vision: VisionConfig = PAPER_VISION
    warm_starts: bool = False
    LEGACY_FIELDS: ClassVar[dict] = {"warm_starts": True, "teams": [], "radii": [], "group_swarms": 8,
                                     "feature_means": False, "readout": "features", "mlp_start": "fit",
                                     "joint_mlp": True}
    """Fields added after files were written, with the value every file written before them had (until
    2026-12-04 every VGAI training warm-started; until 2026-12-06 none drew N or R)."""
    expert_episodes: int = 40
    dagger_rounds: int = 4
    episodes_per_round: int = 16
    p_learner: float = 0.33
    warm_steps: int = 3000
    warm_states: int = 8
    mlp_epochs: int = 4
    mlp_batch: int = 1024
    mlp_late_stride: int = 4
    joint_steps: int = 600
    windows: int = 4
    lr: float = 1e-3
    early_steps: int = 50
    early_share: float = 0.75
    seed: int = 0
    synthetic_share: float = 0.0
    synthetic_speeds: tuple = (0.01, 1.5)
    motion_features: Optional[int] = 0
    aux_weight: float = 0.0
    learner_swarms: float = 0.0
    camera: CameraRanges = CameraRanges()
    teams: tuple = ()
    radii: tuple = ()
    group_swarms: int = 8
    feature_means: bool = False
    readout: str = "features"
    mlp_start: str = "fit"
    joint_mlp: bool = True

    def __post_init__(self) -> None:
        if self.motion_features is None:  # frozen dataclass: resolve the default once, here
            motion = self.vision.motion_gap > 0 and self.vision.motion_mode == "difference"
            object.__setattr__(self, "motion_features", self.F // 3 if motion else 0)
        for name in ("F", "K", "cnn_hidden", "expert_episodes", "episodes_per_round", "warm_steps", "warm_states",
                     "mlp_epochs", "mlp_batch", "mlp_late_stride", "joint_steps", "windows", "early_steps"):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise ValueError(f"VGAITrainConfig: {name} must be a whole number >= 1, got {value!r}")
        for name in ("dagger_rounds", "seed", "motion_features"):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < 0:
                raise ValueError(f"VGAITrainConfig: {name} must be a whole number >= 0, got {value!r}")
        for name in ("p_learner", "early_share", "synthetic_share", "learner_swarms"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"VGAITrainConfig: {name} is a probability, in [0, 1]; got {getattr(self, name)!r}")
        check_flight_mix("VGAITrainConfig", self.teams, self.radii, self.group_swarms)
        if not isinstance(self.warm_starts, bool) or not isinstance(self.feature_means, bool) or self.readout not in READOUTS:
            raise ValueError(f"VGAITrainConfig: warm_starts and feature_means must be True or False and readout one of "
                             f"{READOUTS}, got {self.warm_starts!r}, {self.feature_means!r}, {self.readout!r}")
        if not isinstance(self.joint_mlp, bool) or not (self.joint_mlp or self.warm_starts):
            raise ValueError(f"VGAITrainConfig: joint_mlp is True or False, and False needs warm_starts; got {self.joint_mlp!r}")
        if self.mlp_start != "fit" and self.readout != "local":
            raise ValueError(f"VGAITrainConfig: mlp_start {self.mlp_start!r} (a DAGNN's MLP) needs readout 'local'")
        if not self.lr > 0 or not self.aux_weight >= 0:
            raise ValueError(f"VGAITrainConfig: lr must be > 0 and aux_weight >= 0, got {self.lr!r}, {self.aux_weight!r}")
        lo, hi = self.synthetic_speeds
        if not 0 < lo < hi:
            raise ValueError(f"VGAITrainConfig: synthetic_speeds must be (low, high) m/s with 0 < low < high, "
                             f"got {self.synthetic_speeds!r}")
        if self.motion_features > self.F:
            raise ValueError(f"VGAITrainConfig: motion_features ({self.motion_features}) cannot exceed F ({self.F})")
        if self.motion_features and self.vision.motion_gap == 0:
            raise ValueError("VGAITrainConfig: motion_features needs a motion frame (the 'difference' or, read frame "
                             f"by frame, the 'stack' mode), got motion_gap={self.vision.motion_gap}")

    def to_dict(self) -> dict:
        """Every field as plain values: what a checkpoint stores and a cache key hashes."""
        return config_dict(self)

    @staticmethod
    def read_stored(d: dict) -> dict:
        """A configuration as a checkpoint stored it, in today's form (``LEGACY_FIELDS`` and the renderer's
        later fields filled in with the values it was trained with); as it is if it cannot be read, so
        that it matches no configuration of today and the model is trained again."""
        try:
            return VGAITrainConfig.from_dict(d).to_dict()
        except (ValueError, TypeError, KeyError):
            return d

    @staticmethod
    def from_dict(d: dict) -> "VGAITrainConfig":
        """The inverse of ``to_dict``. Every field must be there, and no other: a file that differs was
        written by another version of the training, whose behaviour this class may not reproduce."""
        names = {f.name for f in dataclasses.fields(VGAITrainConfig)}
        d = {**LEGACY_FIELDS, **d}
        missing, unknown = sorted(names - set(d)), sorted(set(d) - names)
        if missing or unknown:
            raise ValueError(f"a VGAI training configuration lacks {missing} and has unknown fields {unknown}: "
                             "it was written by another version of vgai_lite; train the model again")
        d = {**d, "vision": VisionConfig.from_dict(d["vision"]), "camera": CameraRanges.from_dict(d["camera"])}
        for name in ("hidden", "cnn_widths", "synthetic_speeds", "teams", "radii"):
            d[name] = tuple(d[name])
        return VGAITrainConfig(**d)

    def new_model(self) -> VGAIModel:
        """Freshly initialised CNN_Psi and NN_Theta of this configuration (global torch RNG)."""
        C, H, W = self.vision.image_shape()
        return VGAIModel(visual_cnn(C, H, W, self.F, self.cnn_widths, self.cnn_hidden, self.motion_features,
                                    self.vision.motion_mode, self.vision.motion_scale),
                         AggregationMLP(self.K, read_width(self.readout, self.F), self.hidden),
                         self.readout)


LEGACY_FIELDS = VGAITrainConfig.LEGACY_FIELDS

PAPER = VGAITrainConfig()
"""The paper's VGAI: its sensor (one gray frame), F = 24, K - 1 = 3, the CNN of Fig. 2 from random
weights, the L1 action loss of eq. 10 by K-step BPTT, DAgger's mixture."""

BOOK_SENSOR = {"vision": VisionConfig(), "warm_starts": True}
"""The book's sensor (gray and depth, with a motion channel from the frame g steps earlier) and its
warm starts (stage 1's state estimation, stage 2's MLP fit): the departures every book VGAI makes."""

BOOK_CAMERA = CameraRanges((0.0, 0.05), (0.0, 1.4), (0.9, 1.1), (-0.03, 0.03), dead_share=0.05, depth_noise=(0.0, 0.05))
"""The camera the book's VGAI is trained through: ranges just past the perturbations of the authors'
released test script (``inference_by_dronet.py`` of VITA-Group/VGAI, not the paper: noise 10/255, a 5 x 5 blur, about 0.5 degrees), chosen over wider ones on the validation episodes (notebook 08, ``runs.CAMERA_RUNS``)."""

BOOK_RECIPE = {**BOOK_SENSOR, "motion_features": None, "synthetic_share": 0.5, "aux_weight": 5.0,
               "learner_swarms": 0.5, "camera": BOOK_CAMERA}
"""The book's changes to the paper's VGAI: ``BOOK_SENSOR``, then those added in notebook 11's ablation:
odd motion features (F_m = F // 3), synthetic relative velocities in stage 1, the state-estimation
loss kept in stage 3, half of DAgger's swarms flown by the learner alone, the camera (``BOOK_CAMERA``)."""


def book_recipe(**fields) -> VGAITrainConfig:
    """The book's VGAI with ``fields`` changed (e.g. ``book_recipe(F=6)``): ``PAPER`` + ``BOOK_RECIPE``."""
    return VGAITrainConfig(**{**BOOK_RECIPE, **fields})


BOOK = book_recipe()
"""The book's VGAI at the paper's default F = 24, K - 1 = 3."""


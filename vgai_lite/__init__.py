"""vgai_lite: the method of the VGAI notebook book, in the order of the paper.

The book reproduces Hu, Gama, Chen, Wang, Ribeiro, Sadler, "VGAI: End-to-End Learning of
Vision-Based Decentralized Controllers for Robot Swarms" (ICASSP 2021, arXiv:2002.02308). One module
per idea; data flow one way: a module imports only modules listed before it here
(tests/test_architecture.py checks that this list is complete and in that order):

  the book's ground  ``book`` (quick mode, data paths, the seeds), ``config`` (constants, FlockConfig)
  the problem        ``flocking`` (dynamics, initial conditions, cost eq. 1, rollouts), ``controllers``
                     (expert eqs. 2-3, local heuristic)
  communication      ``graphs`` (who hears whom, S(t)), ``consensus`` (did it flock: velocity variance
                     late in a flight, cohesion), ``evaluate`` (relative cost, close calls and the
                     flocking figures beside it), ``features`` (the DAGNN's 6 exact local features),
                     ``aggregation`` (Z(t), eq. 6)
  what drones see    ``render`` (panoramas, top-down crops), ``physics`` (pymunk reference), ``camera``
                     (what a real camera does to a frame: blur, exposure, noise, a dead camera),
                     ``vision`` (the CNN's input: frames, motion, one image pipeline)
  learning           ``models`` (AggregationMLP eqs. 7-8, VisualCNN), ``learned_controllers``
                     (DAGNNController, VGAIController), ``checkpoints`` (files), ``imitation`` (DAgger,
                     what both trainings share), ``dagnn_training``, ``vgai_config`` (what defines a
                     VGAI run), ``vgai_training`` (VGAI's training top to bottom: state estimation,
                     the MLP, K-step BPTT), ``state_estimation`` (stage 1 run alone, notebook 05)
  pictures           ``viz`` (the paper's figures 1 and 3, ``lab.diagrams``, and the 3-D flight player
                     are in the lab)

The reproduction and the book's tooling live in ``vgai_lite.lab`` (the paper's tables, the shipped
models by name, the robustness sweep, Ray, exercises and grading, the website, benchmarks, records);
they import the method, never the other way round.

``import vgai_lite as vl`` gives every name the notebooks teach (``vl.rollout``, ``vl.gso``,
``vl.render_egocentric``, ``vl.VGAIController``, ``vl.train_vgai``, ``vl.load_controller``, ...).
"""

from .aggregation import AggregationBuffer, aggregation_sequence
from .checkpoints import load_controller, load_estimator, save_controller
from .config import FlockConfig
from .consensus import Consensus, consensus
from .controllers import (ExpertController, LocalController, expert_control, local_control,
                          potential, potential_gradient)
from .dagnn_training import DAGNNTrainConfig, train_dagnn
from .evaluate import RelativeCost, relative_cost
from .features import local_features
from .flocking import (Controller, Trajectory, flocking_cost, min_pair_distance, rollout,
                       sample_initial_state, saturate, step, velocity_variance)
from .graphs import adjacency, gso, k_hop_reach
from .imitation import dagger_mix, fly_dagger, load_or_train
from .learned_controllers import DAGNNController, VGAIController
from .models import AggregationMLP, OddMotionCNN, VGAIModel, VisualCNN
from .render import RenderConfig, render_egocentric, render_topdown
from .state_estimation import train_state_estimator
from .vgai_config import BOOK, PAPER, VGAITrainConfig, book_recipe
from .vgai_training import bptt_loss, train_vgai
from .camera import Camera, CameraRanges
from .vision import VisionConfig, camera_input

__version__ = "0.1.0"

__all__ = [
    "FlockConfig", "sample_initial_state", "step", "saturate", "flocking_cost", "rollout",
    "Trajectory", "Controller", "min_pair_distance", "expert_control", "local_control",
    "potential", "potential_gradient", "ExpertController", "LocalController", "relative_cost",
    "RelativeCost", "adjacency", "gso", "k_hop_reach", "local_features", "AggregationBuffer",
    "aggregation_sequence", "RenderConfig", "render_egocentric", "render_topdown", "VisionConfig",
    "camera_input", "Camera", "CameraRanges", "AggregationMLP", "VisualCNN", "OddMotionCNN", "VGAIModel", "DAGNNController", "VGAIController",
    "save_controller", "load_controller", "load_estimator", "dagger_mix", "fly_dagger", "load_or_train",
    "DAGNNTrainConfig", "train_dagnn", "VGAITrainConfig", "PAPER", "BOOK", "book_recipe", "train_vgai", "bptt_loss",
    "train_state_estimator", "consensus", "Consensus",
    "velocity_variance",
]

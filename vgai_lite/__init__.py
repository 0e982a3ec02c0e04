"""vgai_lite: the helper library of the VGAI notebook book.

The book reproduces Hu, Gama, Chen, Wang, Ribeiro, Sadler, "VGAI: End-to-End Learning of
Vision-Based Decentralized Controllers for Robot Swarms" (CoRL 2020). Modules follow the paper's
pipeline: ``config`` (constants), ``flocking`` (dynamics, initial conditions, cost, rollouts),
``controllers`` (expert, local heuristic), ``evaluate`` (relative cost), ``viz`` (pictures),
``exercises`` (checks), ``book`` (quick mode, data paths).
"""

from .config import FlockConfig
from .controllers import (ExpertController, LocalController, expert_control, local_control,
                          potential, potential_gradient)
from .evaluate import RelativeCost, relative_cost
from .flocking import (Controller, Trajectory, flocking_cost, min_pair_distance, rollout,
                       sample_initial_state, saturate, step)

__version__ = "0.1.0"

__all__ = [
    "FlockConfig", "sample_initial_state", "step", "saturate", "flocking_cost", "rollout",
    "Trajectory", "Controller", "min_pair_distance", "expert_control", "local_control",
    "potential", "potential_gradient", "ExpertController", "LocalController", "relative_cost",
    "RelativeCost",
]

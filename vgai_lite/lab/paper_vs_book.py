"""Where the book follows the paper and where it differs: one table, its book column read from the
config objects (so it says what the code does, never what it did once).

Introduced in notebook 00; notebooks 04 and 05 repeat the rows about what a drone sees. The paper's
column quotes section 3 and "Implementation Details" (../shared/paper/vgai-corl2020.tex).
"""

from __future__ import annotations

from typing import Optional, Sequence

from ..config import FlockConfig
from ..dagnn_training import DAGNNTrainConfig
from ..graphs import DEFAULT_GSO
from ..render import CAMERAS
from ..vgai_config import BOOK
from ..vision import VisionConfig


def _rows() -> dict:
    """topic -> (the paper, the book, why / where), the book's entries from the defaults."""
    cfg, vis, tv, td = FlockConfig(), VisionConfig(), BOOK, DAGNNTrainConfig()
    rc = vis.render
    C, H, W = vis.image_shape()
    return {
        "simulator": (
            "Microsoft AirSim: rendered drones, 2-D motion at a common height",
            f"the stated double integrator, exact for constant u (`flocking.step`), Ts = {cfg.Ts} s; "
            "our own batched renderer for the images, checked against a pymunk ray caster",
            "a laptop CPU instead of a game engine; notebook 04"),
        "observation": (
            "four AirSim camera views (front-centre, front-left, front-right, back), 144 × 256 each (colour in the "
            "authors' code; the paper does not say), "
            "concatenated; one frame per step",
            f"four 90° pinhole cameras ({', '.join(CAMERAS)}) of {rc.view_height} × {rc.view_width}, "
            f"a {rc.view_height} × {rc.panorama_width} panorama with channels {' and '.join(rc.channels)}",
            "drones are discs on the horizon: few rows suffice, and depth gives distance; notebooks 04-05"),
        "depth": (
            "none stated: camera images, distances only from how large and where a drone appears",
            ("a depth channel beside the gray one, so distances are read, not inferred"
             if "depth" in rc.channels else "none: the gray channel only, as the paper's cameras"),
            "a help the paper's drones lack; notebook 11 trains the book's best recipe with gray only and "
            "says what depth buys"),
        "motion": (
            "one frame per step (the CNN sees no motion within one input)",
            f"each frame paired with the one g = {vis.motion_gap} steps earlier as "
            f"[I(t), {vis.motion_scale:g} (I(t) − I(t−g))] ({C} channels); frames before t = 0 drawn from the "
            "initial state flown backwards (prehistory)",
            "the expert's action is mostly velocity alignment, which a single frame cannot show; notebook 05"),
        "CNN": (
            "residual blocks and two fully connected layers, average pooling along the vertical axis only",
            f"the same shape: stem, 4 residual blocks ({tv.cnn_widths[0]} and {tv.cnn_widths[1]} channels), "
            f"fc {tv.cnn_hidden} → F; F/3 of the features odd in the motion channels (`motion_features`)",
            "the odd features read exactly 0 when nothing moves; notebook 11 measures each departure"),
        "training": (
            "CNN and MLP end to end by K-step BPTT, imitation (L1), Adam 1e-3, DAgger with p = 0.33",
            f"the same, after two warm starts: (1) visual state estimation, the CNN regresses the DAGNN's "
            f"6 exact features ({tv.warm_steps} steps, half of the states with synthetic relative "
            f"velocities), (2) the MLP on the frozen CNN; then {tv.dagger_rounds} DAgger rounds of joint BPTT "
            f"with the state-estimation loss kept (weight {tv.aux_weight:g}), half of each round's swarms flown by "
            f"the learner alone; every stage sees its frames through a camera model (noise up to σ = "
            f"{tv.camera.noise[1]:g}, blur up to {tv.camera.blur_deg[1]:g}°, exposure, a dead camera; notebook 08)",
            "the book's additions: notebook 11's leave-one-out says which of them the book's recipe needs to "
            "flock; the paper's VGAI fails first for its sensor (one gray frame: warm starts alone do not rescue it, "
            "notebook 11, section 3: sensor × warm starts); notebooks 05, 06 and 11"),
        "GSO": (
            "S(t) respects the graph's sparsity (adjacency, Laplacian or normalisations cited); which one "
            "is not said (the public reference code averages)",
            f"`{DEFAULT_GSO}`: D^(−1/2) A D^(−1/2) of the disc graph of radius R = {cfg.R} m",
            "transfers to denser teams where the sum does not; notebook 03, section 9"),
        "rho": ("\"the minimum distance allowed\", no value",
                f"ρ = {cfg.rho} m", "the local heuristic's relative cost then lands near the paper's; notebook 01"),
        "potential": ("U = 1/‖r‖² − log ‖r‖² (eq. 3); the public reference code uses + log",
                      f"`potential = \"{cfg.potential}\"`: eq. 3 as printed (the code's sign is an option)",
                      "we follow the paper's text; notebook 01"),
        "initial disc": ("uniform on a disc of radius √N; the reference code draws radius N^(1/4)",
                         f"radius N^{cfg.init_radius_exponent:g}",
                         "with R = 1.5 m the √N disc never gives every drone two neighbours; notebook 01"),
        "episode": ("Ts = 0.01 s; the episode length is not given",
                    f"T = {cfg.T} steps ({cfg.T * cfg.Ts:g} s) for the cost; flights go on to 5 s to say "
                    "whether the swarm flocked",
                    "the expert has aligned by then; the longer flight exposes what eq. 1 hides; notebook 06"),
        "relative cost": ("cost of eq. 1 normalised to the centralized controller's (= 1.00)",
                          "mean over episodes of the controller's cost over the mean of the expert's on the "
                          "same held-out initial conditions, with a bootstrap 95 % interval",
                          "mean over mean is our choice (the paper does not say); notebook 01"),
        "DAGNN features": ("the 6 local features of Tolstaya et al. (relative velocities and two repulsion sums)",
                           f"the same, exact (`features.local_features`); trained by DAgger in {td.rounds} rounds",
                           "notebook 03"),
    }


TOPICS = tuple(_rows())
"""The table's rows, in order: simulator, observation, motion, CNN, training, GSO, rho, potential,
initial disc, episode, relative cost, DAGNN features."""


def table(topics: Optional[Sequence[str]] = None) -> str:
    """The paper-vs-book table as Markdown, all rows or those of ``topics`` (names of TOPICS)."""
    rows = _rows()
    topics = list(topics or TOPICS)
    unknown = [t for t in topics if t not in rows]
    if unknown:
        raise ValueError(f"unknown topics {unknown}; the table's topics are {list(TOPICS)}")
    lines = ["| | the paper | this book | why, and where |", "|---|---|---|---|"]
    lines += [f"| **{t}** | {rows[t][0]} | {rows[t][1]} | {rows[t][2]} |" for t in topics]
    return "\n".join(lines)


def show(topics: Optional[Sequence[str]] = None):
    """The table for a notebook's output (an ``IPython.display.Markdown``)."""
    from IPython.display import Markdown

    return Markdown(table(topics))

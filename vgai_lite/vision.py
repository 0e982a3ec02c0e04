"""What a VGAI agent's CNN is given: the camera, the motion frame, and ONE batched image pipeline.

Introduced in notebook 05. The paper renders one AirSim frame per drone and step (its figure 4). A
single frame shows positions only; the expert's action is dominated by velocity alignment, which a
camera sees only across frames, so the CNN's input pairs the frame of now with the frame of g steps
ago:

    H_i(t) = [ I_i(t), s (I_i(t) - I_i(t - g)) ]        (motion_mode "difference", s = motion_scale)

Both the controller (one step at a time, ``learned_controllers.VGAIController``) and the training
(K-step windows cut from stored flights, ``vgai_training``) call :func:`camera_input` with the
positions of now and of g steps ago; the only difference between the two is where those earlier
positions come from (the controller remembers them, training reads them from the stored flight),
and both take them from :func:`positions_before` / :func:`flown_backwards`.

Shapes: positions r (..., N, 2); images (..., N, C, H, W).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import torch

from .config import FlockConfig, config_dict
from .render import RenderConfig, render_egocentric, render_topdown, with_motion

VIEWS = ("egocentric", "topdown")
MOTION_MODES = ("difference", "stack")

@dataclass(frozen=True)
class VisionConfig:
    """How a VGAI agent turns the world into the CNN's input (our choices; the paper renders one
    AirSim frame per step).

    Attributes:
        view: "egocentric" (the 360° panorama, default) or "topdown".
        render: RenderConfig of the views. Default: the renderer's, 4 cameras of 12 x 32 (a 12 x 128
            panorama, gray and depth channels).
        motion_gap: g, the frame the current one is paired with is g steps old (0: a single frame).
            A single frame shows positions only; the expert's action is dominated by velocity
            alignment, visible only across frames.
        motion_mode: "difference" ([I(t), s (I(t) - I(t-g))]) or "stack" ([I(t), I(t-g)]).
        motion_scale: s, the gain on the frame difference (in the "stack" mode, on the change of the CNN's
            reading, ``OddMotionCNN``): in g = 5 steps a neighbour moves a fraction of a column.
        prehistory: the episode starts mid-flight, the cameras already running: the frames before t = 0
            show the initial state flown backwards at its initial velocity, r(-k) = r(0) - k Ts v(0).
            Else an agent is blind to motion for its first g steps, when the expert acts hardest (80 %
            of eq. 1 accrues in the first 10 steps). The velocities reach the CNN only as pixels.
            False: the first frame stands in for the missing ones.
    """

    view: str = "egocentric"
    render: RenderConfig = RenderConfig()
    motion_gap: int = 5
    motion_mode: str = "difference"
    motion_scale: float = 5.0
    prehistory: bool = True

    def __post_init__(self) -> None:
        if self.view not in VIEWS:
            raise ValueError(f"VisionConfig: view must be one of {VIEWS}, got {self.view!r}")
        if not isinstance(self.motion_gap, int) or self.motion_gap < 0:
            raise ValueError(f"VisionConfig: motion_gap must be an integer >= 0, got {self.motion_gap!r}")
        if self.motion_mode not in MOTION_MODES:
            raise ValueError(f"VisionConfig: motion_mode must be one of {MOTION_MODES}, got {self.motion_mode!r}")
        if not self.motion_scale > 0:
            raise ValueError(f"VisionConfig: motion_scale must be > 0, got {self.motion_scale!r}")

    def image_shape(self) -> tuple:
        """(C, H, W) of the CNN's input."""
        c = len(self.render.channels) if self.view == "egocentric" else 1
        c *= 2 if self.motion_gap > 0 else 1
        if self.view == "egocentric":
            return (c, self.render.view_height, self.render.panorama_width)
        return (c, self.render.topdown_size, self.render.topdown_size)

    def frame(self, r: torch.Tensor, cfg: FlockConfig) -> torch.Tensor:
        """Every agent's raw view at one instant, r (B, N, 2) -> (B, N, C0, H, W)."""
        if self.view == "egocentric":
            return render_egocentric(r, cfg, self.render)
        return render_topdown(r, cfg, self.render)

    def to_dict(self) -> dict:
        return config_dict(self)

    @staticmethod
    def from_dict(d: dict) -> "VisionConfig":
        """The inverse of ``to_dict``. Every field must be there: a file that lacks one was written
        by another version whose behaviour the class defaults may not reproduce."""
        names = {f.name for f in dataclasses.fields(VisionConfig)}
        missing, unknown = sorted(names - set(d)), sorted(set(d) - names)
        if missing or unknown:
            raise ValueError(f"vision settings lack {missing} and have unknown fields {unknown}: the file was "
                             "written by another version of vgai_lite; train the model again")
        rd = dict(d["render"])
        rd["channels"] = tuple(rd["channels"])
        return VisionConfig(**{**d, "render": RenderConfig(**rd)})


def flown_backwards(r0: torch.Tensor, v0: torch.Tensor, steps, Ts: float) -> torch.Tensor:
    """Positions ``steps`` steps before t = 0 of a swarm that flew at its constant initial velocity:
    r(-k) = r(0) - k Ts v(0). ``steps``: an int, or a tensor broadcastable to r0 (e.g. (M, 1, 1))."""
    return r0 - (steps * Ts) * v0


def positions_before(vision: VisionConfig, cfg: FlockConfig, r: torch.Tensor, v: torch.Tensor,
                     e: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
    """The positions g steps before stored states (episode e, step t) of flights r, v (T, E, N, 2):
    (M, N, 2). Before t = 0: the initial state flown backwards (``vision.prehistory``), else the
    first state stands in for the missing ones."""
    t_prev = t - vision.motion_gap
    r_prev = r[t_prev.clamp(min=0), e]
    if vision.prehistory:
        back = flown_backwards(r[0, e], v[0, e], (-t_prev).clamp(min=0).to(r.dtype)[:, None, None], cfg.Ts)
        r_prev = torch.where((t_prev < 0)[:, None, None], back, r_prev)
    return r_prev


def camera_input(vision: VisionConfig, cfg: FlockConfig, r_now: torch.Tensor,
                 r_before: torch.Tensor, camera=None) -> torch.Tensor:
    """The CNN's input H(t) of every agent, from the positions now and g steps before:
    r_now, r_before (M, N, 2) -> (M, N, C, H, W). With motion_gap 0, ``r_before`` is ignored.
    ``camera(frame, lag)``, if given, is what the camera does to each raw frame (M, N, C0, H, W)
    taken ``lag`` steps ago (0 or g) before the CNN sees it: noise, blur, a dead camera
    (``perturbations``)."""
    now = vision.frame(r_now, cfg)
    if camera is not None:
        now = camera(now, 0)
    if vision.motion_gap == 0:
        return now
    before = vision.frame(r_before, cfg)
    if camera is not None:
        before = camera(before, vision.motion_gap)
    return with_motion(now, before, vision.motion_mode, vision.motion_scale)


def stored_images(vision: VisionConfig, cfg: FlockConfig, r: torch.Tensor, v: torch.Tensor,
                  e: torch.Tensor, t: torch.Tensor, camera=None) -> torch.Tensor:
    """CNN inputs of every agent at stored states (episode e, step t), e, t (M,) of flights r, v
    (T, E, N, 2): (M, N, C, H, W). What the agents saw when they flew those states (through
    ``camera``, as in ``camera_input``, when given: e.g. noise augmentation)."""
    return camera_input(vision, cfg, r[t, e], positions_before(vision, cfg, r, v, e, t), camera)

"""What breaks the learned controllers: a world unlike the training's, as controller wrappers.

Introduced in notebook 08. Each perturbation changes one stage of the learned controllers' pipeline
(``learned_controllers``), where it would happen on real drones:

    stage                         perturbation            what it models
    the camera's frames           ImageNoise(sigma)       sensor noise: I + sigma n, n ~ N(0, 1) per pixel
                                                          of the intensity channel, clipped to [0, 1]
                                  DepthNoise(share)       a depth channel's range error: distances off by
                                                          a factor exp(share n) per pixel
                                  Blur(sigma)             defocus or motion blur: a Gaussian of sigma pixels
                                  DeadCamera()            one of the four cameras (a quarter of the
                                                          panorama) black, a random one per drone and episode
    the measured positions        PositionNoise(sigma)    the DAGNN's relative positions measured with
      (DAGNN's exact features)                            noise: each drone's position off by sigma n (m)
    the exchanges S(t)            DroppedLinks(p)         each message (each directed edge of each exchange)
                                                          lost with probability p
                                  MessageDelay(steps)     messages arrive ``steps`` steps late (eq. 6 with
                                                          Z(t-1-steps) in place of Z(t-1))

``perturbed(controller, ImageNoise(0.05), DroppedLinks(0.2), seed=0)`` is a controller in the protocol
(``reset()``, ``u = c(r, v)``) that flies ``controller`` in that world; wrapping it again adds more.
Every draw comes from the wrapper's seed: a rollout is reproducible, and a perturbation of size 0
(p = 0, sigma = 0) changes nothing, bit for bit. Frame noise is a function of the seed and the
instant the frame was taken, so a frame seen again g steps later (the motion input) carries the
same noise, as a real frame would.

Our choices where the paper is silent: the noise is clipped to [0, 1] because a
camera's pixels saturate; links drop per direction (a lost message is one radio packet); the
exact features stay exact except for PositionNoise, because they model the drone's own sensing.
"""

from __future__ import annotations

import math
from typing import Optional

import torch

from ..aggregation import AggregationBuffer
from ..camera import blur_degrees, dead_camera, gaussian_blur, range_noise, sensor_noise
from ..flocking import check_state
from ..graphs import adjacency, gso


def _check(value, name: str, low: float, high: float = math.inf) -> float:
    if not isinstance(value, (int, float)) or not math.isfinite(value) or not low <= value <= high:
        raise ValueError(f"{name} must be a number in [{low}, {high}], got {value!r}")
    return float(value)


class Perturbation:
    """One difference from the training's world. A subclass overrides the stage it touches."""

    delay = 0
    """Extra steps each message takes (MessageDelay)."""

    def frame(self, img: torch.Tensor, t: int, world: "World", k: int) -> torch.Tensor:
        """A raw camera frame (B, N, C0, H, W), taken at step t, as the CNN receives it."""
        return img

    def positions(self, r: torch.Tensor, world: "World") -> torch.Tensor:
        """The positions (B, N, 2) the exact features are computed from."""
        return r

    def links(self, A: torch.Tensor, world: "World") -> torch.Tensor:
        """The links (B, N, N) that carried a message this exchange (A_ij: i heard j)."""
        return A


class ImageNoise(Perturbation):
    """Gaussian pixel noise of standard deviation ``sigma`` on the intensity channel's values in [0, 1],
    then clipped to [0, 1] (``camera.sensor_noise``: a depth channel has its own error, DepthNoise)."""

    def __init__(self, sigma: float):
        self.sigma = _check(sigma, "ImageNoise sigma (pixel values are in [0, 1])", 0.0, 1.0)

    def frame(self, img, t, world, k):
        return sensor_noise(img, self.sigma, world.frame_generator(t, k), world.channels)

    def __repr__(self):
        return f"ImageNoise(sigma={self.sigma:g})"


class DepthNoise(Perturbation):
    """A depth channel's range error: each pixel's distance off by a factor exp(share n), n ~ N(0, 1)
    (``camera.range_noise``); frames without a depth channel are left as they are."""

    def __init__(self, share: float):
        self.share = _check(share, "DepthNoise share (a relative range error)", 0.0, 1.0)

    def frame(self, img, t, world, k):
        return range_noise(img, self.share, world.frame_generator(t, k), world.channels)

    def __repr__(self):
        return f"DepthNoise(share={self.share:g})"


class Blur(Perturbation):
    """A Gaussian blur of ``sigma`` pixels over rows and columns (the panorama wraps around;
    ``camera.gaussian_blur``; ``camera.blur_degrees`` says it in degrees of view)."""

    def __init__(self, sigma: float):
        self.sigma = _check(sigma, "Blur sigma (pixels)", 0.0, 50.0)

    def frame(self, img, t, world, k):
        return gaussian_blur(img, self.sigma, self.sigma)

    def __repr__(self):
        return f"Blur(sigma={self.sigma:g} px)"


class LensBlur(Perturbation):
    """The lens's Gaussian blur of ``sigma_deg`` degrees of view (``camera.blur_degrees``) on the
    cameras ``render`` describes: the same setting means the same at every resolution."""

    def __init__(self, sigma_deg: float, render):
        self.sigma_deg = _check(sigma_deg, "LensBlur sigma (degrees of view)", 0.0, 45.0)
        self.render = render

    def frame(self, img, t, world, k):
        return blur_degrees(img, self.sigma_deg, self.render)

    def __repr__(self):
        return f"LensBlur({self.sigma_deg:g}°)"


class DeadCamera(Perturbation):
    """One of each drone's four cameras shows black (0 in every channel): a quarter of its
    panorama, the same camera for a whole episode, chosen at random per drone."""

    def __init__(self, cameras: int = 4):
        self.cameras = cameras

    def frame(self, img, t, world, k):
        B, N = img.shape[0], img.shape[1]
        dead = world.episode_draw(k, lambda gen: torch.randint(self.cameras, (B, N), generator=gen))
        return dead_camera(img, dead)

    def __repr__(self):
        return "DeadCamera()"


class PositionNoise(Perturbation):
    """Each drone's position, as the exact features measure it, off by sigma n (m), n ~ N(0, I)
    drawn anew each step: relative positions err by the difference of two such errors."""

    def __init__(self, sigma: float):
        self.sigma = _check(sigma, "PositionNoise sigma (m)", 0.0)

    def positions(self, r, world):
        if self.sigma == 0:
            return r
        n = torch.randn(r.shape, generator=world.generator, dtype=r.dtype)
        return r + self.sigma * n.to(r.device)

    def __repr__(self):
        return f"PositionNoise(sigma={self.sigma:g} m)"


class DroppedLinks(Perturbation):
    """Each message of each exchange lost independently with probability ``p``: A_ij(t) = 0."""

    def __init__(self, p: float):
        self.p = _check(p, "DroppedLinks p (a probability)", 0.0, 1.0)

    def links(self, A, world):
        if self.p == 0:
            return A
        keep = torch.rand(A.shape, generator=world.generator) >= self.p
        return A * keep.to(device=A.device, dtype=A.dtype)

    def __repr__(self):
        return f"DroppedLinks(p={self.p:g})"


class MessageDelay(Perturbation):
    """Every message takes ``steps`` more steps to arrive than eq. 6's one."""

    def __init__(self, steps: int = 1):
        if not isinstance(steps, int) or steps < 0:
            raise ValueError(f"MessageDelay steps must be an integer >= 0, got {steps!r}")
        self.delay = steps

    def __repr__(self):
        return f"MessageDelay(steps={self.delay})"


def _mix(*ints: int) -> int:
    """A seed from a few integers, the same in every process (unlike ``hash`` of a string)."""
    x = 0x9E3779B97F4A7C15
    for i in ints:
        x = ((x ^ (i & 0xFFFF_FFFF_FFFF_FFFF)) * 0x100000001B3) & 0x7FFF_FFFF_FFFF_FFFF
    return x


class World:
    """The perturbations of one wrapped controller, with their random draws (seeded) and the clock."""

    def __init__(self, perturbations: tuple, seed: int, channels: Optional[tuple] = None):
        self.perturbations, self.seed = tuple(perturbations), seed
        self.channels = channels  # the names of the frames' channels (RenderConfig.channels), for the camera
        self.delay = sum(p.delay for p in self.perturbations)
        self.reset()

    def reset(self) -> None:
        self.t = 0
        self.generator = torch.Generator().manual_seed(self.seed)
        self._episode: dict = {}

    def frame_generator(self, t: int, k: int) -> torch.Generator:
        """The draws of perturbation k for the frame taken at step t (the same whenever it is seen)."""
        return torch.Generator().manual_seed(_mix(self.seed, k, t + 1_000_000))

    def episode_draw(self, k: int, draw):
        """Perturbation k's draw for the whole episode (made on first use)."""
        if k not in self._episode:
            self._episode[k] = draw(torch.Generator().manual_seed(_mix(self.seed, k, 0)))
        return self._episode[k]

    def camera(self, img: torch.Tensor, lag: int) -> torch.Tensor:
        for k, p in enumerate(self.perturbations):
            img = p.frame(img, self.t - lag, self, k)
        return img

    def positions(self, r: torch.Tensor) -> torch.Tensor:
        for p in self.perturbations:
            r = p.positions(r, self)
        return r

    def links(self, A: torch.Tensor) -> torch.Tensor:
        for p in self.perturbations:
            A = p.links(A, self)
        return A


class DelayedBuffer(AggregationBuffer):
    """``AggregationBuffer`` whose neighbours' messages arrive ``delay`` steps late: Z(t) = [X(t),
    S(t) Z_{0..K-2}(t-1-delay)], zero before the episode (``MessageDelay``; delay 0 is eq. 6)."""

    def __init__(self, K: int, delay: int):
        super().__init__(K)
        self.delay = delay
        self.sent: list = []  # Z(t-1), Z(t-2), ... newest first: the messages still on their way

    def reset(self) -> None:
        super().reset()
        self.sent = []

    def push(self, X: torch.Tensor, S: torch.Tensor) -> torch.Tensor:
        # the messages that arrive now are the ones sent delay steps before the last
        self.Z = self.sent[self.delay] if len(self.sent) > self.delay else None
        Z = super().push(X, S)
        self.sent = [Z] + self.sent[: self.delay]
        return Z


class Perturbed:
    """A learned controller flown in a perturbed world: a controller (``reset()``, ``u = c(r, v)``)."""

    def __init__(self, controller, perturbations: tuple, seed: int = 0):
        if not hasattr(controller, "observe"):
            raise ValueError(f"perturbations act on a learned controller's cameras, features and exchanges "
                             f"(DAGNNController, VGAIController), got {type(controller).__name__}")
        vision = getattr(controller, "vision", None)
        for p in perturbations:
            if not isinstance(p, Perturbation):
                raise ValueError(f"expected Perturbation objects (ImageNoise, DroppedLinks, ...), got {p!r}")
            camera = type(p).frame is not Perturbation.frame
            if camera and vision is None:
                raise ValueError(f"{p!r} acts on camera frames, which the {type(controller).__name__} does not use")
            if camera and vision.view != "egocentric" and isinstance(p, DeadCamera):
                raise ValueError("DeadCamera needs the egocentric panorama of four cameras")
            if type(p).positions is not Perturbation.positions and vision is not None:
                raise ValueError(f"{p!r} acts on the exact features' positions; VGAI sees only images")
        self.controller, self.sees = controller, vision is not None
        self.world = World(perturbations, seed, vision.render.channels if vision is not None else None)
        self.buffer = DelayedBuffer(controller.K, self.world.delay)  # the exchanges, as they arrive here
        self.name = f"{getattr(controller, 'name', 'controller')} + {', '.join(map(repr, perturbations)) or 'nothing'}"

    @property
    def perturbations(self) -> tuple:
        return self.world.perturbations

    @property
    def K(self) -> int:
        return self.controller.K

    def reset(self) -> None:
        self.controller.reset()
        self.world.reset()
        self.buffer.reset()

    def __call__(self, r: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
        """The controller's step (``learned_controllers._Learned.observe`` and ``act``) in this world: S(t)
        keeps only the links that carried a message, X(t) is measured through the world's cameras
        (VGAI) or positions (DAGNN), and the messages arrive as late as the world makes them."""
        check_state(r, v)
        c, w = self.controller, self.world
        with torch.inference_mode(not c.gradients):
            S = gso(w.links(adjacency(r, c.cfg.R)), c.gso_kind)
            X = c.features(r, c.remember(r, v), camera=w.camera) if self.sees else c.features(w.positions(r), v)
            u = c.act(self.buffer.push(X, S))
        w.t += 1
        return u

    def __repr__(self) -> str:
        return f"Perturbed({self.controller!r}, {list(self.perturbations)}, seed={self.world.seed})"


def perturbed(controller, *perturbations: Perturbation, seed: Optional[int] = None) -> Perturbed:
    """``controller`` flown with ``perturbations``, seeded (default 0). Composable: a Perturbed
    controller wrapped again gains the new perturbations after its own (and keeps its seed unless given)."""
    if isinstance(controller, Perturbed):
        return Perturbed(controller.controller, controller.perturbations + perturbations,
                         controller.world.seed if seed is None else seed)
    return Perturbed(controller, perturbations, 0 if seed is None else seed)

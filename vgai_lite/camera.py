"""What a real camera does to the rendered frame: optics, exposure, sensor noise, a dead camera.

Introduced in notebook 05. The renderer (``render``) draws the ideal frame I, values in [0, 1]. A
camera delivers instead

    I_cam = clip( gain * (G_b * I) + offset + sigma * n , 0, 1 ),    n ~ N(0, 1) per pixel and frame,

with G_b a Gaussian blur (the lens's point-spread function) of standard deviation ``blur_deg``
degrees of view, so that a setting means the same at every resolution: a column of the panorama is
90° / view_width wide, a row vertical_fov_deg / view_height tall. A dead camera shows 0 on its
quarter of the panorama.

Exposure and sensor noise are photometric: they act on the intensity channels ("gray", or AirSim's colour,
"red", "green", "blue"; ``PHOTOMETRIC``; noise independent per channel). A depth channel (the book's
"depth camera", D = depth_scale / d) comes from a range sensor, which errs in proportion to the distance it
measures: d_cam = d exp(depth_noise * n), i.e. D_cam = min(1, D exp(-depth_noise * n)) on the pixels that
see a body (no return stays 0). Our choice, the paper has no depth: intensity noise of sigma added to
D = 0.2 / d would be a range error of sigma / D, 50 % at 2 m for sigma = 0.05, where a commodity depth
camera errs by about 2 %. The lens blur and a dead camera act on every channel.

The noise of a frame is drawn from a generator seeded by the frame's time, so that in flight the
frame a drone took at t - g, paired with the one of t (``vision``), is the very frame it saw then,
noise included, and noise is independent between frames. (A training window's frames, its K steps
and the frames g >= K steps before them, are all different frames: each draws its own noise.)

The authors' released test script flies their VGAI with noise sigma = 10/255 and a 5 x 5 box blur at 144 x 256
(about 0.5° of view); the book's training draws these settings per flight (``CameraRanges``, domain
randomisation), and its robustness chapter (08) flies fixed ones (``lab.perturbations``).
Shapes: frames (B, N, C0, H, W); per-swarm settings (B,).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import torch
import torch.nn.functional as nnf

from .config import config_dict
from .render import CAMERAS, RenderConfig


def degrees_per_pixel(render: RenderConfig) -> tuple[float, float]:
    """(horizontal, vertical) degrees of view one column / one row of a camera covers."""
    return 90.0 / render.view_width, render.vertical_fov_deg / render.view_height


def _per_swarm(x, img: torch.Tensor, trailing: int) -> torch.Tensor:
    """A setting, a number or one per swarm (B,), as a tensor that broadcasts over ``trailing`` more
    dimensions of frames ``img`` (B, ...)."""
    x = torch.as_tensor(x, dtype=img.dtype)
    return x.view(-1, *([1] * trailing)).to(img.device) if x.dim() else x


def _gaussian_kernels(sigma_px: torch.Tensor, half: int, dtype) -> torch.Tensor:
    """Normalised 1-D Gaussian kernels (G, 2 half + 1), one per standard deviation (pixels) in sigma_px
    (G,); a standard deviation of 0 gives the identity (a delta)."""
    x = torch.arange(-half, half + 1, dtype=dtype)
    s = sigma_px.to(dtype)[:, None]
    k = torch.where(s > 0, torch.exp(-0.5 * (x / s.clamp(min=1e-12)) ** 2), (x == 0).to(dtype).expand(len(s), -1))
    return k / k.sum(-1, keepdim=True)


def gaussian_blur(img: torch.Tensor, sigma_cols: torch.Tensor, sigma_rows: torch.Tensor) -> torch.Tensor:
    """Blur every image (..., H, W) by a Gaussian of ``sigma_cols`` columns and ``sigma_rows`` rows
    (each broadcastable to img.shape[:-2], e.g. one per swarm (B, 1, 1)); the panorama's columns wrap
    around, its rows end at the image (replicated edge). Returns the same shape."""
    shape = img.shape
    lead = shape[:-2]
    sc = torch.as_tensor(sigma_cols, dtype=img.dtype).expand(lead).reshape(-1)
    sr = torch.as_tensor(sigma_rows, dtype=img.dtype).expand(lead).reshape(-1)
    if not (sc > 0).any() and not (sr > 0).any():
        return img
    G = sc.numel()
    flat = img.reshape(1, G, shape[-2], shape[-1])
    hc = max(1, math.ceil(3 * float(sc.max())))
    hr = max(1, math.ceil(3 * float(sr.max())))
    kc = _gaussian_kernels(sc, hc, img.dtype).to(img.device).view(G, 1, 1, -1)
    kr = _gaussian_kernels(sr, hr, img.dtype).to(img.device).view(G, 1, -1, 1)
    flat = nnf.conv2d(nnf.pad(flat, (hc, hc, 0, 0), mode="circular"), kc, groups=G)   # columns wrap around
    flat = nnf.conv2d(nnf.pad(flat, (0, 0, hr, hr), mode="replicate"), kr, groups=G)  # rows end at the image
    return flat.reshape(shape)


def blur_degrees(img: torch.Tensor, sigma_deg, render: RenderConfig) -> torch.Tensor:
    """The lens: a Gaussian blur of ``sigma_deg`` degrees of view (a number, or one per swarm (B,))
    on frames (B, N, C0, H, W) of cameras ``render``."""
    dx, dy = degrees_per_pixel(render)
    s = _per_swarm(sigma_deg, img, img.dim() - 3)
    return gaussian_blur(img, s / dx, s / dy)


PHOTOMETRIC = ("gray", "red", "green", "blue")
"""The channels a photosite measures: exposure and sensor noise act on these; "depth" has its range noise."""


def _only(img: torch.Tensor, changed: torch.Tensor, channels, kinds) -> torch.Tensor:
    """``changed`` on the channels (dim -3 of img, named by ``channels``) whose name is in ``kinds``,
    ``img`` on the others; every channel when ``channels`` is None (an image of intensities only)."""
    if channels is None:
        return changed
    if len(channels) != img.shape[-3]:
        raise ValueError(f"frames of {img.shape[-3]} channels (dim -3 of shape {tuple(img.shape)}) named by "
                         f"{len(channels)} names {tuple(channels)!r}")
    keep = torch.tensor([c in kinds for c in channels], device=img.device).view(-1, 1, 1)
    return torch.where(keep, changed, img)


def sensor_noise(img: torch.Tensor, sigma, generator: torch.Generator, channels=None) -> torch.Tensor:
    """Gaussian noise of standard deviation ``sigma`` (a number, or one per swarm (B,)) on every pixel
    of the intensity channels, then clipped to [0, 1] as a sensor's range; the draws from ``generator``.
    ``channels`` names the channels of frames (..., C0, H, W) (``RenderConfig.channels``); None: every
    channel is an intensity."""
    s = _per_swarm(sigma, img, img.dim() - 1)
    if not (s > 0).any():
        return img
    n = torch.randn(img.shape, generator=generator, dtype=img.dtype).to(img.device)
    return _only(img, (img + s * n).clamp(0.0, 1.0), channels, PHOTOMETRIC)


def range_noise(img: torch.Tensor, share, generator: torch.Generator, channels) -> torch.Tensor:
    """A range sensor's error on the "depth" channel of frames (..., C0, H, W) named by ``channels``:
    the distance off by a factor exp(share * n), n ~ N(0, 1) per pixel, so D = depth_scale / d becomes
    min(1, D exp(-share * n)); pixels without a return (D = 0) stay 0. ``share`` a number or one per
    swarm (B,)."""
    s = _per_swarm(share, img, img.dim() - 1)
    if "depth" not in channels or not (s > 0).any():
        return img
    n = torch.randn(img.shape, generator=generator, dtype=img.dtype).to(img.device)
    return _only(img, (img * torch.exp(-s * n)).clamp(max=1.0), channels, ("depth",))


def exposure(img: torch.Tensor, gain, offset, channels=None) -> torch.Tensor:
    """gain * I + offset, clipped to [0, 1] (numbers, or one per swarm (B,)), on the intensity channels
    (``channels`` as in ``sensor_noise``)."""
    g, o = (_per_swarm(x, img, img.dim() - 1) for x in (gain, offset))
    return _only(img, (g * img + o).clamp(0.0, 1.0), channels, PHOTOMETRIC)


def dead_camera(img: torch.Tensor, dead: torch.Tensor) -> torch.Tensor:
    """Black out each drone's dead camera: dead (B, N) the index (0-3, CAMERAS' order) of the camera
    that shows 0, or -1 for none; img (B, N, C0, H, W) a panorama of len(CAMERAS) cameras."""
    W = img.shape[-1]
    if W % len(CAMERAS):
        raise ValueError(f"a dead camera needs the egocentric panorama of {len(CAMERAS)} cameras; {W} columns do not split")
    column_camera = torch.arange(W, device=img.device) // (W // len(CAMERAS))  # (W,)
    black = column_camera == dead.to(img.device)[..., None]                     # (B, N, W)
    return img.masked_fill(black[:, :, None, None, :], 0.0)


@dataclass(frozen=True)
class CameraRanges:
    """The camera settings a training draws, uniformly and once per flight or training window
    (domain randomisation): each a (low, high) range, or a share. All at their defaults: the ideal
    camera, the renderer's frames as they are (the paper's and the book's until notebook 08).

    Attributes:
        noise: sigma of the sensor noise (pixel values in [0, 1]); the paper's test: 10/255.
        blur_deg: standard deviation of the lens blur, degrees of view; the paper's test: about 0.5°.
        gain, offset: exposure, gain * I + offset.
        dead_share: the share of drones with one dead camera (which one, drawn too).
        depth_noise: a depth channel's relative range error (``range_noise``); e.g. 0.02, about a
            commodity depth camera's at 2 m."""

    noise: tuple = (0.0, 0.0)
    blur_deg: tuple = (0.0, 0.0)
    gain: tuple = (1.0, 1.0)
    offset: tuple = (0.0, 0.0)
    dead_share: float = 0.0
    depth_noise: tuple = (0.0, 0.0)

    def __post_init__(self) -> None:
        for name, lo_min in (("noise", 0.0), ("blur_deg", 0.0), ("gain", 0.0), ("offset", -1.0), ("depth_noise", 0.0)):
            lo, hi = getattr(self, name)
            if not lo_min <= lo <= hi:
                raise ValueError(f"CameraRanges: {name} must be (low, high) with {lo_min} <= low <= high, "
                                 f"got {getattr(self, name)!r}")
        if not 0.0 <= self.dead_share <= 1.0:
            raise ValueError(f"CameraRanges: dead_share is a share, in [0, 1]; got {self.dead_share!r}")

    @property
    def ideal(self) -> bool:
        return self == CameraRanges()

    def to_dict(self) -> dict:
        return config_dict(self)

    @staticmethod
    def from_dict(d: dict) -> "CameraRanges":
        return CameraRanges(**{k: (tuple(v) if isinstance(v, list) else v) for k, v in d.items()})


class Camera:
    """The cameras of B swarms through one flight (or one training batch): per-swarm settings drawn
    from ``ranges`` with ``generator`` when made, per-frame noise from a seed and the frame's time.

    ``camera.at(t)`` is the ``camera(frame, lag)`` function ``vision.camera_input`` takes at step t:
    the frame of step t - lag through this camera."""

    def __init__(self, ranges: CameraRanges, render: RenderConfig, B: int, N: int, generator: torch.Generator):
        def draw(lo_hi):
            lo, hi = lo_hi
            return lo + (hi - lo) * torch.rand(B, generator=generator)

        self.ranges, self.render = ranges, render
        self.noise, self.blur_deg = draw(ranges.noise), draw(ranges.blur_deg)
        self.gain, self.offset = draw(ranges.gain), draw(ranges.offset)
        has_dead = torch.rand(B, N, generator=generator) < ranges.dead_share
        which = torch.randint(len(CAMERAS), (B, N), generator=generator)
        self.dead = torch.where(has_dead, which, torch.full_like(which, -1))
        self.seed = int(torch.randint(0, 2 ** 62, (1,), generator=generator))
        # drawn last, so that cameras without a range error draw exactly what they drew before it existed
        self.depth_noise = draw(ranges.depth_noise) if ranges.depth_noise != (0.0, 0.0) else torch.zeros(B)

    def frame(self, img: torch.Tensor, frame_time: int) -> torch.Tensor:
        """Frame ``img`` (B, N, C0, H, W), taken at ``frame_time``, as these cameras deliver it."""
        channels = self.render.channels
        img = blur_degrees(img, self.blur_deg, self.render)
        img = exposure(img, self.gain, self.offset, channels)
        gen = torch.Generator().manual_seed((self.seed * 1_000_003 + frame_time) % (2 ** 63))
        img = sensor_noise(img, self.noise, gen, channels)
        img = range_noise(img, self.depth_noise, gen, channels)
        return dead_camera(img, self.dead) if (self.dead >= 0).any() else img

    def repeat(self, k: int) -> "Camera":
        """The same cameras for k consecutive states of each swarm (B k swarms, swarm-major): a
        training window's K steps seen through one flight's cameras."""
        out = object.__new__(Camera)
        out.__dict__.update(self.__dict__)
        for name in ("noise", "blur_deg", "gain", "offset", "dead", "depth_noise"):
            setattr(out, name, getattr(self, name).repeat_interleave(k, dim=0))
        return out

    def at(self, t: int):
        """The ``camera(frame, lag)`` of ``vision.camera_input`` at step t."""
        return lambda img, lag: self.frame(img, t - lag)


def draw_camera(ranges: Optional[CameraRanges], render: RenderConfig, B: int, N: int,
                generator: torch.Generator) -> Optional[Camera]:
    """A ``Camera`` of B swarms drawn from ``ranges``, or None for the ideal camera (no draw made)."""
    if ranges is None or ranges.ideal:
        return None
    return Camera(ranges, render, B, N, generator)

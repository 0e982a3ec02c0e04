"""What each drone sees: batched egocentric (360° panorama) and top-down renderers, in pure torch.

Introduced in notebook 04. The paper renders each drone's view in AirSim with four cameras
(front-centre, front-left, front-right, back) concatenated into a full field of view, all drones at
the same altitude (its figure 4). We model the same geometry with four 90° pinhole cameras.

Egocentric geometry (drones do not yaw, so the cameras' axes are fixed to the world):
  * bearing theta of a point = atan2(dy, dx), counter-clockwise from the world's +x axis;
  * cameras in panorama order: 0 front (+x), 1 right (-y), 2 back (-x), 3 left (+y); within a
    camera the image's columns run left to right, i.e. clockwise, so the whole panorama runs
    clockwise from bearing +45° (left edge) through 0° (centre of camera 0) to +45° again;
  * a point at angle phi to the right of camera c's axis lands at the (continuous) column
    u = c W + W/2 + f tan(phi),  f = (W/2) / tan(45°) = W/2 pixels  (W columns per camera);
  * a body at distance t along the ray appears with half-height f_v (h/2) / t rows around the
    horizon (the image's middle row), f_v = (H/2) / tan(vertical_fov/2).
Each drone is a vertical cylinder (radius ``body_radius``, height ``body_height``). A column shows
the nearest body its pixel sees; coverage is anti-aliased in both directions (a body covering 30 %
of a column contributes 30 % of that column's pixels), and the two nearest bodies of each column
are composited front to back.

Shapes: positions r (B, N, 2); images (B, N, C, H, W_total) with W_total = 4 W for the panorama.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import torch

from .config import FlockConfig
from .flocking import check_state

CAMERAS = ("front", "right", "back", "left")

# Intensity channels in [0, 1] (our choice, none in the paper): sky at the horizon and its darkening upward, ground
# and its change downward, the horizon's colour far bodies fade to (fog), a body close up. "red", "green", "blue":
# AirSim's colour (blue sky, green ground, bluish haze, dark red bodies), where fog (how far) and coverage (how
# much of a pixel a body fills) change a pixel in different directions; in gray, along the same one.
PALETTE = {"gray": (0.85, 0.1, 0.55, -0.25, 0.7, 0.1), "red": (0.7, 0.1, 0.5, -0.25, 0.72, 0.4),
           "green": (0.82, 0.1, 0.55, -0.25, 0.76, 0.1), "blue": (0.95, 0.05, 0.35, -0.2, 0.82, 0.05)}
CHANNELS = (*PALETTE, "depth")


@dataclass(frozen=True)
class RenderConfig:
    """Camera and body model of the renderers (none of this is in the paper beyond "four cameras").

    Attributes:
        view_height, view_width: pixels of one camera (the panorama is 4 x view_width wide). Default
            12 x 32 per camera (12 x 128 panorama), what VGAI's CNN sees: small enough to train a CNN
            on 2 cores; the bodies sit on the horizon and the depth channel gives their distance, so
            a few rows suffice; a neighbour 1.5 m away (the communication radius) is about one column
            wide, and the anti-aliasing keeps its sub-column position and motion visible.
        vertical_fov_deg: vertical field of view of every camera (the horizontal one is 90°).
        body_radius, body_height: each drone's cylinder, in m. The radius is also the physical one
            of the pymunk reference: two bodies touch when their centres are closer than 0.1 m, the
            book's "close call" threshold. Pairs start at least 0.2 m apart.
        channels: "gray" (an intensity: sky, ground, bodies darker the nearer they are) or "red", "green",
            "blue" (in colour, ``PALETTE``), and/or "depth" (depth_scale / distance on bodies, else 0, at most 1).
        fog_distance: bodies fade toward the horizon's colour with distance, exp(-t / fog_distance).
        depth_scale: distance in m at which the depth channel reads 1.
        topdown_size: pixels per side of the top-down crop.
        topdown_half_width: half-width in m of the top-down crop (None: the communication radius R).
        nearest: the panorama draws only each drone's ``nearest`` nearest drones (None: every drone).
            Its cost per drone then stops growing with the team (``column_layers``): at the book's
            N = 50 every drone sees its 49 others either way, in a team of 400 the farthest of them
            sit in fog behind nearer bodies. Our choice, none in the paper (AirSim draws everything).
    """

    view_height: int = 12
    view_width: int = 32
    vertical_fov_deg: float = 60.0
    body_radius: float = 0.05
    body_height: float = 0.1
    channels: tuple = ("gray", "depth")
    fog_distance: float = 4.0
    depth_scale: float = 0.2
    topdown_size: int = 32
    topdown_half_width: Optional[float] = None
    nearest: Optional[int] = None

    def __post_init__(self) -> None:
        for name in ("view_height", "view_width", "topdown_size"):
            if not isinstance(getattr(self, name), int) or getattr(self, name) < 2:
                raise ValueError(f"RenderConfig: {name} must be an integer >= 2, got {getattr(self, name)!r}")
        if not 1.0 <= self.vertical_fov_deg < 179.0:
            raise ValueError(f"RenderConfig: vertical_fov_deg must be in [1, 179), got {self.vertical_fov_deg!r}")
        for name in ("body_radius", "body_height", "fog_distance", "depth_scale"):
            if not getattr(self, name) > 0:
                raise ValueError(f"RenderConfig: {name} must be > 0, got {getattr(self, name)!r}")
        if not self.channels or any(c not in CHANNELS for c in self.channels):
            raise ValueError(f"RenderConfig: channels must be a non-empty tuple drawn from {CHANNELS}, "
                             f"got {self.channels!r}")
        if self.topdown_half_width is not None and not self.topdown_half_width > 0:
            raise ValueError(f"RenderConfig: topdown_half_width must be > 0 or None, got {self.topdown_half_width!r}")
        if self.nearest is not None and (not isinstance(self.nearest, int) or isinstance(self.nearest, bool)
                                         or self.nearest < 1):
            raise ValueError(f"RenderConfig: nearest must be a whole number >= 1 or None (every drone), "
                             f"got {self.nearest!r}")

    @property
    def panorama_width(self) -> int:
        return 4 * self.view_width

    @property
    def focal(self) -> float:
        """Horizontal focal length in pixels: 90° per camera."""
        return self.view_width / 2.0

    @property
    def focal_vertical(self) -> float:
        return (self.view_height / 2.0) / math.tan(math.radians(self.vertical_fov_deg) / 2.0)


# ---------------------------------------------------------------------------------------------
# The panorama's column <-> bearing map (exact pinhole geometry, piecewise over the four cameras)

def bearing_to_column(theta: torch.Tensor, rcfg: RenderConfig) -> torch.Tensor:
    """Continuous panorama column u in [0, 4W) of a bearing theta (radians, CCW from +x)."""
    psi = torch.remainder(math.pi / 4 - theta, 2 * math.pi)  # clockwise from the panorama's left edge
    cam = torch.clamp(torch.floor(psi / (math.pi / 2)), max=3)
    phi = psi - cam * (math.pi / 2) - math.pi / 4  # to the right of camera cam's axis, [-45°, 45°)
    W = rcfg.view_width
    return cam * W + W / 2 + rcfg.focal * torch.tan(phi)


def column_to_bearing(u: torch.Tensor, rcfg: RenderConfig) -> torch.Tensor:
    """Bearing theta (radians, in (-pi, pi]) seen at continuous panorama column u; inverse of the above."""
    W = rcfg.view_width
    u = torch.remainder(u, 4 * W)
    cam = torch.clamp(torch.floor(u / W), max=3)
    phi = torch.atan((u - cam * W - W / 2) / rcfg.focal)
    theta = math.pi / 4 - (phi + math.pi / 4 + cam * (math.pi / 2))
    return torch.atan2(torch.sin(theta), torch.cos(theta))


def _wrap(a: torch.Tensor) -> torch.Tensor:
    return torch.atan2(torch.sin(a), torch.cos(a))


# ---------------------------------------------------------------------------------------------
# Egocentric panorama

@dataclass
class ColumnLayers:
    """Per panorama column of every agent, the two nearest bodies it sees: (B, N, W_total) each.

    depth1/depth2: distance along the column's centre ray to the body's surface (or to the ray's
    closest approach to the body, where the centre ray misses it; inf: none);
    cover1/cover2: share of the column the body covers (anti-aliasing weight, 0 if none);
    hit_depth: distance to the first body the centre ray actually hits (inf: none).
    """

    depth1: torch.Tensor
    cover1: torch.Tensor
    depth2: torch.Tensor
    cover2: torch.Tensor
    hit_depth: torch.Tensor


def seen_pairs(r: torch.Tensor, nearest: Optional[int] = None) -> tuple[torch.Tensor, torch.Tensor]:
    """The (viewer, drone) pairs a panorama draws: every other drone, or each viewer's ``nearest`` nearest.

    Returns the offsets r_j - r_i of the pairs, (P, 2), and the viewer of each pair, b * N + i, (P,),
    viewer-major within each swarm. With ``nearest`` < N - 1 the pairs are found from the swarm's
    distance matrix (N^2 subtractions, no trigonometry), so the rendering after it costs
    ``nearest`` bodies per drone whatever N is.
    """
    B, N, _ = r.shape
    dev = r.device
    owner_of = torch.arange(B * N, device=dev)
    if nearest is None or nearest >= N - 1:
        off = (r[:, None, :, :] - r[:, :, None, :]).reshape(B, N * N, 2)  # r_j - r_i at i * N + j
        not_self = ~torch.eye(N, dtype=torch.bool, device=dev).flatten()
        return off[:, not_self].reshape(-1, 2), owner_of.repeat_interleave(N - 1)
    d = torch.cdist(r, r) + torch.diag_embed(torch.full((N,), math.inf, dtype=r.dtype, device=dev))
    j = d.topk(nearest, dim=-1, largest=False, sorted=False).indices  # (B, N, nearest)
    rj = torch.gather(r, 1, j.reshape(B, N * nearest, 1).expand(-1, -1, 2)).view(B, N, nearest, 2)
    return (rj - r[:, :, None, :]).reshape(-1, 2), owner_of.repeat_interleave(nearest)


def column_layers(r: torch.Tensor, rcfg: RenderConfig) -> ColumnLayers:
    """Find, for every agent and panorama column, the nearest and second-nearest bodies.

    Each other drone j seen from agent i covers the bearings theta_ij +- asin(rho_b / d_ij); the
    columns that interval touches get one entry each (only those: the cost grows with the number
    of covered columns, not with N^2 x W), with its coverage and the depth at which the column's
    centre ray meets j's cylinder (or its closest approach when the centre ray misses).
    """
    check_state(r)
    B, N, _ = r.shape
    Wt, rho_b = rcfg.panorama_width, rcfg.body_radius
    dev, dt = r.device, r.dtype
    o, owner = seen_pairs(r, rcfg.nearest)
    d = o.norm(dim=-1).clamp(min=1e-6)
    theta = torch.atan2(o[:, 1], o[:, 0])
    alpha = torch.asin((rho_b / d).clamp(max=1.0))
    u_left = bearing_to_column(theta + alpha, rcfg)
    u_right = bearing_to_column(theta - alpha, rcfg)
    u_right = torch.where(u_right < u_left, u_right + Wt, u_right)  # the interval wraps the seam
    k0 = torch.floor(u_left)
    count = (torch.ceil(u_right) - k0).long().clamp(min=1)
    # one entry per (pair, touched column); gather the per-pair numbers in one indexing pass
    pair = torch.repeat_interleave(torch.arange(len(d), device=dev), count)
    start = torch.cumsum(count, 0) - count
    per_pair = torch.stack((k0, u_left, u_right, theta, d, (owner * Wt).to(dt)), dim=1)[pair]
    k0p, ul, ur, th, dp, base = per_pair.unbind(1)
    k = k0p + (torch.arange(len(pair), device=dev) - start[pair]).to(dt)
    cover = (torch.minimum(ur, k + 1) - torch.maximum(ul, k)).clamp(0, 1)
    col = torch.remainder(k, Wt)
    # depth along the column's centre ray
    delta = _wrap(column_to_bearing(col + 0.5, rcfg) - th)
    along, across = dp * torch.cos(delta), dp * torch.sin(delta)
    half_chord = (rho_b ** 2 - across ** 2).clamp(min=0).sqrt()
    depth = (along - half_chord).clamp(min=1e-3)
    depth = torch.where(cover > 0, depth, torch.inf)  # a column the body does not touch: ignore
    hits = (across.abs() <= rho_b) & (cover > 0)
    flat = (base + col).long()
    size = B * N * Wt
    inf = torch.full((size,), math.inf, dtype=dt, device=dev)
    d1 = inf.scatter_reduce(0, flat, depth, "amin")
    first = depth <= d1[flat]
    c1 = torch.zeros(size, dtype=dt, device=dev).scatter_reduce(0, flat[first], cover[first], "amax")
    # the second layer: the nearest body that is not the first one
    p1 = torch.full((size,), -1, dtype=torch.long, device=dev).scatter_reduce(
        0, flat[first], pair[first], "amax")
    rest = pair != p1[flat]
    d2 = inf.scatter_reduce(0, flat[rest], depth[rest], "amin")
    second = rest & (depth <= d2[flat])
    c2 = torch.zeros(size, dtype=dt, device=dev).scatter_reduce(0, flat[second], cover[second], "amax")
    hit = inf.scatter_reduce(0, flat[hits], depth[hits], "amin")
    shape = (B, N, Wt)
    return ColumnLayers(d1.view(shape), c1.view(shape), d2.view(shape), c2.view(shape), hit.view(shape))


def egocentric_depth(r: torch.Tensor, rcfg: RenderConfig = RenderConfig()) -> torch.Tensor:
    """Distance (m) along each panorama column's centre ray to the first body it hits, (B, N, W_total);
    inf where the centre ray hits nothing. This is what the pymunk ray caster measures."""
    return column_layers(r, rcfg).hit_depth


def _background(rows: torch.Tensor, H: int, ch: str = "gray") -> torch.Tensor:
    """Sky above the horizon (bright, darker upward), ground below (darker toward the bottom)."""
    y = (rows + 0.5 - H / 2) / (H / 2)  # -1 at the top, +1 at the bottom
    return torch.where(y < 0, PALETTE[ch][0] + PALETTE[ch][1] * y, PALETTE[ch][2] + PALETTE[ch][3] * y)


def render_egocentric(r: torch.Tensor, cfg: FlockConfig, rcfg: RenderConfig = RenderConfig()) -> torch.Tensor:
    """Every agent's 360° panorama: four 90° cameras (front, right, back, left), (B, N, C, H, 4W).

    Channels as ``rcfg.channels``: "gray" in [0, 1] (sky and ground, drones dark, fading with
    distance), "depth" = min(1, depth_scale / distance) on drones, 0 on the background. No agent
    sees itself. ``cfg`` is accepted for symmetry with the other renderers (the panorama has no range
    limit: a drone sees every drone not hidden behind a nearer one).
    """
    layers = column_layers(r, rcfg)
    B, N, Wt = layers.depth1.shape
    H, dt, dev = rcfg.view_height, r.dtype, r.device
    rows = torch.arange(H, dtype=dt, device=dev)
    edge = ((rows + 0.5 - H / 2).abs() - 0.5).clamp(min=0)[:, None]  # (H, 1): row's inner edge to the horizon
    fv, half = rcfg.focal_vertical, rcfg.body_height / 2

    def alpha(depth, cover):  # anti-aliased coverage of every pixel by one layer: (B, N, H, Wt)
        hh = (fv * half / depth).unsqueeze(2)  # half-height in rows (0 where depth = inf)
        return (hh - edge).clamp_(0, 1).mul_(cover.unsqueeze(2))

    a1, a2 = alpha(layers.depth1, layers.cover1), alpha(layers.depth2, layers.cover2)
    out = torch.empty(B, N, len(rcfg.channels), H, Wt, dtype=dt, device=dev)
    fog = [torch.exp(-d / rcfg.fog_distance).unsqueeze(2) for d in (layers.depth2, layers.depth1)] \
        if any(ch in PALETTE for ch in rcfg.channels) else None  # once for every intensity channel
    for c, ch in enumerate(rcfg.channels):
        if ch in PALETTE:  # dark bodies fading to the horizon's colour with distance
            bg, (horizon, body) = _background(rows, H, ch)[:, None].expand(H, Wt), PALETTE[ch][4:]
            far, near = (horizon + (body - horizon) * f for f in fog)
        else:
            bg = torch.zeros((), dtype=dt, device=dev).expand(H, Wt)
            far, near = ((rcfg.depth_scale / d).clamp(max=1).unsqueeze(2) for d in (layers.depth2, layers.depth1))
        # front-to-back compositing: background, then the second layer, then the nearest one
        torch.lerp(torch.lerp(bg, far, a2), near, a1, out=out[:, :, c])
    return out


# ---------------------------------------------------------------------------------------------
# Top-down crops

def render_topdown(r: torch.Tensor, cfg: FlockConfig, rcfg: RenderConfig = RenderConfig()) -> torch.Tensor:
    """Every agent's bird's-eye crop, centred on itself, north up, (B, N, 1, S, S).

    The crop covers [-L, L]^2 around the agent (L = rcfg.topdown_half_width, default R). Other
    drones are discs of radius body_radius with anti-aliased edges (value = covered share of each
    pixel, overlaps summed and capped at 1); the agent itself is drawn at half intensity.
    """
    check_state(r)
    B, N, _ = r.shape
    S = rcfg.topdown_size
    L = rcfg.topdown_half_width or cfg.R
    px = 2 * L / S  # metres per pixel
    rad = rcfg.body_radius / px  # disc radius in pixels
    P = int(math.ceil(2 * rad + 2))  # patch side covering any disc
    dev, dt = r.device, r.dtype
    off = r[:, None, :, :] - r[:, :, None, :]  # (B, i, j, 2): r_j - r_i
    # disc centre in continuous pixel coordinates (col to the east, row to the south)
    cx = off[..., 0] / px + S / 2
    cy = S / 2 - off[..., 1] / px
    visible = (cx > -rad - 1) & (cx < S + rad + 1) & (cy > -rad - 1) & (cy < S + rad + 1)
    b_idx, i_idx, j_idx = torch.nonzero(visible, as_tuple=True)
    cxv, cyv = cx[b_idx, i_idx, j_idx], cy[b_idx, i_idx, j_idx]
    weight = torch.where(i_idx == j_idx, 0.5, 1.0).to(dt)
    d = torch.arange(P, device=dev) - P // 2
    cols = torch.floor(cxv).long()[:, None, None] + d[None, None, :]  # (M, 1, P)
    rows_ = torch.floor(cyv).long()[:, None, None] + d[None, :, None]  # (M, P, 1)
    dist = ((cols.to(dt) + 0.5 - cxv[:, None, None]) ** 2 + (rows_.to(dt) + 0.5 - cyv[:, None, None]) ** 2).sqrt()
    cover = (rad - dist + 0.5).clamp(0, 1) * weight[:, None, None]  # signed-distance anti-aliasing
    cols, rows_ = cols.expand_as(cover), rows_.expand_as(cover)
    inside = (cols >= 0) & (cols < S) & (rows_ >= 0) & (rows_ < S) & (cover > 0)
    bi = (b_idx * N + i_idx)[:, None, None].expand_as(cover)
    flat = (bi * S + rows_) * S + cols
    img = torch.zeros(B * N * S * S, dtype=dt, device=dev)
    img.index_put_((flat[inside],), cover[inside], accumulate=True)
    return img.clamp_(max=1.0).view(B, N, 1, S, S)


# ---------------------------------------------------------------------------------------------
# Motion

def with_motion(current: torch.Tensor, earlier: torch.Tensor, mode: str = "difference",
                scale: float = 1.0) -> torch.Tensor:
    """Give a single-frame image motion: stack it with an earlier frame (g steps before).

    mode "stack": [I(t), I(t-g)] along channels; "difference": [I(t), scale (I(t) - I(t-g))].
    A single frame shows positions only; relative velocities are visible only across frames.
    Shapes: (..., C, H, W) each -> (..., 2C, H, W).
    """
    if current.shape != earlier.shape:
        raise ValueError(f"frames must have the same shape, got {tuple(current.shape)} and {tuple(earlier.shape)}")
    if mode == "stack":
        return torch.cat((current, earlier), dim=-3)
    if mode == "difference":
        return torch.cat((current, scale * (current - earlier)), dim=-3)
    raise ValueError(f"mode must be 'stack' or 'difference', got {mode!r}")

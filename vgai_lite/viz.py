"""Pictures of swarms: snapshots, trajectories, velocity variance over time, animations.

Introduced in notebook 01. All functions take torch tensors (any device) and draw one swarm ``b``
of a batch.
"""

from __future__ import annotations

from typing import Mapping, Optional

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import torch
from matplotlib import animation
from matplotlib.collections import LineCollection

from .config import FlockConfig
from .flocking import Trajectory, velocity_variance
from .render import CAMERAS, RenderConfig, render_egocentric, render_topdown


PALETTE = {"expert": "black", "centralized": "black", "DAGNN": "tab:blue", "VGAI": "tab:orange",
           "Local": "tab:green", "pilot": "tab:purple", "paper's VGAI": "tab:brown",
           "clean frames": "0.45", "gray camera": "tab:pink", "DAGNN (per neighbour)": "tab:cyan"}
"""One colour per controller across the whole book (every figure takes it from here): the expert
black, DAGNN blue (per neighbour: cyan), the book's VGAI orange (through the camera, gray + depth), Local green,
the pilot purple, the paper's VGAI brown, the recipe on clean frames gray, the gray-only camera VGAI pink.
``controller_color`` finds a name's colour by the longest of these keys it contains."""


def controller_color(name: str, default: Optional[str] = None) -> Optional[str]:
    """The book's colour for a controller named ``name`` ("VGAI (F = 6)" -> VGAI's orange; the
    longest matching key wins, case-insensitive), or ``default`` when no key matches."""
    low = name.lower()
    hits = [k for k in PALETTE if k.lower() in low]
    return PALETTE[max(hits, key=len)] if hits else default


def _np(x: torch.Tensor) -> np.ndarray:
    return x.detach().cpu().double().numpy()


def _links(r: np.ndarray, R: float) -> np.ndarray:
    d = np.linalg.norm(r[:, None] - r[None], axis=-1)
    i, j = np.nonzero(np.triu(d <= R, k=1))
    return np.stack((r[i], r[j]), axis=1)


def draw_swarm(ax, r: torch.Tensor, v: Optional[torch.Tensor] = None,
               cfg: Optional[FlockConfig] = None, b: int = 0, links: bool = True,
               color: str = "tab:blue", arrow_scale: float = 0.15):
    """One swarm at one instant: agents as dots, velocities as arrows, links of length <= R.

    r, v: (B, N, 2) or (N, 2).
    """
    r = _np(r[b] if r.ndim == 3 else r)
    if links and cfg is not None:
        ax.add_collection(LineCollection(_links(r, cfg.R), colors="0.8", linewidths=0.6, zorder=1))
    ax.scatter(r[:, 0], r[:, 1], s=14, color=color, zorder=3)
    if v is not None:
        v = _np(v[b] if v.ndim == 3 else v)
        ax.quiver(r[:, 0], r[:, 1], v[:, 0], v[:, 1], angles="xy", scale_units="xy",
                  scale=1 / arrow_scale, width=0.004, color=color, alpha=0.7, zorder=2)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    return ax


def plot_trajectories(ax, traj: Trajectory, b: int = 0, color: str = "tab:blue", every: int = 1):
    """Each agent's path (faint), its start (open circle) and end (dot) for swarm ``b``."""
    r = _np(traj.r[::every, b])  # (T, N, 2)
    ax.add_collection(LineCollection(r.transpose(1, 0, 2), colors=color, linewidths=0.7, alpha=0.45))
    ax.scatter(r[0, :, 0], r[0, :, 1], s=12, facecolors="none", edgecolors=color, linewidths=0.8)
    ax.scatter(r[-1, :, 0], r[-1, :, 1], s=10, color=color)
    ax.autoscale()
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    return ax


def plot_velocity_variance(ax, trajectories: Mapping[str, Trajectory], Ts: float, log: bool = True):
    """Velocity variance (eq. 1's summand) over time: median over episodes, 10-90 % band."""
    for name, traj in trajectories.items():
        var = _np(velocity_variance(traj.v))  # (T, B)
        t = np.arange(var.shape[0]) * Ts
        lo, med, hi = np.percentile(var, [10, 50, 90], axis=1)
        line, = ax.plot(t, med, label=name, color=controller_color(name))
        ax.fill_between(t, lo, hi, color=line.get_color(), alpha=0.2, linewidth=0)
    if log:
        ax.set_yscale("log")
    ax.set_xlabel("time [s]")
    ax.set_ylabel(r"$\frac{1}{N}\sum_i \|v_i - \bar v\|^2$  [m$^2$/s$^2$]")
    ax.legend()
    return ax


def animate_swarms(trajectories: Mapping[str, Trajectory], cfg: FlockConfig, b: int = 0,
                   every: int = 5, tail: int = 20, size: float = 3.6, dpi: int = 72):
    """Side-by-side animation of swarm ``b`` under each controller; returns a FuncAnimation.

    Show it in a notebook with ``animation_image(anim)`` (a looping GIF). ``every`` keeps one
    frame in ``every`` steps; ``tail`` draws the last ``tail`` steps of each path.
    """
    names = list(trajectories)
    fig, axes = plt.subplots(1, len(names), figsize=(size * len(names), size), dpi=dpi, squeeze=False)
    axes = axes[0]
    data = {n: _np(trajectories[n].r[:, b]) for n in names}
    vel = {n: _np(trajectories[n].v[:, b]) for n in names}
    T = min(d.shape[0] for d in data.values())
    artists = []
    for ax, n in zip(axes, names):
        r = data[n]
        lo, hi = r.reshape(-1, 2).min(0) - 0.5, r.reshape(-1, 2).max(0) + 0.5
        ax.set_xlim(lo[0], hi[0]), ax.set_ylim(lo[1], hi[1]), ax.set_aspect("equal")
        ax.set_xticks([]), ax.set_yticks([])
        color = controller_color(n, "tab:blue")
        trails = LineCollection([], colors=color, linewidths=0.6, alpha=0.4)
        links = LineCollection([], colors="0.8", linewidths=0.5)
        ax.add_collection(links), ax.add_collection(trails)
        dots = ax.scatter(r[0, :, 0], r[0, :, 1], s=10, color=color, zorder=3)
        title = ax.set_title(n)
        artists.append((n, trails, links, dots, title))
    fig.tight_layout()

    def draw(t):
        out = []
        for n, trails, links, dots, title in artists:
            r = data[n]
            trails.set_segments(r[max(0, t - tail):t + 1].transpose(1, 0, 2))
            links.set_segments(_links(r[t], cfg.R))
            dots.set_offsets(r[t])
            spread = np.square(vel[n][t] - vel[n][t].mean(0)).sum(-1).mean()
            title.set_text(f"{n}   t = {t * cfg.Ts:.2f} s   var = {spread:.2f}")
            out += [trails, links, dots, title]
        return out

    anim = animation.FuncAnimation(fig, draw, frames=range(0, T, every), blit=False)
    plt.close(fig)
    return anim


def animation_html(anim: animation.FuncAnimation, frame_format: str = "jpeg", loop: bool = True) -> str:
    """An animation as self-contained HTML with play controls (JPEG frames keep notebooks small).

    Its controls need JavaScript (and Font Awesome from a CDN for their icons): JupyterLab shows
    nothing of it in a notebook that is not trusted. The book's notebooks use ``animation_image``."""
    with matplotlib.rc_context({"animation.frame_format": frame_format}):
        return anim.to_jshtml(default_mode="loop" if loop else "once")


def animation_image(anim: animation.FuncAnimation, fps: float = 8.0):
    """An animation as an animated GIF that loops: an ``IPython.display.Image`` for a notebook's output.

    A plain image plays without JavaScript, so it shows in a notebook that is not trusted (a fresh
    clone's), on GitHub and in a static site, and offline. Frames are quantised to 256 colours."""
    import tempfile
    from pathlib import Path

    from IPython.display import Image

    if fps <= 0:
        raise ValueError(f"fps must be > 0, got {fps!r}")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "animation.gif"
        anim.save(path, writer=animation.PillowWriter(fps=fps))
        return Image(data=path.read_bytes(), format="gif")


def animate_views(traj: Trajectory, cfg: FlockConfig, rcfg=None, agent: int = 0, b: int = 0,
                  every: int = 5, dpi: int = 60):
    """The swarm from above beside what one agent sees: its 360° panorama and its top-down crop.

    Returns a FuncAnimation (show it with ``animation_image``). Views are rendered per frame.
    """
    rcfg = rcfg or RenderConfig()
    r = traj.r[:, b : b + 1]  # (T, 1, N, 2)
    frames = list(range(0, r.shape[0], every))
    gray = rcfg.channels.index("gray") if "gray" in rcfg.channels else 0
    fig = plt.figure(figsize=(11, 4.2), dpi=dpi)
    ax_swarm = fig.add_axes([0.02, 0.05, 0.3, 0.9])
    ax_pano = fig.add_axes([0.35, 0.45, 0.63, 0.45])
    ax_top = fig.add_axes([0.35, 0.02, 0.2, 0.38])
    rn = _np(r[:, 0])
    lo, hi = rn.reshape(-1, 2).min(0) - 0.5, rn.reshape(-1, 2).max(0) + 0.5
    ax_swarm.set_xlim(lo[0], hi[0]), ax_swarm.set_ylim(lo[1], hi[1]), ax_swarm.set_aspect("equal")
    ax_swarm.set_xticks([]), ax_swarm.set_yticks([])
    dots = ax_swarm.scatter(rn[0, :, 0], rn[0, :, 1], s=8, color="tab:blue")
    me = ax_swarm.scatter(rn[0, agent, 0], rn[0, agent, 1], s=60, marker="*", color="tab:red")
    pano = ax_pano.imshow(np.zeros((rcfg.view_height, rcfg.panorama_width)), cmap="gray", vmin=0, vmax=1)
    for c in range(1, 4):
        ax_pano.axvline(c * rcfg.view_width - 0.5, color="tab:orange", lw=0.8)
    ax_pano.set_xticks([(c + 0.5) * rcfg.view_width for c in range(4)], CAMERAS)
    ax_pano.set_yticks([])
    top = ax_top.imshow(np.zeros((rcfg.topdown_size, rcfg.topdown_size)), cmap="gray_r", vmin=0, vmax=1)
    ax_top.set_xticks([]), ax_top.set_yticks([])
    ax_top.set_title("top-down crop", fontsize=9)
    title = ax_pano.set_title("")

    def draw(t):
        ego = render_egocentric(r[t], cfg, rcfg)[0, agent, gray]
        crop = render_topdown(r[t], cfg, rcfg)[0, agent, 0]
        pano.set_data(_np(ego)), top.set_data(_np(crop))
        dots.set_offsets(rn[t]), me.set_offsets(rn[t, agent])
        title.set_text(f"agent {agent}'s four cameras, t = {t * cfg.Ts:.2f} s")
        return [pano, top, dots, me, title]

    anim = animation.FuncAnimation(fig, draw, frames=frames, blit=False)
    plt.close(fig)
    return anim

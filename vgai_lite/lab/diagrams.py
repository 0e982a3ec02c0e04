"""Diagrams of the method, drawn with matplotlib: the paper's figure 1 (one drone's pipeline) and
figure 3 (K-step backpropagation through time), in the book's symbols.

Introduced in notebook 00 (the pipeline) and notebook 06 (BPTT). Pictures only: nothing here computes.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

from ..viz import PALETTE

BOX = {"vision": "#fde8cc", "comm": "#dbe8f6", "net": "#e3f1dc", "world": "#eeeeee", "loss": "#f8d7d7"}


def _box(ax, x, y, w, h, text, kind, fontsize=10):
    ax.add_patch(FancyBboxPatch((x - w / 2, y - h / 2), w, h, boxstyle="round,pad=0.02,rounding_size=0.08",
                                facecolor=BOX[kind], edgecolor="0.35", linewidth=1.0))
    ax.text(x, y, text, ha="center", va="center", fontsize=fontsize)


def _arrow(ax, a, b, color="0.25", style="-|>", ls="-", rad=0.0, lw=1.3):
    ax.add_patch(FancyArrowPatch(a, b, arrowstyle=style, mutation_scale=12, color=color, lw=lw,
                                 linestyle=ls, connectionstyle=f"arc3,rad={rad}", shrinkA=2, shrinkB=2))


def pipeline(ax=None):
    """The paper's figure 1 as a picture: what one drone i does at every step t.

    Its four cameras' images H_i(t) go through CNN_Psi to F features x_i(t); K - 1 exchanges with its
    neighbours j (messages one step old) build its row z_i(t) of the aggregation sequence (eq. 6);
    NN_Theta (eqs. 7-8, the same weights on every drone) gives the acceleration u_i(t), and the
    double integrator moves the swarm, which changes what every drone sees next. Returns the axes."""
    if ax is None:
        _, ax = plt.subplots(figsize=(12, 4.2))
    y = 2.0
    _box(ax, 0.9, y, 1.5, 0.9, "images $\\mathbf{H}_i(t)$\nfour cameras,\n360° panorama", "vision")
    _box(ax, 2.9, y, 1.4, 0.9, "CNN$_\\Psi$\n(notebook 05)", "vision")
    _box(ax, 4.9, y, 1.5, 0.9, "visual state\n$\\mathbf{x}_i(t) \\in \\mathbb{R}^F$", "vision")
    _box(ax, 7.1, y, 1.9, 1.2, "delayed aggregation\n$\\mathbf{z}_i(t) = [\\mathbf{x}_i(t),\\ [\\mathbf{S}\\mathbf{X}]_i,"
         "\\ \\ldots]$\n$K-1$ exchanges (eq. 6)", "comm", 9)
    _box(ax, 9.4, y, 1.4, 0.9, "NN$_\\Theta$\n(eqs. 7-8)", "net")
    _box(ax, 11.3, y, 1.4, 0.9, "action\n$\\mathbf{u}_i(t)$", "net")
    for a, b in ((1.65, 2.2), (3.6, 4.15), (5.65, 6.15), (8.05, 8.7), (10.1, 10.6)):
        _arrow(ax, (a, y), (b, y))
    _box(ax, 7.1, 3.75, 3.1, 0.7, "neighbours $j \\in \\mathcal{N}_i(t)$, $\\|\\mathbf{r}_i - \\mathbf{r}_j\\| \\leq R$:\n"
         "their messages, one step old", "comm", 9)
    _arrow(ax, (6.6, 3.4), (6.8, 2.62), color=PALETTE["DAGNN"])
    _arrow(ax, (7.6, 2.62), (7.8, 3.4), color=PALETTE["DAGNN"])
    ax.text(8.05, 3.0, "relay", fontsize=8, color=PALETTE["DAGNN"])
    ax.text(6.0, 3.0, "receive", fontsize=8, color=PALETTE["DAGNN"], ha="right")
    _box(ax, 6.1, 0.35, 4.6, 0.6, "the swarm moves: $\\mathbf{v}_i \\leftarrow \\mathbf{v}_i + T_s \\mathbf{u}_i$,"
         "  $\\mathbf{r}_i \\leftarrow \\mathbf{r}_i + T_s \\mathbf{v}_i + \\frac{T_s^2}{2}\\mathbf{u}_i$", "world", 9)
    _arrow(ax, (11.3, 1.55), (8.45, 0.4), rad=-0.25)
    _arrow(ax, (3.75, 0.4), (0.9, 1.55), rad=-0.25)
    ax.text(0.1, 3.95, "one drone $i$ at step $t$ (the same on every drone)", fontsize=11, weight="bold")
    ax.text(2.9, 1.25, "trained jointly, end to end\n(notebook 06)", ha="center", fontsize=8, color="0.3")
    ax.set_xlim(0, 12.2), ax.set_ylim(0, 4.3), ax.axis("off")
    return ax


def bptt(K: int = 4, ax=None):
    """K-step backpropagation through time (the paper's figure 3), unrolled over a window of K steps.

    Every step tau of the window runs CNN_Psi on every drone's images H(tau); the aggregation mixes
    the features through S(tau) step after step (eq. 6); the MLP acts once, at the window's last
    step t, and the L1 loss against the expert's u*(t) (eq. 10) flows back through all K CNN passes
    (dashed). Returns the axes."""
    if K < 1:
        raise ValueError(f"K must be >= 1, got {K}")
    if ax is None:
        _, ax = plt.subplots(figsize=(2.6 * K + 3.2, 4.6))
    xs = [1.3 + 2.4 * k for k in range(K)]
    for k, x in enumerate(xs):
        lag = K - 1 - k
        tau = "t" if lag == 0 else f"t-{lag}"
        _box(ax, x, 3.9, 1.7, 0.6, f"$\\mathbf{{H}}({tau})$", "vision")
        _box(ax, x, 2.9, 1.7, 0.6, "CNN$_\\Psi$", "vision")
        _box(ax, x, 1.9, 1.7, 0.6, f"$\\mathbf{{X}}({tau})$", "vision")
        _arrow(ax, (x, 3.6), (x, 3.2)), _arrow(ax, (x, 2.6), (x, 2.2))
        _arrow(ax, (x + 0.3, 3.2), (x + 0.3, 3.6), color="tab:red", ls="--", lw=1.0)
        _arrow(ax, (x + 0.3, 2.2), (x + 0.3, 2.6), color="tab:red", ls="--", lw=1.0)
        if k < K - 1:
            nxt = "t" if lag - 1 == 0 else f"t-{lag - 1}"
            _arrow(ax, (x + 0.85, 1.9), (xs[k + 1] - 0.85, 1.9), color=PALETTE["DAGNN"])
            ax.text((x + xs[k + 1]) / 2, 2.02, f"$\\mathbf{{S}}({nxt})$", ha="center", fontsize=9,
                    color=PALETTE["DAGNN"])
            _arrow(ax, (xs[k + 1] - 0.85, 1.72), (x + 0.85, 1.72), color="tab:red", ls="--", lw=1.0)
    xl = xs[-1]
    _box(ax, xl, 0.85, 1.9, 0.6, "$\\mathbf{Z}(t)$ → NN$_\\Theta$ → $\\hat{\\mathbf{u}}(t)$", "net", 9)
    _arrow(ax, (xl, 1.6), (xl, 1.15))
    _box(ax, xl + 2.3, 0.85, 1.9, 0.6, "L1 loss against\nthe expert's $\\mathbf{u}^*(t)$", "loss", 9)
    _arrow(ax, (xl + 0.95, 0.85), (xl + 1.35, 0.85))
    _arrow(ax, (xl + 1.35, 0.7), (xl + 0.95, 0.7), color="tab:red", ls="--", lw=1.0)
    ax.text(xs[0] - 0.85, 4.45, f"one window of K = {K} steps: the MLP acts once, at its last step; "
            "the gradient (dashed) flows back through all K CNN passes", fontsize=10)
    ax.set_xlim(0, xl + 3.5), ax.set_ylim(0.3, 4.7), ax.axis("off")
    return ax

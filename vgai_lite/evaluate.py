"""The relative cost used in every table of the paper, with the figures eq. 1 hides beside it.

Introduced in notebook 01. "Relative cost" is a controller's flocking cost (eq. 1) divided by the
centralized expert's cost on the same initial conditions (paper, section 4: centralized = 1.00).
Beside it, judged as a user would: whether it was safe (closest approaches, close calls) and
whether it flocked (``consensus``: the velocity variance at 2 s, the episode's end, and at 5 s of
the same flights flown on, and whether the communication graph is still connected at 5 s).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Optional

import torch

from .config import FlockConfig
from .consensus import Consensus, groups
from .controllers import ExpertController
from .flocking import flocking_cost, rollout, sample_initial_state, velocity_variance

CLOSE_CALLS = (0.05, 0.1)  # m: a pair closer than this counts as a close call
PINNED_EPISODES = 3
"""Episodes a record keeps one by one (``RelativeCost.pinned``): the first ones of its seed."""
FLOCK_TIMES = (2.0, 5.0)
"""Seconds at which ``relative_cost`` reads the velocity variance: 2 s (the end of the paper-length
episode, T = 200 steps) and 5 s (the same flights flown on: a longer horizon exposes disagreements
that eq. 1, mostly spent in the first steps, hides)."""
FLOCKED_VARIANCE = 2e-3
"""m²/s²: the book's definition of "flocked" (the paper gives none beyond a relative cost below 3,
which notebook 07 shows too weak): the median velocity variance at 5 s at most this, i.e. the
drones' velocities disagree by at most 0.045 m/s RMS, less than half a body length per second, and
the communication graph connected at 5 s in at least FLOCKED_CONNECTED of the episodes."""
FLOCKED_CONNECTED = 0.9


def flocked(summary: dict) -> bool:
    """Whether a record (``RelativeCost.summary()``, or a table cell of ``reproduce``) says the
    controller flocked: FLOCKED_VARIANCE at 5 s and FLOCKED_CONNECTED. The share connected is read at
    the flight's end, ``flocking_horizon_s`` (a table cell, which omits it, ends at the last time its
    variance was read). A record flown without the 5 s figures cannot say (ValueError)."""
    var = summary.get("velocity_variance_median", {})
    horizon = summary.get("flocking_horizon_s", max((float(t.rstrip("s")) for t in var), default=None))
    if "5s" not in var or "share_connected_at_end" not in summary or horizon != 5.0:
        raise ValueError("flocked() needs a record with the velocity variance at 5 s and the share connected "
                         f"at 5 s (relative_cost with flock_times reaching 5.0); got keys {sorted(summary)}")
    return var["5s"] <= FLOCKED_VARIANCE and summary["share_connected_at_end"] >= FLOCKED_CONNECTED


def variance_text(variance: float) -> str:
    """A velocity variance for display beside a flocked / not-flocked label: one decimal (``1.4e-03``),
    but four significant digits within 5 % of FLOCKED_VARIANCE, so that two values that print alike
    do not carry opposite labels (``1.999e-03`` flocked, ``2.020e-03`` not)."""
    v = float(variance)
    if v != v or v < 0:
        raise ValueError(f"a velocity variance is a non-negative number, got {variance!r}")
    return f"{v:.3e}" if abs(v - FLOCKED_VARIANCE) <= 0.05 * FLOCKED_VARIANCE else f"{v:.1e}"


SAFE_MARGIN, SAFE_FLOOR, SAFE_CLOSEST = 0.04, 0.05, 0.9
"""The book's definition of "as safe as the expert" (notebook 01), on the same episodes: the share of
episodes with a pair closer than 0.05 m at most the expert's plus SAFE_MARGIN (or SAFE_FLOOR, whichever
is larger: a few episodes of 50 are not a difference), and the median closest approach at least
SAFE_CLOSEST times the expert's."""


def as_safe_as_expert(summary: dict) -> bool:
    """Whether a record (``RelativeCost.summary()`` or a table cell) is as safe as the expert on its
    episodes: SAFE_MARGIN, SAFE_FLOOR, SAFE_CLOSEST."""
    missing = {"share_below_0.05m", "expert_share_below_0.05m", "median_min_distance",
               "expert_median_min_distance"} - set(summary)
    if missing:
        raise ValueError(f"as_safe_as_expert() needs the record's safety figures and the expert's; missing {sorted(missing)}")
    return (summary["share_below_0.05m"] <= max(SAFE_FLOOR, summary["expert_share_below_0.05m"] + SAFE_MARGIN)
            and summary["median_min_distance"] >= SAFE_CLOSEST * summary["expert_median_min_distance"])


@dataclass
class SafetyFigures:
    """Per-episode minimum pair distance (E,) and the summaries we report beside every cost."""

    min_distance: torch.Tensor

    @property
    def median_min_distance(self) -> float:
        return self.min_distance.median().item()

    def share_below(self, threshold: float) -> float:
        """Share of episodes in which some pair came closer than ``threshold`` metres."""
        return (self.min_distance < threshold).double().mean().item()


@dataclass
class RelativeCost:
    """A controller evaluated against the centralized expert on the same initial conditions.

    Attributes:
        cost, expert_cost: (E,) flocking cost of eq. 1 per episode.
        safety, expert_safety: minimum pair distances per episode.
        mean_ratio: mean(cost) / mean(expert_cost), the paper's relative cost.
        median_ratio: median over episodes of cost / expert_cost.
        ratio_quartiles: 25th and 75th percentiles of the per-episode ratios.
        mean_ratio_ci: 95 % bootstrap interval of ``mean_ratio`` over episodes (2,000 resamples).
        flocking: the flocking figures (velocity variance at ``FLOCK_TIMES``, groups at the last of
            them; whether they count as flocked is ``flocked(summary())``); None when evaluated without
            (``flock_times=()``).
    """

    name: str
    episodes: int
    seed: int
    cost: torch.Tensor
    expert_cost: torch.Tensor
    safety: SafetyFigures
    expert_safety: SafetyFigures
    flocking: Optional[Consensus] = None
    mean_ratio: float = field(init=False)
    median_ratio: float = field(init=False)
    ratio_quartiles: tuple = field(init=False)
    mean_ratio_ci: tuple = field(init=False)

    def __post_init__(self) -> None:
        ratio = self.cost / self.expert_cost
        self.mean_ratio = (self.cost.mean() / self.expert_cost.mean()).item()
        self.median_ratio = ratio.median().item()
        q = torch.quantile(ratio.double(), torch.tensor([0.25, 0.75], dtype=torch.float64))
        self.ratio_quartiles = (q[0].item(), q[1].item())
        g = torch.Generator().manual_seed(self.seed)
        idx = torch.randint(0, self.episodes, (2000, self.episodes), generator=g)
        boot = self.cost.double()[idx].mean(1) / self.expert_cost.double()[idx].mean(1)
        lo, hi = torch.quantile(boot, torch.tensor([0.025, 0.975], dtype=torch.float64))
        self.mean_ratio_ci = (lo.item(), hi.item())

    def summary(self) -> dict:
        """Plain numbers, ready for JSON or a table row."""
        out = {
            "controller": self.name, "episodes": self.episodes, "seed": self.seed,
            "relative_cost_mean": round(self.mean_ratio, 4),
            "relative_cost_mean_ci95": [round(x, 4) for x in self.mean_ratio_ci],
            "relative_cost_median": round(self.median_ratio, 4),
            "relative_cost_quartiles": [round(x, 4) for x in self.ratio_quartiles],
        }
        for label, s in (("", self.safety), ("expert_", self.expert_safety)):
            out[f"{label}median_min_distance"] = round(s.median_min_distance, 4)
            for th in CLOSE_CALLS:
                out[f"{label}share_below_{th}m"] = round(s.share_below(th), 4)
        if self.flocking is not None:
            f = self.flocking.summary()
            out["velocity_variance_median"] = f["median_velocity_variance"]
            out["share_connected_at_end"] = f["share_connected_at_end"]
            out["flocking_horizon_s"] = max(self.flocking.times)
        return out

    def pinned(self, k: int = PINNED_EPISODES) -> dict:
        """The per-episode relative costs of the first ``k`` episodes: what a record keeps so that a
        test can fly those episodes again from its checkpoint and check the record still holds
        (``tests/test_records.py``)."""
        ratio = (self.cost / self.expert_cost)[:k]
        return {"episodes": int(len(ratio)), "relative_cost": [round(float(x), 6) for x in ratio]}

    def flocking_line(self) -> str:
        """One line: velocity variance at each time read, and the share of connected swarms (whether
        that counts as flocked is ``flocked(self.summary())``)."""
        if self.flocking is None:
            return "flocking figures not computed"
        var = ", ".join(f"{x:.1e} at {t:g} s" for t, x in self.flocking.median_variance().items())
        return (f"median velocity variance {var} [m²/s²]; communication graph connected at "
                f"{max(self.flocking.times):g} s in {self.flocking.share_connected:.0%} of episodes")

    def __str__(self) -> str:
        lo, hi = self.mean_ratio_ci
        q1, q3 = self.ratio_quartiles
        s, e = self.safety, self.expert_safety
        return (f"{self.name}: relative cost {self.mean_ratio:.2f} (95% CI {lo:.2f}-{hi:.2f}), "
                f"median {self.median_ratio:.2f} (IQR {q1:.2f}-{q3:.2f}) over {self.episodes} "
                f"episodes (seed {self.seed}); median min distance {s.median_min_distance:.3f} m "
                f"(expert {e.median_min_distance:.3f} m); episodes with a pair < 0.05 m: "
                f"{s.share_below(0.05):.0%} (expert {e.share_below(0.05):.0%}), < 0.1 m: "
                f"{s.share_below(0.1):.0%} (expert {e.share_below(0.1):.0%})"
                + ("" if self.flocking is None else f"; {self.flocking_line()}"))


def relative_cost(controller: Callable, cfg: FlockConfig, episodes: int = 50, *, seed: int,
                  batch: int = 64, device=None, dtype: torch.dtype = torch.float32,
                  name: Optional[str] = None, flock_times: tuple = FLOCK_TIMES) -> RelativeCost:
    """Evaluate ``controller`` against the centralized expert on ``episodes`` initial conditions.

    The initial conditions come from ``sample_initial_state`` with ``torch.Generator`` seeded by
    ``seed``: the same seed gives the same episodes for every controller. ``seed`` has no default: say
    which episodes you fly (``book.VALIDATION_SEED`` to choose, ``book.TEST_SEED`` to report,
    ``book.WORKING_SEED`` to explore; a training's own seed would score it on its training episodes). Episodes run ``batch`` at
    a time (the controller is reset for each batch). The cost of eq. 1 and the closest approaches
    are those of the paper's episode, ``cfg.T`` steps; the controller's flights go on to the last
    of ``flock_times`` (seconds), where its flocking figures are read (``()``: none, T steps only).
    """
    if not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes must be a positive integer, got {episodes!r}")
    if any(not t >= 0 for t in flock_times):
        raise ValueError(f"flock_times must be seconds >= 0, got {flock_times!r}")
    read = [int(round(t / cfg.Ts)) for t in flock_times]
    steps = max([cfg.T] + [k + 1 for k in read])
    g = torch.Generator().manual_seed(seed)
    r0, v0 = sample_initial_state(cfg, episodes, g, dtype=dtype, device=device)
    expert = ExpertController(cfg)
    cost, ecost, dmin, edmin, var, grp = [], [], [], [], [], []
    for start in range(0, episodes, batch):
        r, v = r0[start:start + batch], v0[start:start + batch]
        te = rollout(expert, cfg, r, v)
        tc = rollout(controller, cfg, r, v, steps=steps)
        ecost.append(te.cost), cost.append(flocking_cost(tc.v[:cfg.T]))
        edmin.append(te.min_distance.min(0).values), dmin.append(tc.min_distance[:cfg.T].min(0).values)
        if read:
            var.append(velocity_variance(tc.v)[read].T.cpu()), grp.append(groups(tc.r[-1], cfg.R))
    name = name or getattr(controller, "name", None) or getattr(controller, "__name__", None) \
        or type(controller).__name__
    flocking = Consensus(name, tuple(flock_times), torch.cat(var), torch.cat(grp)) if read else None
    return RelativeCost(name=name, episodes=episodes, seed=seed,
                        cost=torch.cat(cost).cpu(), expert_cost=torch.cat(ecost).cpu(),
                        safety=SafetyFigures(torch.cat(dmin).cpu()),
                        expert_safety=SafetyFigures(torch.cat(edmin).cpu()), flocking=flocking)

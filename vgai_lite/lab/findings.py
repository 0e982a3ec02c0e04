"""One criterion for every finding the book states about its numbers, and the sentence it gives.

Introduced in notebook 03 (its first use); notebook 07 checks the paper's findings with it. A relative cost comes
with an interval: its bootstrap 95 % interval over episodes, or, for a row averaged over several
training seeds (``over_seeds``), mean ± 1.96 × (spread over seeds) / √seeds. A cell flown by ONE training
of a configuration (``one_training``) also carries the spread between that configuration's training seeds:
its interval reaches mean ± √(episode half-width² + (1.96 × seed spread)²), so two single trainings
differ only when they differ by more than the seeds do. Then:

  a < b   when a's interval lies entirely below b's (the two do not overlap)
  a trend ("falls as F grows") holds when every step of the series is such a difference in the
          trend's direction; it is contradicted when some step, or the series from end to end, is one
          in the other direction; otherwise our numbers cannot tell (at least one step is within its intervals).

A share of episodes (connected at 5 s) is compared the same way, with its Wilson 95 % interval.
The paper reports no intervals: its column compares its numbers as printed.
"""

from __future__ import annotations

import math
from typing import Optional, Sequence

from ..evaluate import FLOCKED_CONNECTED, flocked

HOLDS, CONTRADICTED, CANNOT_TELL = "yes", "no", "cannot tell"


SEED_SPREAD_KEY = "one_training_seed_std"
"""The key ``one_training`` adds to a cell: the spread (std) of the cost between training seeds of its configuration."""


def seed_spread(records: Sequence[dict]) -> float:
    """The spread between training seeds of one configuration: the standard deviation (n - 1) of their
    relative costs (records with ``relative_cost_mean``, at least two, on the same episodes)."""
    costs = [float(r["relative_cost_mean"]) for r in records]
    if len(costs) < 2:
        raise ValueError(f"a spread between training seeds needs at least two trainings, got {len(costs)}")
    mean = sum(costs) / len(costs)
    return math.sqrt(sum((c - mean) ** 2 for c in costs) / (len(costs) - 1))


def over_seeds(costs: Sequence[float]) -> dict:
    """A row over the training seeds of one configuration, as ``interval`` reads it: the mean cost, the costs per
    seed and their spread (``seed_spread``)."""
    costs = [float(c) for c in costs]
    return {"relative_cost_mean": sum(costs) / len(costs), "per_seed": costs,
            "seed_std": seed_spread([{"relative_cost_mean": c} for c in costs])}


def one_training(cell: dict, seed_std: float) -> dict:
    """``cell`` (a relative cost with its interval over episodes) flown by one training of a configuration whose
    trainings spread by ``seed_std`` (``seed_spread``): a copy whose ``interval`` also holds that spread."""
    if not seed_std >= 0 or math.isinf(seed_std):
        raise ValueError(f"seed_std must be a finite spread >= 0, got {seed_std!r}")
    if cell.get("per_seed") and len(cell["per_seed"]) > 1:
        raise ValueError("one_training: this cell is already a mean over several training seeds")
    return {**cell, SEED_SPREAD_KEY: float(seed_std)}


def interval(cell: dict) -> tuple[float, float]:
    """(low, high) of a relative cost: a record with ``relative_cost_mean_ci95`` (one evaluation) or
    ``ci95``, widened by the spread between training seeds where ``one_training`` marked it, else a table
    cell over training seeds (``per_seed`` with ``seed_std``)."""
    ci = cell.get("relative_cost_mean_ci95") or cell.get("ci95")
    if ci:
        lo, hi = float(ci[0]), float(ci[1])
        s = 1.96 * float(cell.get(SEED_SPREAD_KEY, 0.0))
        if s:
            m = float(cell["relative_cost_mean"])
            lo, hi = m - math.hypot(m - lo, s), m + math.hypot(hi - m, s)
        return lo, hi
    seeds, std = cell.get("per_seed") or [], cell.get("seed_std")
    if len(seeds) > 1 and std is not None:
        mean, half = float(cell["relative_cost_mean"]), 1.96 * float(std) / math.sqrt(len(seeds))
        return mean - half, mean + half
    raise ValueError(f"a relative cost without an interval (no ci95, no spread over seeds): {sorted(cell)}")


def compare(a: dict, b: dict) -> int:
    """-1 if a is lower than b by the criterion (intervals apart), +1 if higher, 0 if they overlap."""
    (alo, ahi), (blo, bhi) = interval(a), interval(b)
    return -1 if ahi < blo else (1 if alo > bhi else 0)


def share_interval(share: float, episodes: int) -> tuple[float, float]:
    """(low, high): the Wilson 95 % interval of a share of episodes (e.g. those connected at 5 s), the
    interval of a count the way ``interval`` is of a cost."""
    if not 0.0 <= share <= 1.0 or episodes < 1:
        raise ValueError(f"a share in [0, 1] of at least one episode, got {share!r} of {episodes!r}")
    z = 1.96
    centre = (share + z * z / (2 * episodes)) / (1 + z * z / episodes)
    half = z * math.sqrt(share * (1 - share) / episodes + z * z / (4 * episodes * episodes)) / (1 + z * z / episodes)
    return centre - half, centre + half


def compare_connected(a: dict, b: dict) -> int:
    """The same criterion on the share of episodes connected at the end (``share_connected_at_end`` over
    ``episodes``): -1 if a's is lower than b's with the two intervals apart, +1 if higher, 0 if they overlap."""
    (alo, ahi), (blo, bhi) = (share_interval(x["share_connected_at_end"], x["episodes"]) for x in (a, b))
    return -1 if ahi < blo else (1 if alo > bhi else 0)


def trend(cells: Sequence[dict], direction: int) -> str:
    """Whether a series of relative costs moves in ``direction`` (-1: falls, +1: rises) at every
    step, by the criterion: HOLDS, CONTRADICTED or CANNOT_TELL."""
    if direction not in (-1, 1):
        raise ValueError(f"direction must be -1 (falls) or +1 (rises), got {direction!r}")
    if len(cells) < 2:
        raise ValueError(f"a trend needs at least two cells, got {len(cells)}")
    steps = [compare(b, a) for a, b in zip(cells, cells[1:])]
    if all(s == direction for s in steps):
        return HOLDS
    if any(s == -direction for s in steps) or compare(cells[-1], cells[0]) == -direction:  # a step, or end to end
        return CONTRADICTED
    return CANNOT_TELL


def paper_trend(values: Sequence[float], direction: int) -> Optional[str]:
    """The same question of the paper's printed numbers (no intervals): HOLDS or CONTRADICTED."""
    if len(values) < 2:
        return None
    ok = all((b - a) * direction > 0 for a, b in zip(values, values[1:]))
    return HOLDS if ok else CONTRADICTED


def series_text(cells: Sequence[dict], labels: Sequence) -> str:
    """'6: 2.43 (2.30-2.57) → 12: ...', each cost with its interval."""
    return " → ".join(f"{lab}: {c['relative_cost_mean']:.2f} ({interval(c)[0]:.2f}-{interval(c)[1]:.2f})"
                      for lab, c in zip(labels, cells))


def flock_verdict(record: dict, seeds: Sequence[dict]) -> int:
    """Whether one training flocks, judged against ``seeds``, the records of the trainings of a configuration it is
    compared with (on the same episodes): -1 when it flocks (``evaluate.flocked``) with a velocity variance at 5 s
    below every seed's, +1 when it does not flock and ends beyond every seed (variance at 5 s above the largest of
    theirs, or connected in fewer episodes than the least of theirs), 0 when it lies within their spread: one
    draw, which cannot tell a configuration that flocks from one that does not."""
    if len(seeds) < 2:
        raise ValueError(f"a flock verdict needs at least two trainings to judge against, got {len(seeds)}")
    late = [r["velocity_variance_median"]["5s"] for r in seeds]
    var = record["velocity_variance_median"]["5s"]
    if flocked(record) and var < min(late):
        return -1
    if not flocked(record) and (var > max(late) or record["share_connected_at_end"]
                                < min(r["share_connected_at_end"] for r in seeds)):
        return 1
    return 0


def needs(without: dict, seeds: Sequence[dict]) -> str:
    """The book's one sentence on what makes VGAI flock, from the leave-one-out records
    (``runs.LEAVE_ONE_OUT``: departure -> the record of the recipe without it, one training each) judged
    against ``seeds``, the records of the recipe's own trainings on the same episodes. A departure is
    needed when the recipe without it does not flock (``evaluate.flocked``) and ends beyond every one of
    the recipe's training seeds: its velocity variance at 5 s above the largest of theirs, or connected
    in fewer episodes than the least of theirs. A row that does not flock within that spread cannot be
    told from the recipe, which itself does not flock in every seed. Each with its variance at 5 s (and
    its share connected at 5 s where that is what fails)."""
    if not without:
        raise ValueError("needs() takes at least one leave-one-out record")
    if len(seeds) < 2:
        raise ValueError(f"needs() judges against at least two trainings of the recipe, got {len(seeds)}")

    def listed(xs):
        return xs[0] if len(xs) == 1 else ", ".join(xs[:-1]) + " or " + xs[-1]

    def late(rec):
        return rec["velocity_variance_median"]["5s"]

    def shown(d):
        rec = without[d]
        cut = rec["share_connected_at_end"] < FLOCKED_CONNECTED
        return (f"{d} ({late(rec):.1e} m²/s²"
                + (f", connected in {rec['share_connected_at_end']:.0%}" if cut else "") + ")")

    worst_var = max(map(late, seeds))

    def beyond(rec):
        return flock_verdict(rec, seeds) == 1

    spare = [shown(d) for d, rec in without.items() if flocked(rec)]
    needed = [shown(d) for d, rec in without.items() if not flocked(rec) and beyond(rec)]
    within = [shown(d) for d, rec in without.items() if not flocked(rec) and not beyond(rec)]
    parts = []
    if spare:
        parts.append(f"VGAI still flocks without {listed(spare)}")
    if needed:
        parts.append(("it" if parts else "VGAI") + f" does not flock, beyond the spread of the recipe's own trainings, "
                     f"without {listed(needed)}")
    if within:
        parts.append(f"without {listed(within)} it does not flock in its one training, but within that spread, "
                     "so that cannot be told")
    return ("; ".join(parts) + f". The recipe's own {len(seeds)} training seeds end between "
            f"{min(map(late, seeds)):.1e} and {worst_var:.1e} m²/s² at 5 s ({sum(map(flocked, seeds))} of {len(seeds)} "
            "flock).")


def steps_text(cells: Sequence[dict], labels: Sequence) -> str:
    """Each step of a series by the criterion: '1 → 2 lower, 2 → 3 within the intervals'."""
    word = {-1: "lower", 0: "within the intervals", 1: "higher"}
    steps = [f"{la} → {lb} {word[compare(b, a)]}" for (la, a), (lb, b) in zip(zip(labels, cells), zip(labels[1:], cells[1:]))]
    if len(cells) > 2:  # and end to end, which a trend must not reverse either
        steps.append(f"{labels[0]} → {labels[-1]} {word[compare(cells[-1], cells[0])]}")
    return ", ".join(steps)


def sentence(claim: str, verdict: str, cells: Sequence[dict], labels: Sequence) -> str:
    """The finding as a sentence generated from the data: the claim, the verdict by the criterion
    and the numbers behind it; where the verdict is not HOLDS over more than one step, each step's
    own verdict (a clear first step is not hidden by a later one within its intervals)."""
    how = {HOLDS: "holds in ours: every step is larger than its intervals",
           CONTRADICTED: "does not hold in ours: some step, or the series end to end, goes the other way by more than its intervals",
           CANNOT_TELL: "cannot be told from ours: at least one step is within its intervals"}[verdict]
    steps = f"; step by step, {steps_text(cells, labels)}" if verdict != HOLDS and len(cells) > 2 else ""
    return f"{claim}: {how} ({series_text(cells, labels)}{steps})."


def noise_that_breaks(settings: dict) -> float:
    """The smallest sensor noise sigma at which a controller flown through fixed cameras no longer flocks
    (``settings``: a camera record's cells by setting, the noise ones keyed ``noise<sigma>``, e.g.
    ``data/experiments/vgai_clean_seed0_cameras.json``); infinity if it flocks at every noise flown."""
    noises = {k: x for k, x in settings.items() if k.startswith("noise")}
    if not noises:
        raise ValueError(f"noise_that_breaks: no noise setting among {sorted(settings)}")
    return min((float(k[5:]) for k, x in noises.items() if not flocked(x)), default=math.inf)

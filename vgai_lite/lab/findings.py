"""One criterion for every finding the book states about its numbers, and the sentence it gives.

Introduced in notebook 03 (its first use); notebook 07 checks the paper's findings with it. A relative cost comes
with an interval: its bootstrap 95 % interval over episodes, or, for a row averaged over several
training seeds, mean ± 1.96 × (spread over seeds) / √seeds. Then:

  a < b   when a's interval lies entirely below b's (the two do not overlap)
  a trend ("falls as F grows") holds when every step of the series is such a difference in the
          trend's direction; it is contradicted when some step is one in the other direction;
          otherwise our numbers cannot tell (at least one step is within its intervals).

A share of episodes (connected at 5 s) is compared the same way, with its Wilson 95 % interval.
The paper reports no intervals: its column compares its numbers as printed.
"""

from __future__ import annotations

import math
from typing import Optional, Sequence

from ..evaluate import FLOCKED_CONNECTED, flocked

HOLDS, CONTRADICTED, CANNOT_TELL = "yes", "no", "cannot tell"


def interval(cell: dict) -> tuple[float, float]:
    """(low, high) of a relative cost: a record with ``relative_cost_mean_ci95`` (one evaluation) or
    ``ci95``, else a table cell over training seeds (``per_seed`` with ``seed_std``)."""
    ci = cell.get("relative_cost_mean_ci95") or cell.get("ci95")
    if ci:
        return float(ci[0]), float(ci[1])
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
    if any(s == -direction for s in steps):
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


def needs(without: dict) -> str:
    """The book's one sentence on what makes VGAI flock, from the leave-one-out records
    (``runs.LEAVE_ONE_OUT``: departure -> the record of the recipe without it): which departures the
    flock needs (without each, it does not flock by ``evaluate.flocked``) and which it does not, each
    with its velocity variance at 5 s (and its share connected at 5 s where that is what fails)."""
    if not without:
        raise ValueError("needs() takes at least one leave-one-out record")
    def listed(xs):
        return xs[0] if len(xs) == 1 else ", ".join(xs[:-1]) + " or " + xs[-1]

    def shown(d):
        rec = without[d]
        cut = rec["share_connected_at_end"] < FLOCKED_CONNECTED
        return (f"{d} ({rec['velocity_variance_median']['5s']:.1e} m²/s²"
                + (f", connected in {rec['share_connected_at_end']:.0%}" if cut else "") + ")")

    needed = [shown(d) for d, rec in without.items() if not flocked(rec)]
    spare = [shown(d) for d, rec in without.items() if flocked(rec)]
    if not spare:
        return (f"VGAI flocks only with every departure from the paper that the book left out in turn: without "
                f"any one of them ({listed(needed)}) it does not flock.")
    if not needed:
        return f"VGAI still flocks without any one of the departures the book left out in turn ({', '.join(spare)})."
    return f"VGAI still flocks without {listed(spare)}; it does not flock without {listed(needed)}."


def steps_text(cells: Sequence[dict], labels: Sequence) -> str:
    """Each step of a series by the criterion: '1 → 2 lower, 2 → 3 within the intervals'."""
    word = {-1: "lower", 0: "within the intervals", 1: "higher"}
    return ", ".join(f"{la} → {lb} {word[compare(b, a)]}"
                     for (la, a), (lb, b) in zip(zip(labels, cells), zip(labels[1:], cells[1:])))


def sentence(claim: str, verdict: str, cells: Sequence[dict], labels: Sequence) -> str:
    """The finding as a sentence generated from the data: the claim, the verdict by the criterion
    and the numbers behind it; where the verdict is not HOLDS over more than one step, each step's
    own verdict (a clear first step is not hidden by a later one within its intervals)."""
    how = {HOLDS: "holds in ours: every step is larger than its intervals",
           CONTRADICTED: "does not hold in ours: some step goes the other way by more than its intervals",
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

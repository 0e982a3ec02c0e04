"""Relative cost (section 4), exercise checks and the book's quick-mode switch."""

import importlib

import math
import pytest
import torch

from vgai_lite import ExpertController, FlockConfig, LocalController, relative_cost
from vgai_lite.controllers import potential_gradient
from vgai_lite.lab.exercises import check_flocking_cost, check_potential_gradient
from vgai_lite.flocking import flocking_cost


def test_the_expert_against_itself_costs_exactly_one():
    cfg = FlockConfig(N=20, T=60)
    res = relative_cost(ExpertController(cfg), cfg, episodes=6, seed=1, batch=4)
    assert res.mean_ratio == pytest.approx(1.0) and res.median_ratio == pytest.approx(1.0)
    assert torch.equal(res.safety.min_distance, res.expert_safety.min_distance)


def test_local_heuristic_is_worse_than_the_centralized_expert():
    cfg = FlockConfig()
    res = relative_cost(LocalController(cfg), cfg, episodes=8, seed=0)
    assert res.mean_ratio > 2.0        # the paper's upper bound: Local 4.13 at the defaults
    lo, hi = res.mean_ratio_ci
    assert lo <= res.mean_ratio <= hi
    s = res.summary()
    assert s["episodes"] == 8 and 0 <= s["share_below_0.1m"] <= 1
    assert "relative cost" in str(res)


def test_relative_cost_says_whether_it_flocked_without_changing_the_cost():
    """The flocking figures come from the same flights flown on to 5 s; the cost and closest
    approaches stay those of the paper's T-step episode. The expert aligns every velocity; the
    local heuristic at R = 1.5 m leaves disagreements and splits the swarm."""
    cfg = FlockConfig(N=20, T=60)
    with_flock = relative_cost(LocalController(cfg), cfg, episodes=4, seed=3)
    without = relative_cost(LocalController(cfg), cfg, episodes=4, seed=3, flock_times=())
    assert torch.equal(with_flock.cost, without.cost) and without.flocking is None
    assert torch.equal(with_flock.safety.min_distance, without.safety.min_distance)
    f = with_flock.flocking
    assert f.times == (2.0, 5.0) and f.variance.shape == (4, 2) and f.groups_at_end.shape == (4,)
    s = with_flock.summary()
    assert set(s["velocity_variance_median"]) == {"2s", "5s"} and 0 <= s["share_connected_at_end"] <= 1
    assert "velocity variance" in str(with_flock)
    expert = relative_cost(ExpertController(cfg), cfg, episodes=4, seed=3).flocking
    assert expert.median_variance()[5.0] < 1e-6 and expert.share_connected == 1.0
    assert f.median_variance()[5.0] > 100 * expert.median_variance()[5.0]
    with pytest.raises(ValueError, match="flock_times"):
        relative_cost(LocalController(cfg), cfg, episodes=2, seed=0, flock_times=(-1.0,))


def test_relative_cost_uses_the_same_initial_conditions_for_a_seed():
    cfg = FlockConfig(N=20, T=40)
    a = relative_cost(LocalController(cfg), cfg, episodes=4, seed=3)
    b = relative_cost(LocalController(cfg), cfg, episodes=4, seed=3)
    assert torch.equal(a.cost, b.cost) and torch.equal(a.expert_cost, b.expert_cost)


def test_checks_pass_the_library_and_fail_wrong_answers_without_raising(capsys):
    from vgai_lite.config import FlockConfig as C

    def grad(r_ij, rho):  # the paper's potential, written out: the library's own is refused as an answer
        d2 = r_ij.square().sum(-1, keepdim=True).clamp(min=1e-6)
        return torch.where(d2 <= rho ** 2, -2 * r_ij * (1 / d2 ** 2 + 1 / d2), torch.zeros_like(r_ij))

    r = torch.randn(40, 2, dtype=torch.float64) * 0.4
    torch.testing.assert_close(grad(r, 0.5), potential_gradient(r, C(rho=0.5)))  # it is the library's
    assert check_potential_gradient(grad)
    wrong_sign = check_potential_gradient(lambda r_ij, rho: -grad(r_ij, rho))
    assert not wrong_sign and "sign" in wrong_sign.message
    no_cutoff = check_potential_gradient(lambda r_ij, rho: grad(r_ij, 100.0))
    assert not no_cutoff and "rho" in no_cutoff.message

    def crashes(r_ij, rho):
        raise KeyError("oops")

    crashed = check_potential_gradient(crashes)
    assert not crashed and "KeyError" in crashed.message

    def unfinished(r_ij, rho):
        raise NotImplementedError

    assert "not implemented" in check_potential_gradient(unfinished).message
    def cost(v):  # eq. 1 written out
        return (v - v.mean(2, keepdim=True)).square().sum(-1).mean(-1).sum(0)

    v = torch.randn(5, 3, 7, 2, dtype=torch.float64)
    torch.testing.assert_close(cost(v), flocking_cost(v))
    assert check_flocking_cost(cost)
    avg = check_flocking_cost(lambda v: cost(v) / v.shape[0])
    assert not avg and "sum over time" in avg.message
    out = capsys.readouterr().out
    assert "PASSED" in out and "NOT PASSED" in out


def test_quick_mode_is_read_from_one_environment_variable(monkeypatch):
    import vgai_lite.book as book

    monkeypatch.setenv("VGAI_LITE_QUICK", "1")
    assert importlib.reload(book).QUICK and book.pick(100, 2) == 2
    monkeypatch.setenv("VGAI_LITE_QUICK", "0")
    assert not importlib.reload(book).QUICK and book.pick(100, 2) == 100
    monkeypatch.setenv("VGAI_LITE_QUICK", "maybe")
    with pytest.raises(ValueError, match="VGAI_LITE_QUICK"):
        importlib.reload(book)
    monkeypatch.setenv("VGAI_LITE_QUICK", "1")
    importlib.reload(book)


def _copy(f):
    """A function object with the library function's code: the checks refuse the library's own objects."""
    import types

    return types.FunctionType(f.__code__, f.__globals__, f"copy_of_{f.__name__}", f.__defaults__, f.__closure__)


def test_aggregation_and_feature_checks_pass_the_library_and_catch_mistakes():
    from vgai_lite.aggregation import aggregation_sequence
    from vgai_lite.lab.exercises import check_aggregation_sequence, check_local_features
    from vgai_lite.features import local_features

    aggregation_sequence, local_features = _copy(aggregation_sequence), _copy(local_features)  # not the forbidden objects
    assert check_aggregation_sequence(lambda X, S, K: aggregation_sequence(X[None], S[None], K)[0, -1])

    def static_graph(X, S, K):  # uses S(t)^k: forgets that the graph moves
        return torch.stack([torch.linalg.matrix_power(S[-1], k) @ X[-1 - k] for k in range(K)], dim=1)

    wrong = check_aggregation_sequence(static_graph)
    assert not wrong and "graph changes over time" in wrong.message
    assert check_local_features(lambda r, v, R: local_features(r[None], v[None], R)[0])
    flipped = check_local_features(lambda r, v, R: -local_features(r[None], v[None], R)[0])
    assert not flipped and "Sign flipped" in flipped.message


def test_consensus_figures_tell_a_flock_from_a_swarm_that_falls_apart():
    from vgai_lite.consensus import consensus, groups

    cfg = FlockConfig(N=20)
    flock = consensus(ExpertController(cfg), cfg, episodes=2, seed=0, times=(0.0, 1.0))
    v0, v1 = flock.median_variance().values()
    assert v1 < 1e-3 * v0  # the expert aligns every velocity within a second
    assert flock.share_connected == 1.0 and flock.summary()["episodes"] == 2
    # two clusters 10 m apart are two groups; joined by a chain of neighbours they are one
    r = torch.tensor([[[0.0, 0.0], [1.0, 0.0], [10.0, 0.0], [11.0, 0.0]]])
    assert groups(r, 1.5).tolist() == [2]
    chain = torch.tensor([[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]]])
    assert groups(chain, 1.5).tolist() == [1]


def test_connected_at_start_reads_the_graph_the_flown_episodes_start_from():
    """Every drone has two neighbours at t = 0 (the sampler's constraint) but at R = 1 m some graphs start in
    pieces: connected_at_start must tell those episodes apart, on the very initial conditions flown."""
    from vgai_lite.consensus import connected_at_start
    from vgai_lite.flocking import sample_initial_state

    cfg = FlockConfig(R=1.0)
    start = connected_at_start(cfg, 10, seed=3000)
    r0, _ = sample_initial_state(cfg, 10, torch.Generator().manual_seed(3000))
    for e in range(10):  # an independent breadth-first search over the same positions
        near = (torch.cdist(r0[e], r0[e]) <= cfg.R).tolist()
        seen, todo = {0}, [0]
        while todo:
            i = todo.pop()
            new = {j for j, n in enumerate(near[i]) if n} - seen
            seen |= new
            todo += list(new)
        assert bool(start[e]) == (len(seen) == cfg.N), e
    assert 0 < int(start.sum()) < 10  # these episodes hold both kinds
    assert bool(connected_at_start(FlockConfig(), 10, seed=3000).all())  # at R = 1.5 m every one starts connected

def test_prose_renders_computed_numbers_and_refuses_what_it_cannot():
    import pytest

    from vgai_lite.book import prose

    assert prose("Local costs {r:.1f}× the expert's.", r=4.281).data == "Local costs 4.3× the expert's."
    with pytest.raises(ValueError, match="missing"):
        prose("{a} and {b}", a=1)
    with pytest.raises(ValueError, match="finite"):
        prose("{a:.2f}", a=float("nan"))


def test_the_lab_command_trusts_exactly_the_books_notebooks(tmp_path, monkeypatch):
    import shutil

    import nbformat
    from nbformat.sign import NotebookNotary

    from vgai_lite.lab.cli import trust_book
    from vgai_lite.book import ROOT

    monkeypatch.setenv("JUPYTER_DATA_DIR", str(tmp_path / "data"))
    book = tmp_path / "notebooks"
    book.mkdir()
    for p in sorted((ROOT / "notebooks").glob("0[0-1]_*.ipynb")):
        shutil.copy(p, book / p.name)
    nb = nbformat.read(book / "00_overview.ipynb", as_version=4)
    assert not NotebookNotary().check_signature(nb)          # a fresh clone: not trusted
    assert trust_book(book) == ["00_overview.ipynb", "01_flocking_dynamics_and_expert.ipynb"]
    assert NotebookNotary().check_signature(nbformat.read(book / "00_overview.ipynb", as_version=4))
    nb.cells[0].source += " (edited)"                         # a changed notebook is not trusted
    assert not NotebookNotary().check_signature(nb)


def test_a_share_of_connected_episodes_is_judged_by_its_interval():
    from vgai_lite.lab import findings
    lo, hi = findings.share_interval(1.0, 20)
    assert hi == pytest.approx(1.0) and 0.8 < lo < 0.87  # Wilson: 20 of 20 still allows about 84 %
    lo0, hi0 = findings.share_interval(0.0, 20)
    assert lo0 == pytest.approx(0.0, abs=1e-12) and 0.13 < hi0 < 0.2
    rec = lambda share, n=20: {"share_connected_at_end": share, "episodes": n}
    assert findings.compare_connected(rec(0.55), rec(1.0)) == -1  # 11 of 20 against 20 of 20: a split
    assert findings.compare_connected(rec(1.0), rec(0.55)) == 1
    assert findings.compare_connected(rec(0.85), rec(1.0)) == 0  # 17 of 20: within the intervals
    assert findings.compare_connected(rec(0.9, 10), rec(1.0, 10)) == 0
    with pytest.raises(ValueError, match="share"):
        findings.share_interval(1.2, 20)
    with pytest.raises(ValueError, match="episode"):
        findings.share_interval(0.5, 0)


def test_findings_use_one_criterion():
    from vgai_lite.lab import findings

    a = {"relative_cost_mean": 2.0, "relative_cost_mean_ci95": [1.9, 2.1]}
    b = {"relative_cost_mean": 1.5, "relative_cost_mean_ci95": [1.4, 1.6]}
    c = {"relative_cost_mean": 1.55, "ci95": None, "per_seed": [1.5, 1.6], "seed_std": 0.07}
    assert findings.compare(b, a) == -1 and findings.compare(a, b) == 1 and findings.compare(b, c) == 0
    assert findings.trend([a, b], -1) == findings.HOLDS
    assert findings.trend([b, a], -1) == findings.CONTRADICTED
    assert findings.trend([a, b, c], -1) == findings.CANNOT_TELL
    assert "cannot be told" in findings.sentence("x", findings.CANNOT_TELL, [a, b], [6, 24])


def test_a_series_that_cannot_be_told_names_its_clear_steps():
    """03's 'each further exchange lowers it again': 1 → 2 is clear, 2 → 3 is not; the sentence says both."""
    from vgai_lite.lab import findings

    k1, k2, k3 = ({"relative_cost_mean": m, "relative_cost_mean_ci95": [m - h, m + h]}
                  for m, h in ((1.29, 0.035), (1.15, 0.015), (1.14, 0.02)))
    verdict = findings.trend([k1, k2, k3], -1)
    assert verdict == findings.CANNOT_TELL
    text = findings.sentence("Each further exchange lowers it", verdict, [k1, k2, k3], [1, 2, 3])
    assert "1 → 2 lower, 2 → 3 within the intervals" in text
    assert "step by step" not in findings.sentence("x", findings.trend([k1, k2], -1), [k1, k2], [1, 2])


def test_the_sentence_on_what_the_flock_needs_judges_each_departure_against_the_recipes_own_seeds():
    from vgai_lite.evaluate import FLOCKED_CONNECTED, FLOCKED_VARIANCE
    from vgai_lite.lab import findings

    flocks = {"velocity_variance_median": {"5s": FLOCKED_VARIANCE / 2}, "share_connected_at_end": 1.0,
              "flocking_horizon_s": 5.0}
    apart = {**flocks, "velocity_variance_median": {"5s": 10 * FLOCKED_VARIANCE}}
    cut = {**flocks, "share_connected_at_end": FLOCKED_CONNECTED / 2}
    near = {**flocks, "velocity_variance_median": {"5s": 2 * FLOCKED_VARIANCE}}  # not flocked, within the seeds
    seeds = [flocks, {**flocks, "velocity_variance_median": {"5s": 3 * FLOCKED_VARIANCE}}]  # 1 of 2 seeds flocks
    both = findings.needs({"depth": apart, "warm starts": cut}, seeds)
    assert "beyond the spread" in both and "depth" in both and "warm starts" in both and "still flocks" not in both
    assert f"connected in {FLOCKED_CONNECTED / 2:.0%}" in both  # the share connected where that fails
    some = findings.needs({"depth": flocks, "warm starts": apart, "odd features": near}, seeds)
    assert some.startswith(f"VGAI still flocks without depth ({FLOCKED_VARIANCE / 2:.1e} m²/s²); it does not flock, "
                           f"beyond the spread of the recipe's own trainings, without warm starts "
                           f"({10 * FLOCKED_VARIANCE:.1e} m²/s²); without odd features ({2 * FLOCKED_VARIANCE:.1e} m²/s²) "
                           "it does not flock in its one training, but within that spread")
    assert "1 of 2 flock" in some and f"{3 * FLOCKED_VARIANCE:.1e}" in some  # the seeds' own spread is said
    # a row that does not flock is "needed" only beyond the worst seed: with seeds that all fly apart, nothing is
    assert "beyond" not in findings.needs({"depth": apart}, [apart, {**apart, "share_connected_at_end": 0.0}])
    with pytest.raises(ValueError):
        findings.needs({}, seeds)
    with pytest.raises(ValueError):
        findings.needs({"depth": apart}, [flocks])


def test_one_training_widens_its_interval_by_the_spread_between_training_seeds():
    from vgai_lite.lab import findings

    a = {"relative_cost_mean": 1.5, "relative_cost_mean_ci95": [1.45, 1.55]}
    b = {"relative_cost_mean": 1.8, "relative_cost_mean_ci95": [1.75, 1.85]}
    assert findings.compare(a, b) == -1  # the episodes alone tell them apart
    spread = findings.seed_spread([{"relative_cost_mean": c} for c in (1.4, 1.6, 1.5, 1.7)])
    assert spread == pytest.approx(0.1290994, rel=1e-6)
    wa, wb = findings.one_training(a, spread), findings.one_training(b, spread)
    lo, hi = findings.interval(wa)
    assert lo == pytest.approx(1.5 - (0.05 ** 2 + (1.96 * spread) ** 2) ** 0.5) and hi > 1.55
    assert findings.compare(wa, wb) == 0  # two single trainings 0.3 apart: within what seeds do
    far = findings.one_training({"relative_cost_mean": 3.0, "relative_cost_mean_ci95": [2.9, 3.1]}, spread)
    assert findings.compare(wa, far) == -1
    assert findings.trend([wa, wb], -1) == findings.CANNOT_TELL
    with pytest.raises(ValueError):
        findings.seed_spread([{"relative_cost_mean": 1.0}])
    with pytest.raises(ValueError):
        findings.one_training(a, float("nan"))
    with pytest.raises(ValueError):
        findings.one_training({**a, "per_seed": [1.4, 1.6]}, spread)


def test_flocked_reads_the_variance_at_5_s_and_the_connectivity():
    from vgai_lite.evaluate import FLOCKED_CONNECTED, FLOCKED_VARIANCE, flocked

    rec = {"velocity_variance_median": {"2s": 1.0, "5s": FLOCKED_VARIANCE}, "share_connected_at_end": FLOCKED_CONNECTED,
           "flocking_horizon_s": 5.0}
    assert flocked(rec)
    assert not flocked({**rec, "velocity_variance_median": {"2s": 0.0, "5s": 1.01 * FLOCKED_VARIANCE}})
    assert not flocked({**rec, "share_connected_at_end": FLOCKED_CONNECTED - 0.02})
    with pytest.raises(ValueError, match="5 s"):
        flocked({"velocity_variance_median": {"2s": 0.0}, "share_connected_at_end": 1.0, "flocking_horizon_s": 2.0})
    # a table cell carries no horizon: its flight ends at the last time its variance was read
    cell = {k: v for k, v in rec.items() if k != "flocking_horizon_s"}
    assert flocked(cell)
    with pytest.raises(ValueError, match="5 s"):  # flown on to 10 s: connected at 10 s, not 5 s
        flocked({**cell, "velocity_variance_median": {"2s": 0.0, "5s": 0.0, "10s": 0.0}})


def test_threads_reads_its_variable_and_refuses_nonsense(monkeypatch):
    from vgai_lite.book import THREADS_ENV, threads

    monkeypatch.delenv(THREADS_ENV, raising=False)
    assert threads() == 2
    monkeypatch.setenv(THREADS_ENV, "1")
    assert threads() == 1
    for bad in ("0", "two", "-1"):
        monkeypatch.setenv(THREADS_ENV, bad)
        with pytest.raises(ValueError, match=THREADS_ENV):
            threads()


def test_as_safe_as_expert_reads_both_safety_figures_against_the_experts():
    from vgai_lite.evaluate import as_safe_as_expert

    rec = {"share_below_0.05m": 0.06, "expert_share_below_0.05m": 0.04, "median_min_distance": 0.15,
           "expert_median_min_distance": 0.16}
    assert as_safe_as_expert(rec)
    assert as_safe_as_expert({**rec, "share_below_0.05m": 0.05, "expert_share_below_0.05m": 0.0})  # the floor
    assert not as_safe_as_expert({**rec, "share_below_0.05m": 0.10})           # 6 points above the expert
    assert not as_safe_as_expert({**rec, "median_min_distance": 0.14})         # below 0.9 of the expert's
    with pytest.raises(ValueError, match="expert_share_below_0.05m"):
        as_safe_as_expert({"share_below_0.05m": 0.0, "median_min_distance": 0.1, "expert_median_min_distance": 0.1})


def test_a_variance_near_the_flock_threshold_prints_so_that_its_label_can_be_read():
    from vgai_lite.evaluate import FLOCKED_VARIANCE, variance_text

    assert variance_text(1.4e-3) == "1.4e-03" and variance_text(0.0) == "0.0e+00"
    below, above = variance_text(0.9993 * FLOCKED_VARIANCE), variance_text(1.0102 * FLOCKED_VARIANCE)
    assert below != above and float(below) <= FLOCKED_VARIANCE < float(above)
    for bad in (float("nan"), -1e-3):
        with pytest.raises(ValueError, match="non-negative"):
            variance_text(bad)


def test_the_noise_that_breaks_a_flock_is_the_smallest_that_does_not_flock_whatever_the_keys_order():
    from vgai_lite.lab.findings import noise_that_breaks

    def cell(var):
        return {"velocity_variance_median": {"5s": var}, "share_connected_at_end": 1.0, "flocking_horizon_s": 5.0}

    settings = {"clean": cell(5e-4), "noise0.1": cell(0.3), "noise0.01": cell(1e-3), "noise0.05": cell(0.2),
                "noise0.02": cell(4e-3), "blur2.8": cell(0.5)}
    assert noise_that_breaks(settings) == 0.02
    assert noise_that_breaks({"noise0.01": cell(1e-3)}) == math.inf
    with pytest.raises(ValueError, match="no noise setting"):
        noise_that_breaks({"clean": cell(1e-3), "blur1": cell(1.0)})


def test_one_trainings_flock_is_told_only_beyond_the_spread_of_the_seeds_it_is_judged_against():
    from vgai_lite.evaluate import FLOCKED_CONNECTED, FLOCKED_VARIANCE
    from vgai_lite.lab import findings

    def rec(var, connected=1.0):
        return {"velocity_variance_median": {"5s": var}, "share_connected_at_end": connected, "flocking_horizon_s": 5.0}

    seeds = [rec(FLOCKED_VARIANCE / 2), rec(3 * FLOCKED_VARIANCE)]  # one seed flocks, one does not
    assert findings.flock_verdict(rec(FLOCKED_VARIANCE / 4), seeds) == -1   # flocks, tighter than every seed
    assert findings.flock_verdict(rec(FLOCKED_VARIANCE / 1.5), seeds) == 0  # flocks, but so does a seed
    assert findings.flock_verdict(rec(2 * FLOCKED_VARIANCE), seeds) == 0    # does not flock, nor does a seed
    assert findings.flock_verdict(rec(10 * FLOCKED_VARIANCE), seeds) == 1   # beyond the worst seed
    assert findings.flock_verdict(rec(FLOCKED_VARIANCE / 4, FLOCKED_CONNECTED / 2), seeds) == 1  # its swarm splits
    with pytest.raises(ValueError):
        findings.flock_verdict(rec(1.0), seeds[:1])


def test_a_trend_reversed_end_to_end_is_contradicted_even_when_every_step_is_within_its_intervals():
    from vgai_lite.lab import findings

    def c(m, h):
        return {"relative_cost_mean": m, "relative_cost_mean_ci95": [m - h, m + h]}

    falling = [c(5.6, 0.3), c(5.1, 0.4), c(4.4, 0.4)]  # each step within the intervals, the ends apart
    assert findings.trend(falling, 1) == findings.CONTRADICTED   # "rises" is contradicted end to end
    assert findings.trend(falling, -1) == findings.CANNOT_TELL   # "falls" holds at no single step
    assert findings.steps_text(falling, [1, 2, 3]).endswith("1 → 3 lower")

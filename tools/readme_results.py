"""Write the README's results section from the records in data/ (no number in it is typed by hand).

    python tools/readme_results.py           # print the section
    python tools/readme_results.py --write   # replace it in README.md, between the markers

The section lies between ``<!-- results:begin -->`` and ``<!-- results:end -->``; a test checks that
the committed README equals what this script writes.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from vgai_lite.evaluate import FLOCKED_CONNECTED, FLOCKED_VARIANCE, flocked  # noqa: E402
from vgai_lite.ray_runner import projected_hours  # noqa: E402
from vgai_lite.reproduce import PAPER  # noqa: E402

BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"
README = ROOT / "README.md"


def _load(rel: str) -> dict:
    return json.loads((ROOT / rel).read_text())


def _ci(rec: dict) -> str:
    lo, hi = rec["relative_cost_mean_ci95"]
    return f"{rec['relative_cost_mean']:.2f} ({lo:.2f}-{hi:.2f})"


def _flock(rec: dict) -> str:
    """Did it flock: median velocity variance at 2 s / 5 s and the share connected at 5 s ("-" for a
    record written before relative_cost gave them)."""
    var = rec.get("velocity_variance_median")
    if not var:
        return "- | -"
    return f"{var['2s']:.1e} / {var['5s']:.1e} | {rec['share_connected_at_end']:.0%}"


TRAINED_BESIDE = {"K2", "K3"}
"""The book's other VGAIs that trained beside another job (one thread each, on the 2 cores): their
recorded time is not the recipe's time alone."""

TRAINED_ALONE = {"vgai_F24_seed2"}
"""The shipped training seeds that trained alone on the 2 cores (seeds 0 and 1 trained two at a time,
one thread each, in the session that added them): their recorded time is the recipe's time alone."""


def _recipe(rec: dict) -> str:
    return "" if rec["train_config"].get("motion_features") else " (last round's plain CNN)"


TEST_LABELS = {"local": "Local heuristic", "dagnn_K4": "DAGNN, K-1 = 3", "vgai_F24": "VGAI, F = 24, K-1 = 3 (the shipped recipe)"}

LEARNER_SEEDS = {0: "vgai_learner", 1: "vgai_learner_s1", 2: "vgai_learner_s2"}
"""The learner-alone recipe's trainings (data/experiments/, notebook 06), by training seed."""


def _label(name: str) -> str:
    if name in TEST_LABELS:
        return TEST_LABELS[name]
    seed = {v: k for k, v in LEARNER_SEEDS.items()}.get(name)
    if seed is None:
        return name
    val = {n: _load(f"data/experiments/{n}.json")["relative_cost_mean"] for n in LEARNER_SEEDS.values()
           if (ROOT / "data" / "experiments" / f"{n}.json").is_file()}
    chosen = f", the lowest validation cost of {len(val)} seeds" if min(val, key=val.get) == name else ""
    return (f"VGAI, F = 24, K-1 = 3, + the learner flying alone in half the DAgger swarms (training seed {seed}"
            f"{chosen}; `data/experiments/{name}.pt`; notebook 06)")


def _test_table() -> list:
    """The headline figures on the test episodes (data/test/, tools/test_episodes.py), if any."""
    recs = {p.stem: json.loads(p.read_text()) for p in sorted((ROOT / "data" / "test").glob("*.json"))}
    if not recs:
        return []
    first = next(iter(recs.values()))
    rows = ["| controller | relative cost (95% CI) | velocity variance at 2 s / 5 s [m²/s²] | connected at 5 s | "
            "flocked | episodes < 0.05 m (expert) | median closest [m] (expert) |", "|---|---|---|---|---|---|---|"]
    for name, r in recs.items():
        rows.append(f"| {_label(name)} | {_ci(r)} | {_flock(r).rsplit(' | ', 1)[0]} | "
                    f"{r['share_connected_at_end']:.0%} | {'yes' if flocked(r) else 'no'} | "
                    f"{r['share_below_0.05m']:.0%} ({r['expert_share_below_0.05m']:.0%}) | "
                    f"{r['median_min_distance']:.3f} ({r['expert_median_min_distance']:.3f}) |")
    return [f"**On the test episodes** ({first['episodes']} episodes of seed {first['seed']}, never used for a choice; "
            "`python tools/test_episodes.py`, records with their provenance in `data/test/`; \"flocked\": velocity "
            f"variance at 5 s at most {FLOCKED_VARIANCE:.0e}".replace("e-0", "e-") + f" m²/s² and connected in {FLOCKED_CONNECTED:.0%} of the "
            "episodes, `evaluate.flocked`):", "", *rows, "",
            "The tables below were computed on the book's earlier held-out episodes (seed "
            f"{_load('data/dagnn/dagnn_K4.json')['seed']}), on which recipes were also compared; they move to the test "
            "episodes when they are next recomputed.", ""]


def section() -> str:
    dagnn = {k: _load(f"data/dagnn/dagnn_K{k}.json") for k in (1, 2, 3, 4)}
    vgai = {n: _load(f"data/vgai/vgai_{n}.json") for n in ("F24", "F12", "F6", "K3", "K2")}
    results = _load("data/results/results.json")
    choice = _load("data/vgai/seeds/choice.json")
    n75 = _load("data/vgai/vgai_F24_N75.json")
    seed_recs = {n: _load(f"data/vgai/seeds/{n}.json") for n in choice["candidates"]}
    mean_seeds = sum(r["relative_cost_mean"] for r in seed_recs.values()) / len(seed_recs)
    seeds_note = (f"training seed {choice['chosen_seed']} of {len(seed_recs)}, chosen on {choice['episodes']} "
                  f"selection episodes; mean of the {len(seed_recs)} seeds {mean_seeds:.2f}")
    prov = results["provenance"]
    scratch = [i for i in prov.get("invocations", []) if i["retrain"]]
    eps = dagnn[4]["episodes"]
    p = PAPER

    def vg_minutes(rec):
        return (rec["train_seconds"] + (rec.get("stage1_seconds") or 0.0 if rec.get("stage1_cached") else 0.0)) / 60

    local_rec = _load("data/local/local.json")
    rows = [
        "| controller | relative cost (95% CI) | paper | velocity variance at 2 s / 5 s [m²/s²] | connected at 5 s | command |",
        "|---|---|---|---|---|---|",
        f"| Local heuristic | {_ci(local_rec)} | {p['v_init']['Local'][3.0]:.2f} | {_flock(local_rec)} | "
        "`python -m vgai_lite evaluate --controller local --json data/local/local.json` |",
        f"| DAGNN, K-1 = 3 | {_ci(dagnn[4])} | {p['K']['DAGNN'][3]:.2f} | {_flock(dagnn[4])} | "
        "`python -m vgai_lite train-dagnn dagnn_K4` |",
        *[f"| DAGNN, K-1 = {k - 1} | {_ci(dagnn[k])} | {p['K']['DAGNN'].get(k - 1, '-')} | {_flock(dagnn[k])} | "
          f"`python -m vgai_lite train-dagnn dagnn_K{k}` |" for k in (1, 2, 3)],
        f"| VGAI, F = 24, K-1 = 3 (images only; {seeds_note}) | {_ci(vgai['F24'])} | {p['F']['VGAI'][24]:.2f} | "
        f"{_flock(vgai['F24'])} | `python -m vgai_lite train-vgai vgai_F24` |",
        *[f"| VGAI, F = 24, training seed {c['training_seed']} | {_ci(seed_recs[n])} | | {_flock(seed_recs[n])} | "
          f"`python -m vgai_lite train-vgai --seeds` |" for n, c in choice["candidates"].items()],
        f"| VGAI, F = 24, flown by N' = 75 (trained on 50) | {_ci(n75)} | {p['N']['VGAI'][75]:.2f} | {_flock(n75)} | "
        "`python -m vgai_lite evaluate --controller data/vgai/vgai_F24.pt --N 75 --episodes 50 "
        "--json data/vgai/vgai_F24_N75.json` |",
        *[f"| VGAI, {label}{_recipe(vgai[n])} | {_ci(vgai[n])} | {paper:.2f} | {_flock(vgai[n])} | "
          f"`python -m vgai_lite train-vgai vgai_{n}` |"
          for n, label, paper in (("K2", "K-1 = 1", p['K']['VGAI'][1]), ("K3", "K-1 = 2", p['K']['VGAI'][2]),
                                  ("F6", "F = 6", p['F']['VGAI'][6]), ("F12", "F = 12", p['F']['VGAI'][12]))],
    ]
    d4, v24 = dagnn[4], vgai["F24"]
    text = [
        *_test_table(),
        f"All on {eps} held-out episodes (seed {d4['seed']}) unless stated, N = 50, R = 1.5 m, v_init = 3 m/s; "
        "relative cost = cost of eq. 1 over the centralized expert's cost on the same initial conditions.",
        "",
        *rows,
        "",
        "Did it flock: the velocity variance (1/N) Σ‖v_i − v̄‖² (eq. 1's summand) at 2 s, the end of the paper's "
        "episode, and at 5 s of the same flights flown on (median over the episodes), and the share of episodes whose "
        "communication graph is still connected at 5 s."
        + (" The rows marked \"last round's plain CNN\" were trained before the recipe of notebook 06, section 6."
           if any(_recipe(r) for r in vgai.values()) else
           " Every VGAI here is trained with the recipe of notebook 06, section 6."),
        "",
        f"Safety on the same episodes: episodes with a pair closer than 0.05 m: DAGNN {d4['share_below_0.05m']:.0%}, "
        f"VGAI {v24['share_below_0.05m']:.0%}, expert {d4['expert_share_below_0.05m']:.0%}; median closest approach "
        f"DAGNN {d4['median_min_distance']:.3f} m, VGAI {v24['median_min_distance']:.3f} m, expert "
        f"{d4['expert_median_min_distance']:.3f} m.",
        "",
        f"Training time on this 2-core machine: the default DAGNN {d4['train_seconds']:.0f} s alone. The default "
        "VGAI's training seeds: " + ", ".join(
            f"seed {choice['candidates'][n]['training_seed']} {r['train_seconds'] / 60:.0f} min "
            + ("alone" if n in TRAINED_ALONE else "beside another training (one thread each)")
            for n, r in seed_recs.items()) + ". The other VGAIs: "
        + ", ".join(f"{n}{_recipe(r)} {vg_minutes(r):.1f} min"
                    + (" (beside another job, one thread each)" if n in TRAINED_BESIDE else " alone")
                    for n, r in vgai.items() if n != "F24")
        + " (a run that reuses a cached first stage counts that stage's recorded time in its own)."
        + (f" The from-scratch reproduction of every table (`python -m vgai_lite reproduce --retrain --seeds 1`), "
           f"which trained last round's VGAIs, took {scratch[-1]['wall_seconds'] / 60:.0f} min." if scratch else ""),
        "",
        _tables(results),
        "",
        _robustness(),
    ]
    return "\n".join([BEGIN, *text, END])


def _tables(results: dict) -> str:
    """One paragraph: how the tables of notebook 07 were computed, and the quick run on Ray."""
    prov = results["provenance"]
    rc = prov["reproduce_config"]
    last = prov["invocations"][-1]
    text = (f"The paper's tables (notebook 07, `{last['command']}`; {rc['episodes']} held-out episodes per cell, "
            f"{rc['episodes_large']} at N' >= 100; DAGNN rows over {rc['seeds']} training seeds, VGAI rows "
            f"{rc['vgai_seeds']} training each): its last invocation computed {last['cells_computed_now']} cells and "
            f"trained {last['models_trained_now']} models in {last['wall_seconds'] / 60:.0f} min; "
            f"{prov['compute_seconds']['cells']} cells in all.")
    ray_file = ROOT / "data" / "experiments" / "ray_quick.json"
    if ray_file.is_file():
        rq = json.loads(ray_file.read_text())
        text += (f" On Ray (`{rq['command']}`, the quick run of every table on this {rq['cpus']}-core machine): "
                 f"serial {rq['serial_2_threads_seconds']:.0f} s (2 threads), {rq['serial_1_thread_seconds']:.0f} s "
                 f"(1 thread), Ray {rq['ray_seconds']:.0f} s (2 CPUs, 1 thread per task), {rq['ray_over_serial']:.2f}x "
                 f"the serial run; tables {'identical' if rq['ray_equals_serial_1_thread'] else 'NOT identical'} "
                 "to the 1-thread serial run's.")
    proj = {m: projected_hours(results, ROOT / "data" / "results", m) for m in (1, 4, 16)}
    text += (" The full reproduction with 3 training seeds per VGAI row, projected from these cells' recorded times "
             "(`vgai_lite.ray_runner.projected_hours`, notebook 07): "
             + ", ".join(f"{p['projected_hours']:.1f} h on {m} machine{'s' if m > 1 else ''}" for m, p in proj.items())
             + " of 2 cores.")
    return text


def _robustness() -> str:
    """One paragraph: the targets of notebook 08's sweep, with the noise-trained VGAI beside."""
    import sys

    sys.path.insert(0, str(ROOT))
    from vgai_lite import robustness

    res = robustness.load(ROOT / "data" / "robustness")
    T = robustness.TARGETS
    local, clean = robustness.find(res, "Local"), robustness.find(res, "VGAI")
    links = robustness.find(res, "VGAI", (("links", T["links_p"]),))
    noisy = robustness.find(res, "VGAI", (("image_noise", T["image_noise_sigma"]),))
    dl = robustness.find(res, "DAGNN", (("links", T["links_p"]),))
    aug = _load("data/experiments/vgai_F24_noise_augmented.json")["image_noise"][f"{T['image_noise_sigma']:g}"]
    eps = res["config"]["episodes"]
    return (f"Robustness (notebook 08, `python -m vgai_lite reproduce --only robustness`; {eps} held-out episodes per "
            f"cell): with {T['links_p']:.0%} of messages lost VGAI costs {_ci(links)} (clean {_ci(clean)}; Local "
            f"unperturbed {local['relative_cost_mean']:.2f}), connected at 5 s in {links['share_connected_at_end']:.0%} "
            f"of episodes; the DAGNN {_ci(dl)}. With pixel noise sigma = {T['image_noise_sigma']:g} VGAI costs "
            f"{_ci(noisy)}, {noisy['relative_cost_mean'] / clean['relative_cost_mean']:.2f}x its clean cost; trained two "
            f"more rounds on noisy frames (`python tools/experiments/noise_augmentation.py`) {_ci(aug)}.")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="replace the section in README.md")
    args = ap.parse_args()
    new = section()
    if not args.write:
        print(new)
        return
    text = README.read_text()
    if text.count(BEGIN) != 1 or text.count(END) != 1:
        raise SystemExit(f"README.md must hold {BEGIN} and {END} once each")
    head, rest = text.split(BEGIN)
    _, tail = rest.split(END)
    README.write_text(head + new + tail)
    print("README.md: results section rewritten")


if __name__ == "__main__":
    main()

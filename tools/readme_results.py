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
from vgai_lite.lab.ray_runner import projected_hours  # noqa: E402
from vgai_lite.lab import findings  # noqa: E402
from vgai_lite.lab.reproduce import PAPER  # noqa: E402
from vgai_lite.lab.runs import (PAPER_SEEDS, TIMED_ALONE, TRAINING_TARGET_MINUTES, chosen_camera_runs, seed_records,  # noqa: E402
                                how_trained, training_minutes)
from vgai_lite.vgai_config import VGAITrainConfig, book_recipe  # noqa: E402
from vgai_lite.book import TEST_SEED  # noqa: E402
from vgai_lite.config import FlockConfig  # noqa: E402
from vgai_lite.consensus import connected_at_start  # noqa: E402

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


def _recipe(rec: dict) -> str:
    t = VGAITrainConfig.from_dict(rec["train_config"])
    return "" if t == book_recipe(F=t.F, K=t.K, seed=t.seed) else " (not the book's recipe)"


TEST_LABELS = {"local": "Local heuristic", "dagnn_K4": "DAGNN, K-1 = 3 (exact features)",
               "vgai_F24": "VGAI, F = 24, K-1 = 3 (its own gray and depth images, trained through the camera: the book's recipe)",
               "vgai_clean": "VGAI, the book's recipe on clean frames (no camera model; training seed 0)",
               "vgai_F24_mixture": "VGAI, the recipe on clean frames without the learner flying alone (DAgger's mixture only)"}


def _test_labels() -> dict:
    """TEST_LABELS, then the gray-only camera VGAI notebook 08 chooses and the paper's VGAI (notebook 11)."""
    labels = dict(TEST_LABELS)
    gray = chosen_camera_runs()["gray only"]
    labels[gray] = "VGAI trained through the camera, gray only, no depth (notebook 08's choice; clean frames here)"
    for s in PAPER_SEEDS:
        labels[f"vgai_paper_seed{s}"] = ("The paper's VGAI as the paper describes it (one gray frame, from random "
                                         f"weights), training seed {s}")
    return labels


def _episodes(rec: dict) -> str:
    return f"{rec['episodes']} of seed {rec['seed']}"


def _test_table() -> list:
    """The headline figures on the test episodes (data/test/, tools/test_episodes.py)."""
    labels = _test_labels()
    recs = {name: _load(f"data/test/{name}.json") for name in labels if (ROOT / "data" / "test" / f"{name}.json").is_file()}
    first = next(iter(recs.values()))
    rows = ["| controller | relative cost (95% CI) | velocity variance at 2 s / 5 s [m²/s²] | connected at 5 s | "
            "flocked | episodes < 0.05 m (expert) | median closest [m] (expert) |", "|---|---|---|---|---|---|---|"]
    for name, r in recs.items():
        rows.append(f"| {labels[name]} | {_ci(r)} | {_flock(r).rsplit(' | ', 1)[0]} | "
                    f"{r['share_connected_at_end']:.0%} | {'yes' if flocked(r) else 'no'} | "
                    f"{r['share_below_0.05m']:.0%} ({r['expert_share_below_0.05m']:.0%}) | "
                    f"{r['median_min_distance']:.3f} ({r['expert_median_min_distance']:.3f}) |")
    return [f"**The headline figures, on the test episodes** ({first['episodes']} episodes of seed {first['seed']}, never "
            "used for a choice; `python tools/test_episodes.py`, records with their provenance in `data/test/`; "
            "\"flocked\": velocity variance at 5 s at most "
            f"{FLOCKED_VARIANCE:.0e}".replace("e-0", "e-") + f" m²/s² and connected in {FLOCKED_CONNECTED:.0%} of the "
            "episodes, `evaluate.flocked`):", "", *rows, ""]


def section() -> str:
    dagnn = {k: _load(f"data/dagnn/dagnn_K{k}.json") for k in (1, 2, 3, 4)}
    pn_rec = _load("data/dagnn/dagnn_K4_per_neighbour.json")
    vgai = {n: _load(f"data/vgai/vgai_{n}.json") for n in ("F24", "F12", "F6", "K3", "K2")}
    results = _load("data/results/results.json")
    choice = _load("data/vgai/seeds/choice.json")
    seed_recs = {n: _load(f"data/vgai/seeds/{n}.json") for n in choice["candidates"]}
    alone = _load(f"data/experiments/{TIMED_ALONE}.json")
    alone_command = alone["command"].split(" --note")[0].replace(" --stage1-cache ", ' --stage1-cache ""')  # the note is long
    mean_seeds = sum(r["relative_cost_mean"] for r in seed_recs.values()) / len(seed_recs)
    seeds_note = (f"training seed {choice['chosen_seed']} of {len(seed_recs)}, chosen on validation episodes by the book's rule; "
                  f"mean of the {len(seed_recs)} seeds {mean_seeds:.2f}")
    p = PAPER

    vg_minutes = training_minutes

    local_rec = _load("data/local/local.json")
    rows = [
        "| controller | relative cost (95% CI) | paper | velocity variance at 2 s / 5 s [m²/s²] | connected at 5 s | "
        "episodes | command |",
        "|---|---|---|---|---|---|---|",
        f"| Local heuristic | {_ci(local_rec)} | {p['v_init']['Local'][3.0]:.2f} | {_flock(local_rec)} | {_episodes(local_rec)} | "
        "`python -m vgai_lite evaluate --controller local --json data/local/local.json` |",
        *[f"| DAGNN, K-1 = {k - 1} | {_ci(dagnn[k])} | {format(p['K']['DAGNN'][k - 1], '.2f') if k - 1 in p['K']['DAGNN'] else '-'} | {_flock(dagnn[k])} | "
          f"{_episodes(dagnn[k])} | `python -m vgai_lite train-dagnn dagnn_K{k}` |" for k in (4, 1, 2, 3)],
        f"| VGAI, F = 24, K-1 = 3 ({seeds_note}) | {_ci(vgai['F24'])} | {p['F']['VGAI'][24]:.2f} | "
        f"{_flock(vgai['F24'])} | {_episodes(vgai['F24'])} | `python -m vgai_lite train-vgai --seeds --choose` |",
        *[f"| VGAI, F = 24, training seed {c['training_seed']} | {_ci(seed_recs[n])} | | {_flock(seed_recs[n])} | "
          f"{_episodes(seed_recs[n])} | `python -m vgai_lite train-vgai {n}` |" for n, c in choice["candidates"].items()],
        *[f"| VGAI, {label}{_recipe(vgai[n])} | {_ci(vgai[n])} | {paper:.2f} | {_flock(vgai[n])} | {_episodes(vgai[n])} | "
          f"`python -m vgai_lite train-vgai vgai_{n}` |"
          for n, label, paper in (("K2", "K-1 = 1", p['K']['VGAI'][1]), ("K3", "K-1 = 2", p['K']['VGAI'][2]),
                                  ("F6", "F = 6", p['F']['VGAI'][6]), ("F12", "F = 12", p['F']['VGAI'][12]))],
        f"| DAGNN, K-1 = 3, features per neighbour (the local features' sums divided by the degree; not the paper's) | "
        f"{_ci(pn_rec)} | - | {_flock(pn_rec)} | {_episodes(pn_rec)} | "
        "`python -m vgai_lite train-dagnn dagnn_K4_per_neighbour` |",
    ]
    d4, v24 = dagnn[4], vgai["F24"]
    text = [
        *_test_table(),
        "**Each shipped model's own record** (N = 50, R = 1.5 m, v_init = 3 m/s; relative cost = cost of eq. 1 over "
        "the centralized expert's on the same initial conditions). The VGAIs' records are their evaluations on the "
        "validation episodes, where the choice among training seeds is made; the DAGNNs' and Local's are on the "
        "book's working episodes (seed 2020, notebook 01), on which the chapters compare designs, so neither is a test:",
        "",
        *rows,
        "",
        "Did it flock: the velocity variance (1/N) Σ‖v_i − v̄‖² (eq. 1's summand) at 2 s, the end of the paper's "
        "episode, and at 5 s of the same flights flown on (median over the episodes), and the share of episodes whose "
        "communication graph is still connected at 5 s."
        + (" Rows marked \"not the book's recipe\" were trained before the recipe of notebook 11, section 1."
           if any(_recipe(r) for r in vgai.values()) else
           " Every VGAI here is trained with the book's recipe (notebook 11, section 1)."),
        "",
        f"Training time on this 2-core machine: the default DAGNN {d4['train_seconds']:.0f} s alone. The VGAIs, stages "
        "1-3 in minutes, with their torch threads and whether each had the two cores to itself or shared them with "
        "another job (read from its record's provenance, `runs.how_trained`): "
        + ", ".join(f"seed {choice['candidates'][n]['training_seed']} {vg_minutes(r):.0f}{_how(r)}" for n, r in seed_recs.items())
        + "; " + ", ".join(f"{n}{_recipe(r)} {vg_minutes(r):.0f}{_how(r)}" for n, r in vgai.items() if n != "F24")
        + " (`runs.training_minutes`: a run that reused a cached first stage adds that stage's recorded time). "
        f"The recipe timed alone (training seed {alone['train_config']['seed']}, "
        f"`{alone_command}`): "
        f"{vg_minutes(alone):.0f} min{_how(alone)}, against a target of at most {TRAINING_TARGET_MINUTES} min; "
        f"where they go, `seconds_by_phase` in data/experiments/{TIMED_ALONE}.json (notebook 06). That training costs "
        f"{alone['relative_cost_mean']:.2f} on the validation episodes and {'flocks' if flocked(alone) else 'does not flock'} "
        f"(variance at 5 s {alone['velocity_variance_median']['5s']:.1e} m²/s²).",
        "",
        _tables(results),
        "",
        _robustness(),
    ]
    return "\n".join([BEGIN, *text, END])


def _per_neighbour_cells(results: dict) -> str:
    """The tables' row "DAGNN (per neighbour)" at N' = 200 and R = 1 m against the paper's DAGNN, in one sentence."""
    rows = results["tables"]
    def cell(table, row, column):
        x = rows[table]["rows"][row][column]
        lo, hi = findings.interval(x)
        return (f"{x['relative_cost_mean']:.2f} ({lo:.2f}-{hi:.2f}), variance at 5 s "
                f"{x['velocity_variance_median']['5s']:.1e} m²/s², connected at 5 s in {x['share_connected_at_end']:.0%}, "
                + ("flocked" if flocked(x) else "not flocked"))
    seeds = len(rows["N"]["rows"]["DAGNN (per neighbour)"]["200"]["per_seed"])
    r1 = rows["R"]["rows"]["DAGNN (per neighbour)"]["1.0"]
    start_r1 = float(connected_at_start(FlockConfig(R=1.0), r1["episodes"], seed=TEST_SEED).double().mean())
    seed_recs = seed_records()
    n75 = findings.one_training(rows["N"]["rows"]["VGAI"]["75"], findings.seed_spread(seed_recs))
    lo75, hi75 = findings.interval(n75)
    told = {-1: "flocked, tighter than every one of the recipe's training seeds",
            0: "within the spread of the recipe's training seeds at N = 50, so whether the recipe flocks there cannot be told",
            1: "not flocked, beyond every one of the recipe's training seeds"}[findings.flock_verdict(n75, seed_recs)]
    return (f" Table 3's VGAI at N' = 75 (trained on 50; one training, its interval widened by the spread between the "
            f"recipe's training seeds): {n75['relative_cost_mean']:.2f} ({lo75:.2f}-{hi75:.2f}), the "
            f"paper's {PAPER['N']['VGAI'][75]:.2f}, variance at 5 s {n75['velocity_variance_median']['5s']:.1e} m²/s², "
            f"connected at 5 s in {n75['share_connected_at_end']:.0%}: {told}."
            f" The row *DAGNN (per neighbour)* of Tables 2b and 3 (the paper's DAGNN with the local features' sums divided by each "
            f"drone's degree, trained at N = 50 and R = 1.5 m, {seeds} training seeds): at N' = 200 "
            f"{cell('N', 'DAGNN (per neighbour)', '200')}, against the paper's DAGNN's {cell('N', 'DAGNN', '200')}; at R = 1 m "
            f"{cell('R', 'DAGNN (per neighbour)', '1.0')}, against {cell('R', 'DAGNN', '1.0')}; "
            f"{start_r1:.0%} of these test episodes start with a connected graph at R = 1 m "
            f"(`consensus.connected_at_start`; notebook 03, section 9, flies the DAGNN against that share).")


def _how(record: dict) -> str:
    """" (1 thread, load 2.4)": how a training ran (``runs.how_trained``), or nothing if unrecorded."""
    how = how_trained(record)
    return "" if how is None else f" ({how})"


def _tables(results: dict) -> str:
    """One paragraph: how the tables of notebook 07 were computed, and the quick run on Ray."""
    prov = results["provenance"]
    rc = prov["reproduce_config"]
    last = prov["invocations"][-1]
    stale = rc["seed"] != TEST_SEED
    text = (("**Not yet recomputed on the test episodes, nor for the VGAIs shipped now**: " if stale else "")
            + f"The paper's tables (notebook 07, `{last['command']}`; {rc['episodes']} episodes of seed {rc['seed']} per cell, "
            f"{rc['episodes_large']} at N' >= 100; DAGNN rows over {rc['seeds']} training seeds, VGAI rows "
            f"{rc['vgai_seeds']} training each): "
            + (f"its last invocation computed {last['cells_computed_now']} cells and trained {last['models_trained_now']} "
               f"models in {last['wall_seconds'] / 60:.0f} min; " if last["cells_computed_now"] else "")
            + f"{prov['compute_seconds']['cells']} cells in all, whose evaluations took "
            f"{prov['compute_seconds']['evaluation'] / 60:.0f} min as each cell recorded when it was computed "
            f"(the invocations that computed them, with their commands and threads, are listed in "
            f"`data/results/results.json`).")
    timed_file = ROOT / "data" / "results" / "timed_run.json"
    tr = json.loads(timed_file.read_text()) if timed_file.is_file() else None
    if tr and tr.get("adopted") and tr["command"] == last["command"]:  # the tables ARE one timed run
        text = (f"The paper's tables (notebook 07; {rc['episodes']} episodes of seed {rc['seed']} per cell, "
                f"{rc['episodes_large']} at N' >= 100; DAGNN rows over {rc['seeds']} training seeds, VGAI rows "
                f"{rc['vgai_seeds']} training each, training seed 0 of every configuration, so the F = 24 cell is not "
                f"the headline VGAI above) are one run, alone (`{tr['command']}`): {tr['cells']} evaluations (a DAGNN "
                f"cell is one per training seed) from the shipped checkpoints, {tr['models_trained_now']} models trained, "
                f"in {tr['wall_seconds'] / 60:.0f} min at {tr['provenance']['torch_threads']} threads "
                f"(`data/results/timed_run.json` holds the run's provenance). The trainings those checkpoints record "
                f"took {tr['training_recorded_seconds'] / 3600:.1f} h more." + _per_neighbour_cells(results))
        tr = None
    if tr:  # tools/experiments/reproduce_timed.py: every cell recomputed in one run
        big = tr["largest_difference"]
        text += (f" Recomputed as one run, alone (`{tr['command']}`: all {tr['cells']} cells evaluated anew in a fresh "
                 f"folder from the same checkpoints, {tr['models_trained_now']} models trained): "
                 f"{tr['wall_seconds'] / 60:.0f} min at {tr['provenance']['torch_threads']} threads, load average "
                 f"{tr['provenance']['load_average_mean']:.1f}; "
                 + ("every cell's relative cost equals the committed one to 1e-3" if tr["cells_equal_committed"] else
                    "not every cell's relative cost equals the committed one to 1e-3")
                 + f" (the largest difference: {big['cell']}, {big['committed']} against {big['now']}, "
                 f"{abs(big['now'] - big['committed']) / big['committed']:.2%}). The trainings those checkpoints record "
                 f"took {tr['training_recorded_seconds'] / 3600:.1f} h more.")
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
             "(`vgai_lite.lab.ray_runner.projected_hours`, notebook 10, the appendix): "
             + ", ".join(f"{p['projected_hours']:.1f} h on {m} machine{'s' if m > 1 else ''}" for m, p in proj.items())
             + " of 2 cores.")
    return text


def _robustness() -> str:
    """One paragraph: the targets of notebook 08's sweep, with the VGAIs trained through the camera beside."""
    import sys

    sys.path.insert(0, str(ROOT))
    from vgai_lite.lab import robustness

    res = robustness.load(ROOT / "data" / "robustness")
    T = robustness.TARGETS
    local, clean = robustness.find(res, "Local"), robustness.find(res, "VGAI")
    links = robustness.find(res, "VGAI", (("links", T["links_p"]),))
    noisy = robustness.find(res, "VGAI", (("image_noise", T["image_noise_sigma"]),))
    dl = robustness.find(res, "DAGNN", (("links", T["links_p"]),))
    cams = {sensor: (name, _load(f"data/experiments/{name}_cameras.json")["settings"])
            for sensor, name in chosen_camera_runs().items()}
    authors = f"noise{10 / 255:.4g}"

    def through(sensor):
        name, ev = cams[sensor]
        return (f"{sensor} (`{name}`) {_ci(ev['clean'])} on clean frames, "
                + ("flocked" if ev["clean"]["flocked"] else "not flocked")
                + f" (variance at 5 s {ev['clean']['velocity_variance_median']['5s']:.1e}), and {_ci(ev[authors])} at the "
                "authors' noise of 10/255, " + ("flocked" if ev[authors]["flocked"] else "not flocked")
                + f" ({ev[authors]['velocity_variance_median']['5s']:.1e})")

    eps = res["config"]["episodes"]
    stale = clean.get("checkpoint") != robustness.checkpoint_id(robustness.CONTROLLERS["VGAI"])
    return (("**Not yet recomputed for the shipped VGAI**: the sweep below flew an earlier VGAI of the book. " if stale else "")
            + f"Robustness (notebook 08, `python -m vgai_lite reproduce --only robustness`; {eps} episodes of seed "
            f"{res['config']['seed']} per "
            f"cell): with {T['links_p']:.0%} of messages lost VGAI costs {_ci(links)} (clean {_ci(clean)}; Local "
            f"unperturbed {local['relative_cost_mean']:.2f}), connected at 5 s in {links['share_connected_at_end']:.0%} "
            f"of episodes; the paper's DAGNN (dagnn_K4) {_ci(dl)}. With pixel noise sigma = {T['image_noise_sigma']:g} on the gray channel "
            f"VGAI costs {_ci(noisy)}, {noisy['relative_cost_mean'] / clean['relative_cost_mean']:.2f}x its clean cost. "
            f"The recipe through the camera, training seed 0 (notebook 08, section 6; "
            f"{cams['gray + depth'][1]['clean']['episodes']} validation episodes; gray + depth is the book's recipe): "
            + "; ".join(through(s) for s in ("gray + depth", "gray only")) + ".")


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

# %% [markdown]
# # 09 · Results at a glance, and what is still open
#
# *Paper: sections 4 and 5.*
#
# The book in one page: every controller it ships, on the test episodes (notebook 01: nothing was
# chosen on them), by the three questions the book asks of every controller (what does it cost
# relative to the expert, did the drones flock, were they as safe as the expert), with what it
# sends its neighbours and what it took to train. Then a fair comparison with the paper, in both
# directions, and the problems this reproduction leaves open. Every number is read from a record in
# `data/`; nothing is computed anew here.
#
# **Learning objectives.** After this notebook you can summarise what the book reproduced of the
# paper and how well, say what favours our numbers and what disfavours them, and name the open
# problems with the measurement behind each.

# %%
import json

from IPython.display import Markdown, display

from vgai_lite.book import DATA_DIR, TEST_SEED, prose
from vgai_lite.evaluate import FLOCKED_VARIANCE, as_safe_as_expert, flocked
from vgai_lite.lab.paper import PAPER
from vgai_lite.lab.reproduce import load_results
from vgai_lite.lab.findings import compare, flock_verdict, needs, noise_that_breaks, one_training, seed_spread
from vgai_lite.lab.runs import (CAMERA_SEED_RUNS, CLEAN_SEED_RUNS, LEAVE_ONE_OUT, DAGNN_RUNS, PAPER_SEEDS, VGAI_RUNS,
                                 chosen_camera_runs, how_trained, seed_records, training_minutes,
                                 TIMED_ALONE, TRAINING_TARGET_MINUTES)
from vgai_lite.vgai_config import PAPER as PAPER_T


def load(rel):
    return json.loads((DATA_DIR / rel).read_text())


# %% [markdown]
# ## 1. Every controller, on the test episodes
#
# "Bytes per step" is what a drone broadcasts to its neighbours at every step: $(K-1)\,F$ numbers of
# 4 bytes (notebook 07). Training minutes are as each training recorded on this 2-core machine, with
# how it ran: alone, or one of two trainings side by side at one thread each.

# %%
dagnn_t, vgai_t = DAGNN_RUNS["dagnn_K4"], VGAI_RUNS["vgai_F24"]
dagnn_rec, vgai_rec = load("dagnn/dagnn_K4.json"), load("vgai/vgai_F24.json")
gray_name = chosen_camera_runs()["gray only"]


def minutes(rec, fmt=".0f"):
    """A training's recorded minutes, with how it ran (threads; alone or sharing the two cores)."""
    how = how_trained(rec)
    return f"{training_minutes(rec):{fmt}}" + (f" ({how})" if how else "")


ROWS = [("Centralized expert", "everyone's positions and velocities", None, 1.0, "—", "—"),
        ("Local heuristic", "its neighbours' positions and velocities", "local", PAPER["R"]["Local"][1.5], "0", "—"),
        ("DAGNN, K-1 = 3", "exact local features, neighbours' messages", "dagnn_K4", PAPER["R"]["DAGNN"][1.5],
         f"{(dagnn_t.K - 1) * 6 * 4}", minutes(dagnn_rec, ".1f")),
        ("VGAI, F = 24, K-1 = 3 (the book's recipe, trained through a camera model)",
         "its own images, neighbours' messages", "vgai_F24",
         PAPER["R"]["VGAI"][1.5], f"{(vgai_t.K - 1) * vgai_t.F * 4}", minutes(vgai_rec)),
        ("VGAI, the same recipe trained on clean frames (training seed 0)", "the same", "vgai_clean", None,
         f"{(vgai_t.K - 1) * vgai_t.F * 4}", minutes(load("experiments/vgai_clean_seed0.json"))),
        ("VGAI on clean frames without the learner flying alone", "the same", "vgai_F24_mixture", None,
         f"{(vgai_t.K - 1) * vgai_t.F * 4}", "—"),
        ("Modular vision pilot (a state estimator trained alone, feeding the DAGNN's MLP)",
         "its own images, neighbours' messages", "pilot", None, f"{(dagnn_t.K - 1) * 6 * 4}", "—"),
        ("VGAI trained through the camera, gray only: the paper's cameras, without depth (two frames, as the book's recipe; notebook 08's choice)",
         "its own gray frames, neighbours' messages", gray_name, PAPER["R"]["VGAI"][1.5],
         f"{(vgai_t.K - 1) * vgai_t.F * 4}",
         minutes(load(f"experiments/{gray_name}.json"))),
        *[(f"The paper's VGAI as described (one intensity frame, no depth, from random weights), training seed {s}",
           "its own gray frames, neighbours' messages", f"vgai_paper_seed{s}", PAPER["R"]["VGAI"][1.5],
           f"{(PAPER_T.K - 1) * PAPER_T.F * 4}", minutes(load(f"experiments/vgai_paper_seed{s}.json")))
          for s in PAPER_SEEDS]]
test = {name: load(f"test/{name}.json") for _, _, name, *_ in ROWS if name}
rows = []
for label, sees, name, paper, nbytes, minutes in ROWS:
    if name is None:
        rows.append(f"| {label} | {sees} | 1.00 | {paper:.2f} | — | — | {nbytes} | {minutes} |")
        continue
    rec = test[name]
    lo, hi = rec["relative_cost_mean_ci95"]
    rows.append(f"| {label} | {sees} | **{rec['relative_cost_mean']:.2f}** ({lo:.2f}-{hi:.2f}) | "
                f"{'—' if paper is None else f'{paper:.2f}'} | {'yes' if flocked(rec) else 'no'} "
                f"({rec['velocity_variance_median']['5s']:.1e}, {rec['share_connected_at_end']:.0%}) | "
                f"{'yes' if as_safe_as_expert(rec) else 'no'} | {nbytes} | {minutes} |")
first = test["vgai_F24"]
display(Markdown(f"{first['episodes']} test episodes (seed {first['seed']}), N = 50, R = 1.5 m, v_init = 3 m/s:\n\n"
                 "| controller | sees | relative cost (95% CI) | paper | flocked (variance at 5 s [m²/s²], connected) "
                 "| as safe as the expert | "
                 "bytes per step | training [min] |\n|---|---|---|---|---|---|---|---|\n" + "\n".join(rows)))

# %%
v, d, l, pil = (test[n] for n in ("vgai_F24", "dagnn_K4", "local", "pilot"))
# one rule: each single training's interval also holds the spread between training seeds of its kind (notebook 07):
# the recipe's four trainings for VGAI and the pipeline, the DAGNN's three at the defaults
SEED_STD = seed_spread(seed_records())
dagnn_std = load_results()["tables"]["N"]["rows"]["DAGNN"]["50"]["seed_std"]
v, d, pil = one_training(v, SEED_STD), one_training(d, dagnn_std), one_training(pil, SEED_STD)
order = {-1: "below", 1: "above", 0: "within the intervals of"}
paper_costs = [test[f"vgai_paper_seed{s}"]["relative_cost_mean"] for s in PAPER_SEEDS]
display(prose("On these episodes, each training's interval widened by the spread between its training seeds (VGAI "
      "{sv:.2f}, the DAGNN {sd:.2f}), the DAGNN is {dv} VGAI and VGAI is {vl} the local heuristic (the paper: DAGNN < VGAI < Local), "
      "at lower costs than the paper's: VGAI {vc:.2f} against the paper's {vp:.2f}, the DAGNN {dc:.2f} against {dp:.2f}. "
      "{flock} The paper's VGAI as the paper describes it, trained at the book's budget, costs {plo:.2f} to {phi:.2f} "
      "over {pn} training seeds and flocks in {pfl} of them (variance at 5 s {pv} m²/s²; notebook 11 sets it beside a "
      "swarm that does nothing), so "
      "the book's VGAI is the paper's method with the book's departures, not the paper's VGAI reproduced.",
      pn=len(PAPER_SEEDS), pfl=sum(flocked(test[f"vgai_paper_seed{s}"]) for s in PAPER_SEEDS), sv=SEED_STD, sd=dagnn_std,
      pv=", ".join(f"{test[f'vgai_paper_seed{s}']['velocity_variance_median']['5s']:.1e}" for s in PAPER_SEEDS),
      dv=order[compare(d, v)], vl=order[compare(v, l)],
      vc=v["relative_cost_mean"], vp=PAPER["R"]["VGAI"][1.5], dc=d["relative_cost_mean"], dp=PAPER["R"]["DAGNN"][1.5],
      plo=min(paper_costs), phi=max(paper_costs),
      flock=("The book's VGAI (training seed {s}), which sees only its own camera images (gray and depth) and talks to "
             "its neighbours, flocks: at 5 s its drones' velocities differ by {rms:.3f} m/s RMS (variance {var:.1e} "
             "m²/s²); its recipe flocks in {k} of its {n} trainings (notebook 11)."
             .format(rms=v["velocity_variance_median"]["5s"] ** 0.5, var=v["velocity_variance_median"]["5s"],
                     s=vgai_t.seed, k=sum(map(flocked, seed_records())), n=len(seed_records()))
             if flocked(v) else "But the book's VGAI does not flock by the book's definition.")))
display(prose("The paper trains the CNN and the GNN together, end to end; it never compares them with a pipeline of parts "
              "trained apart. The book does: the modular vision pilot is that pipeline, the same kind of CNN trained alone to estimate the six "
              "local features, feeding the DAGNN's network. It costs {pc:.2f} ({plo:.2f}-{phi:.2f}) and {pfl} (variance "
              "at 5 s {pv:.1e} m²/s²); VGAI, trained end to end, costs {vc:.2f} (variance at 5 s {vv:.1e}) and is {order} it "
              "(each one training, judged with the recipe's seed spread): {verdict}. {tighter}",
              vv=v["velocity_variance_median"]["5s"],
              tighter=("Both swarms flock (the variance a label, not a ranking: a median over episodes, without an "
                       "interval), so on the flock itself the two cannot be told apart." if flocked(pil) and flocked(v) else
                       "Only the pipeline's swarm flocks." if flocked(pil) else "Only VGAI's swarm flocks." if flocked(v)
                       else "Neither swarm flocks."),
              pc=pil["relative_cost_mean"], plo=pil["relative_cost_mean_ci95"][0], phi=pil["relative_cost_mean_ci95"][1],
              pfl="flocks" if flocked(pil) else "does not flock", pv=pil["velocity_variance_median"]["5s"],
              vc=v["relative_cost_mean"], order=order[compare(v, pil)],
              verdict={-1: "here joint training beats the pipeline on cost",
                       0: "the book cannot tell the two apart on cost",
                       1: "here the pipeline beats joint training on cost"}[compare(v, pil)]))

# %% [markdown]
# ## 2. The paper's criterion for flocking does not hold here
#
# The paper states that "relative velocity variations less than 3 would in general achieve
# successful flocking of a team" (section 4). The book judges flocking directly instead (notebook 01:
# the velocity variance at 5 s and the swarm connected). Every record and table cell the book has
# with both figures that costs less than 3 and still does not flock:

# %%
candidates = [(f"test episodes: {n}", r) for n, r in test.items()]
candidates += [(f"record: dagnn/{p.stem}", json.loads(p.read_text())) for p in sorted((DATA_DIR / "dagnn").glob("dagnn_K*.json"))]
results = load_results()
tables_seed = results["provenance"]["reproduce_config"]["seed"]
assert tables_seed == TEST_SEED, (f"the tables' cells are on seed {tables_seed}, not the test episodes: "
                                  "`python -m vgai_lite reproduce` recomputes them")
for table, t in results["tables"].items():
    for row, cells in t["rows"].items():
        for col, c in cells.items():
            if "velocity_variance_median" in c:
                candidates.append((f"Table {t['title'].split(':')[0].replace('Table ', '')}: {row}, {t['column']} = {col}", c))
counter = []
for label, rec in candidates:
    var = rec.get("velocity_variance_median", {})
    if rec.get("relative_cost_mean", 99) < 3 and "5s" in var and "share_connected_at_end" in rec:
        one_vgai = ("vgai" in label.lower() or "VGAI" in label) and len(rec.get("per_seed") or []) < 2
        if (flock_verdict(rec, seed_records()) == 1) if one_vgai else not flocked(rec):  # one VGAI training: beyond the seeds
            counter.append(f"| {label} | {rec['relative_cost_mean']:.2f} | {var['5s']:.1e} | {rec['share_connected_at_end']:.0%} |")
display(Markdown("| where | relative cost | variance at 5 s [m²/s²] | connected at 5 s |\n|---|---|---|---|\n"
                 + "\n".join(counter) + "\n\nA single VGAI training is listed only beyond the spread of the recipe's "
                 "seeds (`findings.flock_verdict`); the DAGNN records and cells by the book's definition alone (the "
                 f"spread of their seeds' variances is not measured). Test records: {test['vgai_F24']['episodes']} episodes of seed "
                 f"{test['vgai_F24']['seed']}; dagnn records: the working episodes (seed 2020, notebook 01)."))
prose("{verdict}", verdict=(f"{len(counter)} controllers or cells cost less than 3 and do not flock: a relative cost "
                            "below 3 does not mean a flock, because eq. 1 is spent in the first second, while the "
                            "drones brake hard, and says little about whether they end up moving as one."
                            if counter else "Every controller that costs less than 3 flocks here: the criterion holds in our data."))

# %% [markdown]
# ## 3. A fair comparison with the paper
#
# **What favours our numbers.**
#
# * **Depth.** Our drones see a gray channel *and* a depth channel; the paper's cameras give images
#   only. What the recipe does without depth is measured below (and in notebook 11's leave-one-out).
# * **Two frames.** Our CNN sees each frame beside its difference with the frame 5 steps earlier;
#   the paper's takes one frame, which shows where the neighbours are but not how they move
#   (notebook 05, section 3). The paper's VGAI with its one frame is measured in notebook 11, and the
#   book's recipe with one frame below.
# * **Noiseless renders in the tables.** The book's VGAI is trained through a camera model (sensor
#   noise, blur, exposure, a dead camera; notebook 08), but the tables of notebook 07 fly the VGAIs on
#   clean frames (the paper does not say whether its renders were perturbed); notebook 08 flies them
#   through the perturbations of the authors' released test script.
# * **Supervision on the exact features.** Stages 1 and 3 of the book's training regress the six
#   exact local features (the state-estimation loss); the paper trains on the actions alone (eq. 10).
# * **A noiseless simulator that is the expert's model.** Our drones are the paper's stated double
#   integrators, with exact relative positions and no latency; the paper's fly in AirSim with their
#   own dynamics between command and motion. Imitation is easier when the expert's model is the world.
# * **The potential's radius $\rho$ is a calibration.** The paper gives no $\rho$; the book chose it
#   so that the local heuristic lands near the paper's 4.13 (notebook 01), so that agreement is by
#   construction, not a finding. (The initial disc follows the authors' code, notebook 01.)
#
# **What disfavours them.** Our images are 12 × 128 pixels from four cameras, the CNN is sized to
# train on two CPU cores (section 1 gives each training's minutes), and each VGAI cell of the
# tables is one training (the DAGNN rows average three training seeds).

# %%
gray, seed0 = load("experiments/vgai_learner_gray.json"), load(f"experiments/{CLEAN_SEED_RUNS[0]}.json")
gray_cam, depth_cam = load(f"experiments/{gray_name}.json"), load(f"experiments/{CAMERA_SEED_RUNS[0]}.json")
yn = lambda rec: "yes" if flocked(rec) else "no"
assert len({r["episodes"] for r in (gray, seed0, gray_cam, depth_cam)}) == 1, "the four records fly as many episodes"
display(prose("The depth channel, measured ({ep} validation episodes each, training seed 0): trained on clean frames, with gray "
      "and depth the recipe costs {dc:.2f} and ends at {d5:.1e} m²/s² at 5 s (flocked: {df}), with the gray channel only "
      "{gc:.2f} and {g5:.1e} (flocked: {gf}); trained through the camera, with gray and depth {dcc:.2f} and {dc5:.1e} "
      "(flocked: {dcf}), with gray only {gcc:.2f} and {gc5:.1e} (flocked: {gcf}).", ep=depth_cam["episodes"], d5=seed0["velocity_variance_median"]["5s"], df=yn(seed0),
      g5=gray["velocity_variance_median"]["5s"], gf=yn(gray), gc=gray["relative_cost_mean"], dc=seed0["relative_cost_mean"],
      dc5=depth_cam["velocity_variance_median"]["5s"], dcf=yn(depth_cam), gc5=gray_cam["velocity_variance_median"]["5s"],
      gcf=yn(gray_cam), gcc=gray_cam["relative_cost_mean"], dcc=depth_cam["relative_cost_mean"]))
one = load(f"experiments/{LEAVE_ONE_OUT['the second frame'][0]}.json")
display(prose("The second frame, measured the same way: with one frame per step (no motion channel) the book's recipe "
              "ends at {o5:.1e} m²/s² at 5 s (flocked: {of}), at a cost of {oc:.2f}.", o5=one["velocity_variance_median"]["5s"],
              of="yes" if flocked(one) else "no", oc=one["relative_cost_mean"]))
display(prose("What VGAI's flocking needs, by notebook 11's leave-one-out (the book's recipe without one departure "
              "at a time, one training each from seed 0, validation episodes, clean frames): {s} Through a camera's noise the camera model is needed too: trained without "
              "it, the recipe no longer flocks at σ = {b:g} (notebook 08).", s=needs(
    {d: load(f"experiments/{name}.json") for d, (name, _) in LEAVE_ONE_OUT.items()}, seed_records()),
    b=noise_that_breaks(load(f"experiments/{CLEAN_SEED_RUNS[0]}_cameras.json")["settings"])))

# %% [markdown]
# ## 4. What is still open
#
# Each item with the measurement behind it.

# %%
choice = load("vgai/seeds/choice.json")
seed_minutes = [training_minutes(load(f"vgai/seeds/{n}.json")) for n in choice["candidates"]]
alone = load(f"experiments/{TIMED_ALONE}.json")
n_cols = results["tables"]["N"]["columns"]
n_vgai = {c: results["tables"]["N"]["rows"]["VGAI"][str(c)] for c in n_cols}
apart = [c for c in n_cols if not flocked(n_vgai[c])]
unsafe = [c for c in n_cols if not as_safe_as_expert(n_vgai[c])]
verdict_at = lambda k: ", ".join(f"{c:g}" for c in n_cols if flock_verdict(n_vgai[c], seed_records()) == k) or "none"
from vgai_lite.lab import robustness

rob = robustness.load()
rob_current = robustness.find(rob, "VGAI").get("checkpoint") == robustness.checkpoint_id(robustness.CONTROLLERS["VGAI"])
assert rob_current, "the robustness sweep flew another VGAI: `python -m vgai_lite reproduce --only robustness`"
noisy = robustness.find(rob, "VGAI", (("image_noise", robustness.TARGETS["image_noise_sigma"]),))
cams = {sensor: load(f"experiments/{name}_cameras.json")["settings"] for sensor, name in chosen_camera_runs().items()}
authors = f"noise{10 / 255:.4g}"
cams_seed1 = load(f"experiments/{chosen_camera_runs()['gray only']}_seed1_cameras.json")["settings"]
clean_cams = load(f"experiments/{CLEAN_SEED_RUNS[0]}_cameras.json")["settings"]
clean_breaks = noise_that_breaks(clean_cams)
expert_200 = load("experiments/expert_stability.json")["teams"]["200"]
does = lambda rec: "does" if flocked(rec) else "does not"
pn_n, dg_n = ({c: results["tables"]["N"]["rows"][row][f"{c:g}"] for c in n_cols} for row in ("DAGNN (per neighbour)", "DAGNN"))
pn_r1 = results["tables"]["R"]["rows"]["DAGNN (per neighbour)"]["1.0"]
stage1 = load("experiments/stage1_capacity.json")["recipes"].values()  # notebook 08: each CNN at the end of stage 1
gray_rec_vision = load(f"experiments/{gray_name}.json")["train_config"]["vision"]  # the recipe as trained (the depth one alike)
trained_as = lambda x: x["motion_gap"] == gray_rec_vision["motion_gap"] and x["view_width"] == gray_rec_vision["render"]["view_width"]
s1_gray, s1_depth = (next(x for x in stage1 if x["record"] == chosen_camera_runs()[k] and trained_as(x))
                     for k in ("gray only", "gray + depth"))
late_read = lambda x: x["correlation"][str(max(map(int, x["correlation"])))]  # the latest step read
s1_pos = lambda x: sum(late_read(x)[2:4]) / 2  # the r/r^4 sums, mean of x and y
s1_vel = lambda x: sum(late_read(x)[:2]) / 2  # the velocity sums
s1_stack = load("experiments/stage1_stack.json")["recipes"].values()  # the same stage 1, each frame read alone
swaps = {name: x["5s"]["velocity_variance_median"] for name, x in load("experiments/modular_velocity_gain.json")["swaps"].items()}
swap_var = lambda dist: next(x for name, x in swaps.items() if name.startswith(f"distances: {dist};"))
swap_word = lambda dist: "flocks" if swap_var(dist) <= FLOCKED_VARIANCE else "does not flock"
does_mod = lambda x: "does" if x["modular_pilot"]["5s"]["velocity_variance_median"] <= FLOCKED_VARIANCE else "does not"
s1_noise = {x["stage1_file"]: x for name in ("stage1_noise", "stage1_noise_floor")  # notebook 08: stage 1 through less noise
            for x in load(f"experiments/{name}.json")["recipes"].values() if x["motion_gap"] == gray_rec_vision["motion_gap"]}
s1_quiet = [x for x in s1_noise.values() if x["camera_noise"][1] == 0]
s1_depth_noise = load(f"experiments/{chosen_camera_runs()['gray + depth']}.json")["train_config"]["camera"]["noise"][1]
quiet = load("experiments/vgai_camera_quiet_gray.json")  # the gray recipe trained through noise up to 0.005
quiet_joint = next(x for x in load("experiments/stage1_noise_joint.json")["recipes"].values() if "checkpoint_sha256" in x)
quiet_limit = load("experiments/consensus_limit_quiet.json")["controllers"]["vgai_camera_quiet_gray"]["5s"]
q_local, q_dagnn = load("experiments/vgai_camera_quiet_local.json"), load("experiments/vgai_camera_quiet_dagnn.json")
q_fixed = load("experiments/vgai_camera_quiet_fixed_mlp.json")
q_fixed_limit = load("experiments/consensus_limit_fixed_mlp.json")["controllers"]["vgai_camera_quiet_fixed_mlp"]["5s"]
q_fixed_run = load("experiments/vgai_camera_quiet_fixed_mlp_test_cameras.json")["settings"]  # reported on the test episodes
q_fixed_test, q_fixed_noisy = q_fixed_run["clean"], next(x for k, x in q_fixed_run.items() if k != "clean")
q_local_limit, q_dagnn_limit = (load("experiments/consensus_limit_readout.json")["controllers"][k]["5s"]
                                for k in ("vgai_camera_quiet_local", "vgai_camera_quiet_dagnn"))
quiet_mod_run = load("experiments/vgai_camera_quiet_gray_test_modular.json")["settings"]  # reported on the test episodes
quiet_mod, quiet_mod_noisy = quiet_mod_run["clean"], next(x for k, x in quiet_mod_run.items() if k != "clean")
quiet_through = {float(s): r["5s"]["velocity_variance_median"] for x in s1_quiet for s, r in x["modular_pilot_noise"].items()}
quiet_ok = max([s for s, var in quiet_through.items() if var <= FLOCKED_VARIANCE], default=0.0)
quiet_bad = min(s for s, var in quiet_through.items() if var > FLOCKED_VARIANCE)
noise_sentence = (("flocks" if does_mod(s1_quiet[0]) == "does" else "does not flock") + " as a modular pilot on clean frames"
                  + f" (variance at 5 s "
                  f"{s1_quiet[0]['modular_pilot']['5s']['velocity_variance_median']:.1e} m²/s²; the depth camera's, trained "
                  f"through noise up to {s1_depth_noise:g}: {s1_depth['modular_pilot']['5s']['velocity_variance_median']:.1e}), "
                  + (f"through pixel noise of σ = {quiet_ok:g} too, " if quiet_ok > 0 else "")
                  + f"not through σ = {quiet_bad:g} ({quiet_through[quiet_bad]:.1e}), {10 / 255 / quiet_bad:.0f} times less than the "
                  "authors' 10/255; trained through noise drawn up to " + " or ".join(
                      f"{x['camera_noise'][1]:g}" for x in s1_noise.values() if x["camera_noise"][1] > 0
                      and x["modular_pilot"]["5s"]["velocity_variance_median"] > FLOCKED_VARIANCE)
                  + " it reads too little of the motion to flock even on clean frames")
items = [
    "* **Vision without depth.** The book's VGAI flocks with a depth channel the paper's cameras do not give; with "
    f"the gray channel only, trained on clean frames, it {does(gray)} (variance at 5 s "
    f"{gray['velocity_variance_median']['5s']:.1e} m²/s²), and trained through the camera it "
    f"{does(cams['gray only']['clean'])} ({cams['gray only']['clean']['episodes']} validation episodes, clean frames: "
    f"{cams['gray only']['clean']['relative_cost_mean']:.2f}, variance at 5 s "
    f"{cams['gray only']['clean']['velocity_variance_median']['5s']:.1e} m²/s², connected in "
    f"{cams['gray only']['clean']['share_connected_at_end']:.0%}; trained from a second seed, "
    f"{cams_seed1['clean']['relative_cost_mean']:.2f}, variance {cams_seed1['clean']['velocity_variance_median']['5s']:.1e}, "
    f"connected in {cams_seed1['clean']['share_connected_at_end']:.0%}). What it lacks, measured (notebook 08, section 6; "
    "`data/experiments/stage1_capacity.json`): at the end of stage 1 the gray CNN reads its neighbours' r/r⁴ sums with "
    f"{s1_pos(s1_gray):.3f} against the depth camera's {s1_pos(s1_depth):.3f}, their velocity sums with {s1_vel(s1_gray):.3f} "
    f"against {s1_vel(s1_depth):.3f}; flown with the DAGNN's own MLP, the gray reading {does_mod(s1_gray)} flock (variance at "
    f"5 s {s1_gray['modular_pilot']['5s']['velocity_variance_median']:.1e} m²/s²), the depth camera's {does_mod(s1_depth)} "
    f"({s1_depth['modular_pilot']['5s']['velocity_variance_median']:.1e}). With each frame read alone and the velocity "
    "estimates taken from the change of the CNN's features between the frames (`OddMotionCNN`'s 'stack' pairing, s its gain; "
    "`stage1_stack.json`), the gray stage 1 reads the velocity sums with " + ", ".join(
        f"{s1_vel(x):.3f} (s = {x['motion_scale']:g})" for x in s1_stack) + f" against {s1_vel(s1_gray):.3f} from the motion "
    "channel, and its modular pilot " + ("does not flock" if all(
        x["modular_pilot"]["5s"]["velocity_variance_median"] > FLOCKED_VARIANCE for x in s1_stack) else "flocks at some s")
    + " (variance at 5 s " + ", ".join(f"{x['modular_pilot']['5s']['velocity_variance_median']:.1e}" for x in s1_stack)
    + " m²/s²). With the readings swapped between the two stage 1s (`modular_velocity_gain.json`), a pilot with the gray "
    f"distances and the depth camera's velocity estimates {swap_word('gray')} (variance {swap_var('gray'):.1e}), one with the "
    f"depth camera's distances and the gray velocity estimates {swap_word('gray + depth')} ({swap_var('gray + depth'):.1e})"
    + (": what the gray camera lacks is its reading of the neighbours' motion. " if swap_word("gray") == "flocks" and
       swap_word("gray + depth") != "flocks" else ". ")
    + f"Trained without sensor noise, its stage 1 {noise_sentence} (`stage1_noise.json`, `stage1_noise_floor.json`). "
    f"The whole recipe trained through noise drawn up to {quiet['train_config']['camera']['noise'][1]:g} "
    f"(`vgai_camera_quiet_gray`) {does(quiet)} flock on clean frames ({quiet['episodes']} validation "
    f"episodes: {quiet['relative_cost_mean']:.2f}, variance at 5 s {quiet['velocity_variance_median']['5s']:.1e} m²/s²), "
    f"though its CNN after the joint training, flown as a modular pilot, {('flocks' if does_mod(quiet_joint) == 'does' else 'does not')} "
    f"({quiet_joint['modular_pilot']['5s']['velocity_variance_median']:.1e}; `stage1_noise_joint.json`): the VGAI itself brakes with "
    f"γ = {quiet_limit['damping_gain_median']:.0f} /s and is pushed at rest with f = {quiet_limit['forcing_at_rest_rms_median']:.2f} "
    "m/s² (`consensus_limit_quiet.json`; notebook 08 sets these beside the depth camera's VGAI). That CNN with the DAGNN's "
    f"MLP, a camera-only controller though not trained end to end, {'flocks' if quiet_mod['flocked'] else 'does not flock'} "
    f"on clean frames of the {quiet_mod['episodes']} test episodes ({quiet_mod['relative_cost_mean']:.2f}, variance at 5 s "
    f"{quiet_mod['velocity_variance_median']['5s']:.1e} m²/s², {'as safe as' if quiet_mod['safe'] else 'less safe than'} the "
    f"expert; `vgai_camera_quiet_gray_test_modular.json`) and {'flocks' if quiet_mod_noisy['flocked'] else 'does not'} through "
    f"10/255 ({quiet_mod_noisy['relative_cost_mean']:.2f}, variance {quiet_mod_noisy['velocity_variance_median']['5s']:.1e}). "
    + f"With its MLP reading the CNN's estimate of the six local features instead of its {quiet['train_config']['F']} features "
    f"(`vgai_camera_quiet_local`) the VGAI {does(q_local)} flock ({q_local['episodes']} validation episodes: relative cost "
    f"{q_local['relative_cost_mean']:.2f}, variance at 5 s "
    f"{q_local['velocity_variance_median']['5s']:.1e} m²/s², γ = {q_local_limit['damping_gain_median']:.0f} /s, f = "
    f"{q_local_limit['forcing_at_rest_rms_median']:.2f} m/s²); started as the DAGNN's MLP (`vgai_camera_quiet_dagnn`) it "
    f"{does(q_dagnn)} flock ({q_dagnn['relative_cost_mean']:.2f}, {q_dagnn['velocity_variance_median']['5s']:.1e}, f = "
    f"{q_dagnn_limit['forcing_at_rest_rms_median']:.2f} m/s²; `consensus_limit_readout.json`, notebook 08)"
    + (f", its MLP having learned in the joint training a push at rest (f = {q_dagnn_limit['forcing_at_rest_rms_median']:.2f} "
       f"against {q_fixed_limit['forcing_at_rest_rms_median']:.2f} m/s² with the DAGNN's MLP kept)" if not flocked(q_dagnn)
       and q_dagnn_limit["forcing_at_rest_rms_median"] > q_fixed_limit["forcing_at_rest_rms_median"] else "")
    + "; with the DAGNN's MLP kept through stage 3 and "
    f"only the CNN learning end to end (`vgai_camera_quiet_fixed_mlp`) it {does(q_fixed)} flock ({q_fixed['relative_cost_mean']:.2f}, "
    f"{q_fixed['velocity_variance_median']['5s']:.1e} m²/s², connected in {q_fixed['share_connected_at_end']:.0%} of the validation "
    f"episodes); reported on the {q_fixed_test['episodes']} test episodes it {'flocks' if q_fixed_test['flocked'] else 'does not flock'} "
    f"on clean frames ({q_fixed_test['relative_cost_mean']:.2f}, {q_fixed_test['velocity_variance_median']['5s']:.1e} m²/s², "
    f"{'as safe as' if q_fixed_test['safe'] else 'less safe than'} the expert) and {'flocks' if q_fixed_noisy['flocked'] else 'does not'} "
    f"through 10/255 ({q_fixed_noisy['relative_cost_mean']:.2f}, {q_fixed_noisy['velocity_variance_median']['5s']:.1e}; "
    "`vgai_camera_quiet_fixed_mlp_test_cameras.json`): its MLP, though, is the DAGNN's, not learned from the images. "
    "A camera-only VGAI whose MLP too is learned end to end and that flocks, on clean frames or at the authors' noise, is an "
    "open problem.",
    "* **Larger teams.** Trained on 50 drones (one training, judged against the spread of the recipe's own seeds at "
    "N = 50, `findings.flock_verdict`), VGAI flocks when flown by N' = " + verdict_at(-1) + "; it does not by N' = "
    + verdict_at(1) + " (variance at 5 s " + ", ".join(f"{n_vgai[c]['velocity_variance_median']['5s']:.1e} m²/s² at N' = {c:g}"
                                                     for c in n_cols if flock_verdict(n_vgai[c], seed_records()) == 1)
    + "), and N' = " + verdict_at(0) + " lie within the seeds' spread; it is " + ("as safe as the expert at every N'" if not unsafe else
                               "not as safe as the expert at N' = " + ", ".join(
                                   f"{c:g} ({n_vgai[c]['share_below_0.05m']:.0%} of episodes < 0.05 m, expert "
                                   f"{n_vgai[c]['expert_share_below_0.05m']:.0%}; median closest approach "
                                   f"{n_vgai[c]['median_min_distance'] / n_vgai[c]['expert_median_min_distance']:.2f}× "
                                   "the expert's)" for c in unsafe))
    + " (Table 3, notebook 07). More drones crowd each panorama, and no training saw more than 50. "
    f"At N' = 200 the teacher itself does not flock: the expert of eq. 2, sampled at Ts = {expert_200['Ts']:g} s, "
    f"multiplies each velocity deviation by 1 − N Ts = {expert_200['predicted_factor']:+.0f} per step, and its variance "
    f"at 5 s is {expert_200['expert']['velocity_variance_median']['5s']:.1e} m²/s² "
    f"(`data/experiments/expert_stability.json`, notebook 03). The DAGNN with each of the local features' sums divided by the "
    "drone's number of neighbours (the row *DAGNN (per neighbour)* of Tables 2b and 3, trained on 50 drones only (three training seeds) at "
    "R = 1.5 m) flocks at N' = " + (", ".join(f"{c:g}" for c in n_cols if flocked(pn_n[c])) or "none")
    + f" (variance at 5 s at N' = {n_cols[-1]:g}: {pn_n[n_cols[-1]]['velocity_variance_median']['5s']:.1e} m²/s², the "
    f"paper's DAGNN {dg_n[n_cols[-1]]['velocity_variance_median']['5s']:.1e}); at R = 1 m its swarm is connected at 5 s "
    f"in {pn_r1['share_connected_at_end']:.0%} of episodes (variance {pn_r1['velocity_variance_median']['5s']:.1e} m²/s²).",
    f"* **Noisy cameras.** With pixel noise of sigma {robustness.TARGETS['image_noise_sigma']:g} the book's VGAI, "
    f"trained through the camera, costs {noisy['relative_cost_mean']:.2f} on the test episodes and {does(noisy)} flock by "
    f"the book's definition (variance at 5 s {noisy['velocity_variance_median']['5s']:.1e} m²/s²; notebook 08; one training: "
    + {-1: "tighter than every seed of the recipe", 0: "within the spread of the recipe's seeds",
       1: "beyond every seed of the recipe"}[flock_verdict(noisy, seed_records())] + f"). Trained on clean frames, the "
    f"same recipe no longer flocks at sigma = {clean_breaks:g}. Through the camera, training seed 0 costs "
    f"{cams['gray + depth']['clean']['relative_cost_mean']:.2f} on clean frames and "
    f"{cams['gray + depth'][authors]['relative_cost_mean']:.2f} at the authors' noise of 10/255, the gray-only VGAI "
    f"{cams['gray only']['clean']['relative_cost_mean']:.2f} and {cams['gray only'][authors]['relative_cost_mean']:.2f} "
    f"({cams['gray only']['clean']['episodes']} validation episodes; variance at 5 s " + ", ".join(
        f"{c[k]['velocity_variance_median']['5s']:.1e}" for c in cams.values() for k in ("clean", authors))
    + " m²/s² in that order). "
    + ("At 10/255 the noise costs each of them at most a quarter of its clean cost"
       if all(c[authors]["relative_cost_mean"] <= 1.25 * c["clean"]["relative_cost_mean"] for c in cams.values())
       else "The noise still costs them more than a quarter of their clean cost")
    + (". With depth, then, the camera's noise is no longer what stops the flock" if all(
        flocked(cams["gray + depth"][k]) for k in ("clean", authors)) else "; with depth, flocking through the camera's noise is still open")
    + ("; without depth it is the sensor, not the noise: the gray-only VGAI does not flock on clean frames either."
       if not flocked(cams["gray only"]["clean"]) else "."),
    f"* **Training time.** Timed on the two cores (training seed {alone['train_config']['seed']}, "
    f"{how_trained(alone)}), the book's recipe takes {training_minutes(alone):.0f} minutes, "
    + (f"{TRAINING_TARGET_MINUTES - training_minutes(alone):.0f} under" if training_minutes(alone) <= TRAINING_TARGET_MINUTES
       else f"{training_minutes(alone) - TRAINING_TARGET_MINUTES:.0f} over")
    + f" the {TRAINING_TARGET_MINUTES} minutes a training may take (notebook 06 says where they go); that training "
    f"{does(alone)} flock on the validation episodes (variance at 5 s {alone['velocity_variance_median']['5s']:.1e} m²/s²), "
    f"and over its {len(CAMERA_SEED_RUNS)} training seeds the recipe flocks in "
    f"{sum(flocked(load(f'experiments/{n}.json')) for n in CAMERA_SEED_RUNS)} (variance at 5 s "
    + ", ".join(f"{load(f'experiments/{n}.json')['velocity_variance_median']['5s']:.1e}" for n in CAMERA_SEED_RUNS)
    + " m²/s²; notebook 11). "
    f"The seeds the book chose from took {min(seed_minutes):.0f} to {max(seed_minutes):.0f} minutes each ("
    + "; ".join(sorted({how_trained(load(f"vgai/seeds/{n}.json")) for n in choice["candidates"]}))
    + ")"
    + ("; the two VGAIs of Table 2b's extra row, trained at two threads by `reproduce --extras --threads 2`, took "
       + " and ".join(f"{load(f'results/cells/{key}.json')['train_seconds_recorded'] / 60:.0f}"
                      for key in (results["tables"]["R"]["rows"]["VGAI (retrained)"][c]["cells"][0] for c in ("1.0", "2.0")))
       + " minutes" if results["tables"]["R"]["rows"].get("VGAI (retrained)") else
       "; the VGAIs of Table 2b's extra row (retrained at R = 1.0 and 2.0 m) are not in this run "
       "(`reproduce --extras` trains them with this recipe)")
    + ". So each VGAI cell of the tables is one training, judged with the spread between the recipe's training seeds "
    "at the defaults (notebook 07); the spread of the other configurations is not measured (the DAGNN rows average "
    "their three training seeds).",
    "* **The paper's simulator.** AirSim's dynamics and cameras are not reproduced; the findings, not the numbers, "
    "are what should carry over.",
]
display(Markdown("\n".join(items)))

# %% [markdown]
# ## References
#
# * Hu, Gama, Chen, Wang, Ribeiro, Sadler. *VGAI: End-to-End Learning of Vision-Based Decentralized Controllers for Robot Swarms.* ICASSP 2021 ([arXiv:2002.02308](https://arxiv.org/abs/2002.02308); the arXiv text, set in the CoRL 2020 template): sections 4 and 5.

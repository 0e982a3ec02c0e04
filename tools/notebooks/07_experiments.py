# %% [markdown]
# # 07 · Experiments: the paper's tables, regenerated
#
# *Paper: section 4, Tables 1-3.*
#
# The paper reports five small tables of **relative cost** (the flocking cost of eq. 1 over the
# centralized expert's, on the same initial conditions; the expert is 1.00). This notebook shows
# each of them with the paper's numbers beside ours, plots them, checks the paper's qualitative
# findings against our numbers, and adds what the paper discusses but never tabulates: how close
# the drones came to each other, and how many bytes each drone sends per step.
#
# Every number below is read from `data/results/results.json`, written by one command:
#
# ```bash
# python -m vgai_lite reproduce                 # every table (trains what is missing, then evaluates)
# python -m vgai_lite reproduce --only K R      # some tables
# python -m vgai_lite reproduce --quick --out /tmp/q   # every table in miniature, about a minute
# ```
#
# The command reuses trained checkpoints whose configuration matches (the book's shipped DAGNNs
# and VGAIs), evaluates every controller of a column on the same held-out initial conditions, and
# stores each cell as soon as it is computed, so an interrupted run resumes where it stopped. This
# notebook does **not** retrain anything; set `RERUN = True` below to run the command from here.
#
# **Learning objectives.** After this notebook you can regenerate the paper's tables with one
# command, read a relative cost with its spread, and say which of the paper's findings our
# simulator confirms, which it does not, and why.

# %%
import subprocess
import sys

import matplotlib.pyplot as plt
import torch
from IPython.display import Markdown, display

from vgai_lite import ExpertController, FlockConfig, LocalController, relative_cost, rollout, sample_initial_state
from vgai_lite.book import EVAL_SEED, ROOT, pick
from vgai_lite.graphs import adjacency
from vgai_lite.reproduce import PAPER, TABLES, load_results

RERUN = False  # True: run `python -m vgai_lite reproduce` first (reuses what is computed; see above)
if RERUN:
    done = subprocess.run([sys.executable, "-m", "vgai_lite", "reproduce"], capture_output=True, text=True, cwd=ROOT)
    print(done.stdout[-3000:] if done.returncode == 0 else done.stderr[-3000:])

results = load_results()  # the committed full run: data/results/results.json
prov = results["provenance"]
cs = prov["compute_seconds"]
print(f"results assembled {prov['started']} at commit {(prov['git_commit'] or '?')[:10]}: {cs['cells']} cells, "
      f"{cs['cells_computed_now']} computed by that invocation, the others read back from data/results/cells/")
print(f"evaluation time summed over the cells when they were computed: {cs['evaluation'] / 60:.0f} min; "
      f"training time recorded in the checkpoints used: {cs['training_recorded'] / 60:.0f} min "
      "(wall times on a shared machine, see the note below)")
print("settings:", prov["reproduce_config"])

# %% [markdown]
# ## How the experiments are set up, and where the paper is silent
#
# * **Time.** The committed cells were computed by several invocations of the command on this
#   2-core machine while VGAI trainings ran beside them (up to five processes), so the summed times
#   printed above overstate what a run alone costs: alone, one VGAI evaluation episode takes about
#   0.8 s and a default VGAI training is projected at about 20 minutes
#   (`python -m vgai_lite benchmark --vgai`).
# * **Same episodes for everyone.** Every cell of a column is flown from the same held-out initial
#   conditions (seed 2020, never used in training); the relative cost of a cell is the mean of its
#   costs over the mean of the expert's on those episodes, with a 95% bootstrap interval.
# * **Episodes per cell**: 30 for $N' \le 75$ and 10 for $N' \ge 100$, where every VGAI drone renders
#   and processes a view of all the others at every step (the shipped default VGAI was also
#   evaluated on 50 episodes in notebook 06).
# * **Training seeds.** The DAGNN rows are trained with three seeds (a DAGNN trains in under a
#   minute) and report the mean over seeds with its standard deviation; VGAI rows use one seed (a
#   VGAI trains in about half an hour on this machine).
# * **Tables 2a and 2b** (initial velocity, radius): the paper does not say whether it retrains. Its
#   section is about robustness, so the rows DAGNN and VGAI are the controllers trained at the
#   defaults ($v_{init} = 3$, $R = 1.5$) and flown in each condition; the row *DAGNN (retrained)*
#   is trained in that condition, to show what retraining buys.
# * **Table 3**: trained on $N = 50$, flown by $N'$ agents. At $N' \ge 75$ the paper's rejection
#   sampling of initial conditions practically never accepts a draw, so those episodes come from
#   our "repair" sampler (notebook 01).
# * **Our simulator is not AirSim**: the paper's drones fly in AirSim with its physics and cameras;
#   ours are the paper's stated double integrators and our own renderer. Numbers need not match;
#   the findings should.

# %%
def cell(table, row, col):
    return results["tables"][table]["rows"].get(row, {}).get(str(col))


def table_markdown(table):
    t = results["tables"][table]
    head = f"| {t['column']} | " + " | ".join(f"{c:g}" for c in t["columns"]) + " |"
    lines = [head, "|---" * (len(t["columns"]) + 1) + "|"]
    for row, cells in t["rows"].items():
        parts = []
        for c in t["columns"]:
            x = cells.get(str(c))
            if x is None:
                parts.append("")
                continue
            spread = (f" ± {x['seed_std']:.2f}" if x["seed_std"] is not None
                      else f" ({x['ci95'][0]:.2f}-{x['ci95'][1]:.2f})" if x["ci95"] else "")
            paper = f" [{x['paper']:.2f}]" if x["paper"] is not None else ""
            parts.append(f"**{x['relative_cost_mean']:.2f}**{spread}{paper}")
        lines.append(f"| {row} | " + " | ".join(parts) + " |")
    return f"**{t['title']}** — ours in bold (95% CI over episodes, or ± std over training seeds), paper's in brackets\n\n" + "\n".join(lines)


def plot_table(ax, table, logx=False):
    t = results["tables"][table]
    cols = t["columns"]
    colors = {"DAGNN": "C0", "DAGNN (retrained)": "C9", "Local": "C3", "VGAI": "C2"}
    for row, cells in t["rows"].items():
        xs = [c for c in cols if str(c) in cells]
        ys = [cells[str(c)]["relative_cost_mean"] for c in xs]
        err = [cells[str(c)]["seed_std"] or 0 for c in xs]
        ax.errorbar(xs, ys, yerr=err, fmt="o-", color=colors[row], label=f"{row} (ours)", capsize=3)
        px = [c for c in xs if cells[str(c)]["paper"] is not None]
        if px:
            ax.plot(px, [cells[str(c)]["paper"] for c in px], "s--", color=colors[row], alpha=0.5,
                    mfc="none", label=f"{row} (paper)")
    ax.axhline(1, color="0.5", lw=0.8, ls=":")
    ax.set_xticks(cols)
    ax.set_xlabel(t["column"]), ax.set_ylabel("relative cost"), ax.set_title(t["title"], fontsize=9)


for table in TABLES:
    display(Markdown(table_markdown(table)))

# %%
fig, axes = plt.subplots(1, 5, figsize=(22, 4.2))
for ax, table in zip(axes, TABLES):
    plot_table(ax, table)
axes[-1].legend(fontsize=7, loc="upper left")
axes[2].legend(fontsize=7, loc="upper left")
plt.tight_layout()
plt.show()

# %% [markdown]
# ## The paper's findings, checked against our numbers
#
# Each line is computed from the tables above (and, for the paper's column, from its numbers).

# %%
def series(table, row):
    t = results["tables"][table]
    return [cell(table, row, c)["relative_cost_mean"] for c in t["columns"] if cell(table, row, c)]


def paper_series(table, row):
    return [PAPER[table][row][c] for c in TABLES[table]["columns"] if c in PAPER[table].get(row, {})]


def decreasing(xs):
    return len(xs) > 1 and all(a > b for a, b in zip(xs, xs[1:]))


def increasing(xs):
    return len(xs) > 1 and all(a < b for a, b in zip(xs, xs[1:]))


def ordered(table, source):
    cols = TABLES[table]["columns"]
    ok = []
    for c in cols:
        get = (lambda r: (cell(table, r, c) or {}).get("relative_cost_mean")) if source == "ours" \
            else (lambda r: PAPER[table].get(r, {}).get(c))
        d, v, l = get("DAGNN"), get("VGAI"), get("Local")
        if None not in (d, v, l):
            ok.append(d < v < l)
    return (all(ok), f"{sum(ok)}/{len(ok)} columns") if ok else (None, "no column with all three")


def mark(x):
    return "—" if x is None else ("yes" if x else "**no**")


findings = []
for table in ("v_init", "R", "N"):
    (p, pn), (o, on) = ordered(table, "paper"), ordered(table, "ours")
    findings.append((f"DAGNN < VGAI < Local in every column ({TABLES[table]['title'].split(':')[0]})", p, o, on))
for row in ("DAGNN", "VGAI"):
    findings.append((f"more exchanges help {row} (Table 1b decreasing in K-1)",
                     decreasing(paper_series("K", row)), decreasing(series("K", row)),
                     " → ".join(f"{x:.2f}" for x in series("K", row))))
for row in ("DAGNN", "Local", "VGAI"):
    findings.append((f"larger R helps {row} (Table 2b decreasing in R)",
                     decreasing(paper_series("R", row)), decreasing(series("R", row)),
                     " → ".join(f"{x:.2f}" for x in series("R", row))))
for row in ("DAGNN", "Local", "VGAI"):
    findings.append((f"higher v_init is harder for {row} (Table 2a increasing)",
                     increasing(paper_series("v_init", row)), increasing(series("v_init", row)),
                     " → ".join(f"{x:.2f}" for x in series("v_init", row))))
findings.append(("VGAI improves with more features F (Table 1a, F = 6 → 24)",
                 paper_series("F", "VGAI")[-1] < paper_series("F", "VGAI")[0],
                 series("F", "VGAI")[-1] < series("F", "VGAI")[0],
                 " → ".join(f"{x:.2f}" for x in series("F", "VGAI"))))
vg = {c: cell("N", "VGAI", c) for c in TABLES["N"]["columns"]}
lo = {c: cell("N", "Local", c) for c in TABLES["N"]["columns"]}
findings.append(("VGAI still flocks as N' grows (below the local heuristic at every N')", True,
                 all(vg[c]["relative_cost_mean"] < lo[c]["relative_cost_mean"] for c in vg),
                 ", ".join(f"{c}: {vg[c]['relative_cost_mean']:.2f} vs {lo[c]['relative_cost_mean']:.2f}" for c in vg)))
display(Markdown("| finding | paper | ours | our numbers |\n|---|---|---|---|\n" +
                 "\n".join(f"| {f} | {mark(p)} | {mark(o)} | {n} |" for f, p, o, n in findings)))

# %% [markdown]
# ## Collisions: what the cost does not see
#
# The cost of eq. 1 only measures velocity disagreement; a controller could flock well and crash.
# For every cell: the closest any pair came in any episode, the median over episodes of each
# episode's closest approach, and the share of episodes with a pair closer than 0.05 m (a drone's
# body in our renderer and pymunk is a 5 cm-radius cylinder, so 0.1 m is contact), the expert's
# beside them on the same episodes.

# %%
rows = []
for table, t in results["tables"].items():
    for row, cells in t["rows"].items():
        for c in t["columns"]:
            x = cells.get(str(c))
            if x is None:
                continue
            rows.append(f"| {table} | {row} | {c:g} | {x['min_distance']:.3f} | {x['median_min_distance']:.3f} | "
                        f"{x['share_below_0.05m']:.0%} | {x['expert_min_distance']:.3f} | "
                        f"{x['expert_median_min_distance']:.3f} | {x['expert_share_below_0.05m']:.0%} |")
display(Markdown("| table | controller | column | closest [m] | median closest [m] | episodes < 0.05 m | "
                 "expert closest | expert median | expert < 0.05 m |\n|---|---|---|---|---|---|---|---|---|\n"
                 + "\n".join(rows)))

# %% [markdown]
# ## Communication: bytes per drone per step
#
# In the delayed aggregation (eq. 6) a drone's $k$-th block at time $t$ is the sum of its
# neighbours' $(k-1)$-th blocks at $t-1$. So at every step each drone broadcasts its blocks
# $0, \dots, K-2$ of the previous step: $(K-1)\,F$ numbers, $4 (K-1) F$ bytes as float32, whatever
# the number of neighbours (one broadcast). Over point-to-point links it sends that to each
# neighbour, so the mean degree (measured below on expert flights) multiplies it. At $T_s = 0.01$ s
# there are 100 steps per second. The DAGNN exchanges its 6 exact features; VGAI its $F$ learned
# ones, and nothing of its images.

# %%
cfg = FlockConfig()
r0, v0 = sample_initial_state(cfg, pick(20, 2), torch.Generator().manual_seed(EVAL_SEED))
traj = rollout(ExpertController(cfg), cfg, r0, v0)
degree = {}
for R in TABLES["R"]["columns"]:
    A = adjacency(traj.r.flatten(0, 1), R)
    degree[R] = A.sum(-1).mean().item()
rows = []
for name, F in (("DAGNN", 6), ("VGAI", 6), ("VGAI", 12), ("VGAI", 24)):
    for km1 in TABLES["K"]["columns"]:
        b = 4 * F * km1
        rows.append(f"| {name} | {F} | {km1} | {b} | {b * 100 / 1000:.1f} | "
                    + " | ".join(f"{b * degree[R] * 100 / 1000:.0f}" for R in degree) + " |")
display(Markdown(
    "| controller | F | K-1 | bytes per drone per step (broadcast) | kB/s (broadcast) | "
    + " | ".join(f"kB/s point-to-point, R = {R:g} (mean degree {d:.1f})" for R, d in degree.items())
    + " |\n|---|---|---|---|---|" + "---|" * len(degree) + "\n" + "\n".join(rows)))

# %% [markdown]
# Relating bytes to cost with our tables: going from $F = 6$ to $F = 24$ quadruples what each drone
# sends; going from one exchange to three triples it. The tables above show what each buys.

# %%
F_row = {c: cell("F", "VGAI", c)["relative_cost_mean"] for c in TABLES["F"]["columns"]}
K_row = {c: cell("K", "VGAI", c)["relative_cost_mean"] for c in TABLES["K"]["columns"]}
fig, ax = plt.subplots(figsize=(6, 3.8))
ax.plot([4 * F * 3 for F in F_row], list(F_row.values()), "o-", label="VGAI, F = 6, 12, 24 (K-1 = 3)")
ax.plot([4 * 24 * k for k in K_row], list(K_row.values()), "s-", label="VGAI, K-1 = 1, 2, 3 (F = 24)")
d_row = {c: cell("K", "DAGNN", c)["relative_cost_mean"] for c in TABLES["K"]["columns"]}
ax.plot([4 * 6 * k for k in d_row], list(d_row.values()), "^-", label="DAGNN, K-1 = 1, 2, 3 (exact, F = 6)")
ax.set_xlabel("bytes per drone per step (broadcast)"), ax.set_ylabel("relative cost")
ax.legend(fontsize=8)
plt.tight_layout()
plt.show()

# %% [markdown]
# ## Where we differ from the paper, and why
#
# The discussion below is generated from the numbers, then commented.

# %%
d3, v3, l3 = (cell("K", "DAGNN", 3)["relative_cost_mean"], cell("K", "VGAI", 3)["relative_cost_mean"],
              cell("v_init", "Local", 3.0)["relative_cost_mean"])
display(Markdown(
    f"* At the defaults our DAGNN scores **{d3:.2f}** (paper 1.70), our VGAI **{v3:.2f}** (paper 2.26) and our "
    f"local heuristic **{l3:.2f}** (paper 4.13). The ratio VGAI / DAGNN is {v3 / d3:.2f} in ours and "
    f"{2.26 / 1.70:.2f} in the paper's.\n"
    f"* Table 3's first column in the paper (1.70 at N' = 50) is the paper's DAGNN number, not its VGAI's "
    f"(2.26 in Tables 1-2 for the same configuration); ours at N' = 50 is the same cell as the default VGAI: "
    f"{cell('N', 'VGAI', 50)['relative_cost_mean']:.2f}.\n"
    "* Retraining the DAGNN in each condition (Table 2) instead of flying the one trained at the defaults "
    "changes its relative cost by " + ", ".join(
        f"{TABLES[t]['column']} = {c:g}: {cell(t, 'DAGNN (retrained)', c)['relative_cost_mean'] - cell(t, 'DAGNN', c)['relative_cost_mean']:+.2f}"
        for t in ("v_init", "R") for c in TABLES[t]["columns"]) + "."))

# %% [markdown]
# Absolute costs behind Table 2a's local-heuristic row (same held-out episodes):

# %%
for v in TABLES["v_init"]["columns"]:
    c_v = FlockConfig(v_init=v)
    res = relative_cost(LocalController(c_v), c_v, episodes=pick(30, 2), seed=EVAL_SEED)
    print(f"v_init = {v:g}: expert cost {res.expert_cost.mean():6.1f}, local heuristic {res.cost.mean():6.1f}, "
          f"ratio {res.mean_ratio:.2f}")

# %% [markdown]
# * **Our DAGNN is better than the paper's.** Our simulator is exactly the model the expert and the
#   DAGNN assume (a noiseless double integrator, exact relative positions and velocities, no
#   latency), while the paper's AirSim drones have their own flight dynamics between command and
#   motion. Imitation is easier when the expert's model is the world. At $R = 2$ m our DAGNN even
#   scores below 1: the expert is a hand-designed potential-field controller, not the minimiser of
#   eq. 1, so a learned controller can beat its cost.
# * **VGAI is close to the paper's numbers at the defaults, and its trends in F and K are the
#   paper's**: more features and more exchanges both lower the cost, F = 6 still flocks, far better
#   than the local heuristic. The gap between VGAI and the DAGNN is larger in ours because our DAGNN
#   is better: our VGAI must infer velocities from two rendered frames of 12 × 128 pixels, with a
#   CNN sized to train in half an hour on two CPU cores, and the alignment term that dominates the
#   expert's action needs velocities (notebook 05).
# * **The radius table is where we differ most.** Our rows DAGNN and VGAI are trained at $R = 1.5$
#   and flown at 1.0 and 2.0; the paper does not say whether it retrained. The row *DAGNN
#   (retrained)* shows that retraining matters at $R = 1$ m, where fewer neighbours carry less
#   information and the deployed DAGNN can fall behind VGAI. VGAI flown at $R = 2$ m does not
#   improve: its MLP never saw the larger, more distant neighbourhoods, in the features its CNN
#   makes, that a 2 m radius brings. A VGAI retrained per radius (half an hour each) is the
#   experiment that would settle it; we have not run it. Our local heuristic collapses at
#   $R = 1$ m much more than the paper's: with one-hop information only and few neighbours, our
#   swarms break apart (notebook 01 shows how sensitive it is to the potential's radius $\rho$).
# * **Initial velocity**: VGAI finds slow starts easier, as in the paper. Our DAGNN's row is flat
#   within its spread over training seeds. Retraining the DAGNN on slow starts ($v_{init} = 1$)
#   does *worse* than flying the default one there (the line above); we have not investigated why.
#   Our local heuristic's *relative* cost falls as $v_{init}$ grows: relative cost divides by the
#   expert's cost, which grows faster with $v_{init}$ than the local heuristic's (the cell above).
# * **Spread.** Differences smaller than the intervals are not evidence either way, in ours or (no
#   spread reported) in the paper's. The DAGNN's spread over three training seeds is often larger
#   than its interval over episodes (compare the ± with the intervals of notebook 03), so one
#   training seed per cell, as for our VGAI rows and, as far as it says, the paper's, understates
#   the uncertainty.
# * **Scaling**: trained on 50 agents, VGAI keeps flocking at 60, 75, 100 and 200, well below the
#   local heuristic; its cost creeps up with $N'$, and so do its close calls (the share of episodes
#   with a pair closer than 0.05 m grows faster than the expert's). With the symmetric-normalised GSO
#   what a drone aggregates stays on the same scale as its degree grows (notebook 03 shows the
#   un-normalised GSO failing at 100).
#
# ## What's next
#
# * More training seeds for VGAI (`--vgai-seeds 3`, about an hour and a half more) would give the
#   VGAI rows a spread over training, as the DAGNN rows have.
# * The exercises of notebooks 01-06 can be graded automatically; see the README's section for
#   instructors.

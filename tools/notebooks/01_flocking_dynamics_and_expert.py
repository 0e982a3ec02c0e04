# %% [markdown]
# # 01 · Flocking: the dynamics, the expert and the local heuristic
#
# *Paper: Hu et al., "VGAI", ICASSP 2021, section 3.1 and "Implementation Details".*
#
# Everything in this book imitates one controller, the **centralized expert**, and is measured
# against it. This notebook builds the world it acts in:
#
# 1. $N$ drones flying in a plane as **double integrators** (we command accelerations);
# 2. the paper's **initial conditions**, with resampling of unsolvable draws;
# 3. the **flocking cost** (eq. 1) and the **relative cost** used in every table of the paper;
# 4. the **expert** (eq. 2) with its **collision potential** (eq. 3), and the **local heuristic**
#    that a decentralized controller must beat;
# 5. what the cost does *not* see: close approaches between drones.
#
# Every constant lives in one object, `FlockConfig`; every function used here is in
# `vgai_lite/` (click through: `flocking.py`, `controllers.py`, `evaluate.py`).
#
# **Learning objectives.** After this notebook you can simulate a batched double-integrator swarm with
# the paper's initial conditions; compute the flocking cost (eq. 1) and the relative cost of every
# table; explain what the expert (eq. 2-3) needs that a drone does not have.
#
# **You implement** the gradient of the collision potential (exercise 01.1) and the flocking cost
# (exercise 01.2); an automatic check tells you at once whether it is right, and the last cell gives
# your score.

# %%
import inspect
import time

import matplotlib.pyplot as plt
import numpy as np
import torch
from IPython.display import Markdown, display

from vgai_lite import (ExpertController, FlockConfig, LocalController, flocking_cost, potential,
                       potential_gradient, relative_cost, rollout, sample_initial_state, step)
from vgai_lite.book import WORKING_SEED, QUICK, VALIDATION_SEED, pick, prose, threads
from vgai_lite.lab.paper import PAPER
from vgai_lite.evaluate import CLOSE_CALLS, FLOCK_TIMES, FLOCKED_CONNECTED, FLOCKED_VARIANCE
from vgai_lite.viz import (PALETTE, animate_swarms, controller_color, animation_image, draw_swarm, plot_trajectories,
                           plot_velocity_variance, velocity_variance)

torch.set_num_threads(threads())  # 2, or VGAI_LITE_THREADS (vgai_lite.book)
print("quick mode" if QUICK else "full mode")

# %% [markdown]
# ## 1. The constants
#
# `FlockConfig` holds the problem. The paper fixes $N = 50$, $R = 1.5$ m, $T_s = 0.01$ s,
# $v_{init} = 3$ m/s and the $\pm 30$ m/s² saturation. It is silent on two things the book had to
# choose, the potential's radius $\rho$ and the episode length $T$, and its text and the reference
# code disagree on a third, the initial disc; each is explained below.

# %%
# NBVAL_CHECK_OUTPUT
cfg = FlockConfig()
print(cfg)
print(f"initial disc radius N**{cfg.init_radius_exponent} = {cfg.init_radius:.3f} m")

# %% [markdown]
# A wrong value is refused on creation with a message that says what was expected:

# %%
for bad in (dict(N=1), dict(R=0.0), dict(potential="quadratic")):
    try:
        FlockConfig(**bad)
    except ValueError as err:
        print(err)

# %% [markdown]
# ## 2. Double integrators
#
# Agent $i$ has position $\mathbf r_i(t)$, velocity $\mathbf v_i(t)$ and commands an acceleration
# $\mathbf u_i(t)$, held constant over one sampling period $T_s$. Integrating exactly over the period:
#
# $$\mathbf r_i(t+1) = \mathbf r_i(t) + T_s\,\mathbf v_i(t) + \tfrac{T_s^2}{2}\,\mathbf u_i(t),\qquad
#   \mathbf v_i(t+1) = \mathbf v_i(t) + T_s\,\mathbf u_i(t).$$
#
# (The public reference code drops the $T_s^2/2$ term; with $T_s = 0.01$ s it changes positions by
# at most 1.5 mm per step at full saturation. We keep the exact update.) Everything is batched:
# `r` and `v` are `(B, N, 2)` tensors, $B$ swarms at once.

# %%
print(inspect.getsource(step).split('"""')[-1])

# %% [markdown]
# A quick sanity check: under a constant acceleration, 100 steps land exactly where
# $\mathbf r_0 + \mathbf v_0 t + \mathbf u t^2/2$ says.

# %%
r, v = torch.zeros(1, 1, 2, dtype=torch.float64), torch.tensor([[[1.0, 0.0]]], dtype=torch.float64)
u = torch.tensor([[[0.0, 2.0]]], dtype=torch.float64)
for _ in range(100):
    r, v = step(r, v, u, cfg)
print("after 1 s:", r.flatten().tolist(), " expected: [1.0, 1.0]")

# %% [markdown]
# ## 3. Initial conditions
#
# The paper: positions uniform on a disc "with radius $\sqrt N$ to normalize the density";
# velocities uniform in $[-v_{init}, v_{init}]^2$ plus a flock-wide bias uniform in
# $[-0.3\,v_{init}, 0.3\,v_{init}]^2$; a draw is rejected if any agent has fewer than two neighbours
# within $R$ or any pair starts closer than 0.2 m.
#
# **The disc.** Taken literally, $\sqrt{50} = 7.07$ m makes the swarm so sparse that *no* draw
# ever gives every agent two neighbours within 1.5 m. The authors' public code instead draws the
# radius as $\sqrt{U(0, \sqrt N)}$, which is uniform on a disc of radius $N^{1/4}$ = 2.66 m. We
# follow the code (`init_radius_exponent = 0.25`). Let us count how often each disc passes each test:

# %%
from vgai_lite.flocking import pairwise_offsets


def acceptance(cfg, draws, generator):
    """Share of raw candidate swarms passing each of the paper's two tests."""
    rad = cfg.init_radius * torch.rand(draws, cfg.N, generator=generator).sqrt()
    ang = 2 * np.pi * torch.rand(draws, cfg.N, generator=generator)
    _, _, d2 = pairwise_offsets(torch.stack((rad * ang.cos(), rad * ang.sin()), -1))
    two = (d2 <= cfg.R ** 2).sum(-1).min(-1).values >= cfg.min_neighbours
    apart = d2.flatten(1).min(1).values >= cfg.min_init_distance ** 2
    return two.double().mean().item(), apart.double().mean().item(), (two & apart).double().mean().item()


draws = pick(20_000, 2_000)
g = torch.Generator().manual_seed(0)
for exponent, label in ((0.5, "paper text, sqrt(N)"), (0.25, "reference code, N**0.25")):
    c = cfg.replace(init_radius_exponent=exponent)
    two, apart, both = acceptance(c, draws, g)
    print(f"{label:26s} radius {c.init_radius:4.2f} m: >=2 neighbours {two:6.1%}, "
          f"no pair < 0.2 m {apart:6.1%}, both {both:7.3%}  ({draws} draws)")

# %%
survivors = (f"about one candidate in {1 / both:,.0f} survives" if both > 0
             else f"none of the {draws:,} candidates survived")
prose("With the $N^{{1/4}}$ disc the neighbour test almost always passes and the 0.2 m test almost always "
      f"fails: {survivors}. `sample_initial_state` therefore draws candidates in vectorised chunks, "
      "screens them cheaply, and raises a clear error (rather than looping forever) if a configuration "
      "is essentially unsatisfiable.")

# %%
t0 = time.perf_counter()
r0, v0 = sample_initial_state(cfg, pick(50, 8), torch.Generator().manual_seed(WORKING_SEED))
dt = time.perf_counter() - t0
print(f"{len(r0)} initial conditions in {dt:.2f} s ({1000 * dt / len(r0):.0f} ms each)")

try:
    sample_initial_state(cfg.replace(init_radius_exponent=0.5, max_init_tries=20_000), 1)
except RuntimeError as err:
    print("\nthe sqrt(N) disc:", err)

# %%
fig, ax = plt.subplots(figsize=(5.5, 5.5))
draw_swarm(ax, r0, v0, cfg)
ax.add_patch(plt.Circle((0, 0), cfg.init_radius, fill=False, ls="--", color="0.5"))
ax.set_title(f"An initial swarm: N = {cfg.N}, links of length <= R = {cfg.R} m,\n"
             "arrows = velocity (0.15 s of flight)")
plt.show()

# %% [markdown]
# ## 4. The flocking cost (eq. 1) and the relative cost
#
# Flocking means every agent flies with the same velocity. The paper states it as a problem over
# the accelerations:
#
# \begin{equation*}
# \min_{\substack{\mathbf u_i(t)\\ i=1,\dots,N\\ t\ge 0}} \frac{1}{N} \sum_{t} \sum_{i=1}^{N} \Big\| \mathbf v_i(t) - \frac1N \sum_{j=1}^N \mathbf v_j(t) \Big\|^2 . \tag{1}
# \end{equation*}
#
# Its objective, summed over the $T$ steps of a flight, is the **flocking cost** $C$ of a controller:
# the velocity variance across the swarm, summed over time (`vgai_lite.flocking_cost`).
#
# It ignores positions entirely: a swarm can score well while two drones touch. The paper reports
# every controller's cost **relative to the centralized expert's** on the same initial conditions
# (expert = 1.00). We report the mean of costs over the mean of the expert's costs (the number we
# set beside the paper's; the paper does not say how it averages), the median of per-episode ratios, and a bootstrap 95 % interval.
#
# **Episode length.** The paper does not give $T$. We use $T = 200$ steps (2 s): by then the
# expert has flocked and its action is zero, so a longer episode adds only the learner's residual
# disagreement.
#
# You will write eq. 1 yourself in exercise 01.2, at the end of this notebook; the book uses
# `vgai_lite.flocking_cost`.

# %% [markdown]
# **When has a swarm flocked?** A relative cost is an average, and most of eq. 1 accrues in the
# first steps (section 7 measures how much): a controller can score well and leave its drones
# drifting past each other for ever. The paper's only criterion is a relative cost below 3. This
# book uses one operational definition everywhere it says a controller *flocked* (`evaluate.flocked`):

# %%
prose("A controller **flocked** when, over the episodes it flew, the median velocity variance (the summand of eq. 1) "
      "at {late:g} s, the same flights flown on past the {T:g} s of an episode, is at most {v:g} m²/s², velocities "
      "that disagree by {rms:.3f} m/s RMS, less than half a body length per second; and the communication graph is "
      "still connected at {late:g} s in at least {c:.0%} of the episodes. Why {late:g} s: a late horizon shows "
      "whether the disagreement keeps shrinking, which an average over the first {T:g} s hides.",
      late=max(FLOCK_TIMES), T=min(FLOCK_TIMES), v=FLOCKED_VARIANCE, rms=FLOCKED_VARIANCE ** 0.5, c=FLOCKED_CONNECTED)

# %% [markdown]
# ## 5. The collision potential (eq. 3) and the expert (eq. 2)
#
# The expert (Tolstaya et al. 2019, eq. 10) steers every agent's velocity toward every other
# agent's and pushes agents apart through a potential:
#
# $$ \mathbf u_i^*(t) = -\sum_{j=1}^{N} \big(\mathbf v_i(t) - \mathbf v_j(t)\big) - \sum_{j=1}^N \nabla_{\mathbf r_i(t)} U\big(\mathbf r_i(t), \mathbf r_j(t)\big), \tag{2}$$
#
# \begin{equation*}
# U(\mathbf r_i, \mathbf r_j) = \begin{cases} 1/\|\mathbf r_{ij}\|^2 - \log \|\mathbf r_{ij}\|^2 & \text{if } \|\mathbf r_{ij}\| \le \rho \\
#    1/\rho^2 - \log \rho^2 & \text{otherwise,} \end{cases} \qquad \mathbf r_{ij} = \mathbf r_i - \mathbf r_j, \tag{3}
# \end{equation*}
#
# saturated per axis to ±30 m/s². Three remarks:
#
# * The alignment sum over *all* $j$ equals $N(\bar{\mathbf v} - \mathbf v_i)$: every agent needs the
#   swarm's mean velocity. That is why the expert is **centralized**.
# * As printed, $U$ decreases all the way to $\rho$: it is **purely repulsive**. The public reference
#   code uses $1/\|r\|^2 + \log\|r\|^2$, which repels below 1 m and would *attract* between 1 m and
#   $\rho$ (were $\rho$ above 1 m). We follow the paper (`potential="paper"`) and keep the code's version as an option.
# * **$\rho$** is not given. We use **0.5 m**: with it the local heuristic's relative cost lands
#   near the paper's 4.13 (section 8 below measures the alternatives). Note the potential's value
#   jumps by nothing at $\rho$ but its gradient does: the push drops from about 20 m/s² to 0.

# %%
d = torch.linspace(0.08, 1.2, 400, dtype=torch.float64)
fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
for which, style in (("paper", "-"), ("reference", "--")):
    c = cfg.replace(potential=which)
    r_ij = torch.stack((d, torch.zeros_like(d)), -1)
    axes[0].plot(d, potential(d ** 2, c), style, label=f"{which}: U")
    axes[1].plot(d, -potential_gradient(r_ij, c)[:, 0], style, label=f"{which}: push on i, $-\\partial U/\\partial x_i$")
for ax in axes:
    ax.axvline(cfg.rho, color="0.6", lw=0.8)
    ax.set_xlabel(r"distance $\|r_{ij}\|$ [m]")
    ax.legend()
axes[0].set_ylim(-2, 40), axes[0].set_title(f"potential, rho = {cfg.rho} m (grey line)")
axes[0].set_ylabel(r"$U(r_i, r_j)$ of eq. 3")
axes[1].set_ylabel(r"$-\partial U / \partial x_i$: eq. 2's term [m/s²]")
axes[1].set_yscale("symlog", linthresh=1), axes[1].set_ylim(bottom=0), axes[1].set_title("repulsive acceleration (> 0 pushes apart)")
plt.tight_layout()
plt.show()

# %% [markdown]
# The expert in code, the equation term by term (`vgai_lite/controllers.py`):

# %%
from vgai_lite import controllers

print(inspect.getsource(controllers.expert_control).split('"""')[-1])

# %% [markdown]
# ## 6. The local heuristic
#
# The natural decentralized controller computes eq. 2 with both sums restricted to the neighbours
# $\mathcal N_i(t) = \{ j : \|\mathbf r_i - \mathbf r_j\| \le R \}$ (the paper displays it without a number):
#
# $$ \tilde{\mathbf u}_i(t) = -\sum_{j\in\mathcal N_i(t)} \big(\mathbf v_i(t) - \mathbf v_j(t)\big) - \sum_{j\in\mathcal N_i(t)} \nabla_{\mathbf r_i(t)} U\big(\mathbf r_i(t), \mathbf r_j(t)\big).$$
#
# It uses present, one-hop information only. Since $\rho < R$, its repulsion equals the expert's; only the alignment differs:
# each agent aligns with its neighbours, not with the swarm. This is the paper's **upper bound**: a
# learned decentralized controller should do better by listening to neighbours' neighbours.

# %%
print(inspect.getsource(controllers.local_control).split('"""')[-1])

# %% [markdown]
# ## 7. Both controllers at work
#
# We fly the same initial conditions under both controllers.
#
# **Three sets of initial conditions, never mixed.** A number means something only if nothing was
# chosen by looking at it. The book draws its episodes from three seeds, named in `vgai_lite/book.py`:
#
# | episodes | seed | used for |
# |---|---|---|
# | training | a run's own seed (its per-round checks at a fixed offset from it) | what a controller learns from |
# | **validation** | `VALIDATION_SEED` | every choice: a design, a recipe, a hyperparameter ($\rho$ below), which of several training seeds to ship |
# | **test** | `TEST_SEED` | only the numbers the book reports for the controllers it ships; nothing is chosen on them |
# | working | `WORKING_SEED` | the chapters' pictures and worked experiments (this chapter's pictures and section 8's costs, notebook 03's worked examples, the shipped DAGNNs' own records) |
#
# Why: a choice made on the episodes that are then reported flatters the choice (with enough
# variants, one looks good on those episodes by luck). The **working episodes** are held out from
# training too, but the chapters compare designs on them while they teach, so they are not a test:
# this chapter's pictures and section 8's costs use them (its choice of ρ is made on the validation
# episodes), and the headline figures of the shipped controllers
# are flown on the test episodes (their records in `data/` say which seed each number came from).

# %%
expert, local = ExpertController(cfg), LocalController(cfg)
t0 = time.perf_counter()
trajs = {c.name: rollout(c, cfg, r0, v0) for c in (expert, local)}
print(f"{2 * len(r0)} episodes of {cfg.T} steps in {time.perf_counter() - t0:.2f} s")

fig, axes = plt.subplots(1, 2, figsize=(11, 5))
for ax, (name, traj) in zip(axes, trajs.items()):
    plot_trajectories(ax, traj, b=0, color=controller_color(name))
    ax.set_title(f"{name}: paths over {cfg.T * cfg.Ts:.0f} s (o = start)")
plt.tight_layout()
plt.show()

# %% [markdown]
# The expert turns the whole swarm into one group moving with the mean velocity. The local heuristic
# aligns small clusters that then drift apart: agents that lose their neighbours keep whatever
# velocity they had.
#
# Velocity variance over time (the summand of eq. 1), median over episodes with a 10-90 % band:

# %%
fig, axes = plt.subplots(1, 2, figsize=(12, 4))
plot_velocity_variance(axes[0], trajs, cfg.Ts)
axes[0].set_ylim(bottom=1e-6)
axes[0].set_title("velocity variance across the swarm")
for name, traj in trajs.items():
    t = np.arange(cfg.T) * cfg.Ts
    axes[1].plot(t, traj.u.abs().amax(-1).mean((1, 2)), label=name, color=controller_color(name))
axes[1].axhline(cfg.u_max, color="0.6", lw=0.8, ls="--")
axes[1].set_xlabel("time [s]"), axes[1].set_ylabel("mean over agents of max(|u_x|, |u_y|) [m/s²]")
axes[1].set_title("how hard the controllers push (saturation at 30)"), axes[1].legend()
plt.tight_layout()
plt.show()

# %% [markdown]
# Two things to keep in mind for the rest of the book. The expert works **early**: it is saturated
# for the first few tenths of a second and idle after about one second. And so is the **cost**: most
# of eq. 1 accrues in the first steps (the cell below measures how much).

# %%
var = velocity_variance(trajs["Centralized"].v)  # (T, B)
share = (var.cumsum(0) / var.sum(0)).median(1).values
for k in (10, 20, 50, 100):
    print(f"share of the expert's cost accrued in the first {k:3d} steps: {share[k - 1]:.0%}")

# %% [markdown]
# An animation of one swarm under both controllers (links drawn between agents within $R$):

# %%
anim = animate_swarms(trajs, cfg, b=0, every=pick(8, 50), size=4.0, dpi=80)
animation_image(anim)

# %% [markdown]
# ## 8. The relative cost of the local heuristic, and close approaches
#
# The paper reports **Local = 4.13** (centralized = 1.00). Here is ours on the working episodes:

# %%
episodes = pick(50, 8)
t0 = time.perf_counter()
res_local = relative_cost(local, cfg, episodes=episodes, seed=WORKING_SEED)
print(f"({time.perf_counter() - t0:.1f} s)")
print(res_local)

# %%
ratio = (res_local.cost / res_local.expert_cost).numpy()
fig, axes = plt.subplots(1, 2, figsize=(12, 3.8))
axes[0].hist(ratio, bins=20, color=PALETTE["Local"], alpha=0.8)
axes[0].axvline(res_local.mean_ratio, color="k", label=f"ours, mean ratio {res_local.mean_ratio:.2f}")
paper_local = PAPER["R"]["Local"][1.5]  # the paper's Local at the defaults (R = 1.5 m, v_init = 3 m/s)
axes[0].axvline(paper_local, color="tab:red", ls="--", label=f"paper: {paper_local:.2f}")
axes[0].set_xlabel("per-episode cost ratio Local / Centralized"), axes[0].set_ylabel("episodes")
axes[0].legend()
bins = np.linspace(0, 0.3, 31)
axes[1].hist(res_local.expert_safety.min_distance.numpy(), bins=bins, alpha=0.6, label="Centralized",
             color=PALETTE["expert"])
axes[1].hist(res_local.safety.min_distance.numpy(), bins=bins, alpha=0.6, label="Local", color=PALETTE["Local"])
for th, ls in zip(CLOSE_CALLS, (":", "--")):
    axes[1].axvline(th, color="0.4", ls=ls, label=f"close call: < {th:g} m")
axes[1].set_xlabel("closest approach of any pair in an episode [m]"), axes[1].set_ylabel("episodes")
axes[1].legend()
plt.tight_layout()
plt.show()

# %%
lo, hi = res_local.mean_ratio_ci
prose("Our local heuristic costs {m:.2f} ({lo:.2f}-{hi:.2f}); the paper's {p:.2f} lies {where} that interval "
      "(the paper flies AirSim drones; we fly the stated double integrator).", m=res_local.mean_ratio, lo=lo, hi=hi,
      p=paper_local, where="below" if paper_local < lo else "above" if paper_local > hi else "inside")

# %% [markdown]
# The safety columns matter as much as the cost: eq. 1 is blind to
# collisions, and the initial conditions allow pairs to start 0.2 m apart and close in at up to
# $6\sqrt2 \approx 8.5$ m/s (the flock-wide bias cancels in relative velocity). When is the closest
# approach reached?

# %%
for name, traj in trajs.items():
    when = traj.min_distance.argmin(dim=0).double()
    print(f"{name:12s} closest approach at step {when.median().item():.0f} (median; "
          f"90th percentile {when.quantile(0.9).item():.0f})")

# %% [markdown]
# **How the book reports safety.** Each drone's body is a cylinder of 5 cm radius (notebook 04), so
# two drones touch when their centres are closer than 0.1 m. The book reports, beside every cost,
# the median over the episodes of each episode's closest approach and the share of episodes with a
# pair closer than 0.05 m: bodies half into each other, a crash rather than a graze. The share
# below 0.1 m (contact) is in every record too, and shown where a table has room. Since even the
# expert comes close in some episodes (closer than 0.1 m in some of the episodes above, closer than
# 0.05 m in some of notebook 06's test episodes; its closest approaches are set by the initial
# conditions, below), a controller is called **as safe as the expert** when its share below 0.05 m
# is at most the expert's plus 4 points (or 5%, whichever is larger) and its median closest approach
# at least 0.9 times the expert's, on the same episodes.
#
# In the first handful of steps, for both controllers alike: a pair that starts close and fast is
# braked by a repulsion of thousands of m/s², saturated at 30, so the closest approach is set by the
# initial conditions and the saturation, not by the alignment rule. A learned controller must keep
# this braking: the repulsion lives in a few samples at the start of a few episodes.
#
# **Why $\rho$ = 0.5 m.** The paper gives no value. A sweep on validation episodes (fewer per value
# than above), with the local swarm's mean number of neighbours at the end of the episode:

# %%
rows = []
for rho in (0.3, 0.5, 0.75, 1.0):
    c = cfg.replace(rho=rho)
    res = relative_cost(LocalController(c), c, episodes=pick(20, 2), seed=VALIDATION_SEED)  # a choice: validation episodes
    r_val, v_val = sample_initial_state(c, pick(20, 2), torch.Generator().manual_seed(VALIDATION_SEED))
    end = rollout(LocalController(c), c, r_val, v_val).r[-1]
    degree = (pairwise_offsets(end)[2] <= c.R ** 2).sum(-1).double().mean().item()
    rows.append(f"| {rho:.2f} | {res.expert_cost.mean():.1f} | {res.cost.mean():.1f} | "
                f"{res.mean_ratio:.2f} | {degree:.1f} |")
display(Markdown("| rho [m] | expert cost | Local cost | Local / Centralized | Local: neighbours at the end |\n"
                 "|---|---|---|---|---|\n" + "\n".join(rows)))

# %% [markdown]
# The expert's cost rises with $\rho$, the local heuristic's far more (the table above). A wider repulsion pushes neighbours
# apart before they have aligned, links break, and agents that lose all neighbours keep their
# velocity for good: the local swarm disintegrates and its cost explodes. $\rho$ = 0.5 m puts the
# Local ratio near the paper's 4.13, so we take it as the default (`FlockConfig.rho`).
#
# ## 9. Exercises
#
# **Exercise 01.1: the potential's gradient.** Write $\nabla_{\mathbf r_i} U(\mathbf r_i, \mathbf r_j)$
# for the paper's potential (eq. 3) as a function of the offsets $\mathbf r_{ij} = \mathbf r_i - \mathbf r_j$,
# shape `(M, 2)`, returning `(M, 2)`. Hints: $\nabla \|\mathbf r\|^2 = 2\mathbf r$; beyond $\rho$
# the potential is constant. The check compares your function with the library's on fresh random
# offsets.

# %% [solution ex01-1]

def my_potential_gradient(r_ij, rho):
    ### BEGIN SOLUTION
    # HINT: differentiate through the squared distance by the chain rule, and remember that U is constant beyond rho.
    d2 = (r_ij ** 2).sum(dim=-1, keepdim=True)
    grad = -2 * r_ij / d2 ** 2 - 2 * r_ij / d2
    return torch.where(d2 <= rho ** 2, grad, torch.zeros_like(grad))
    ### END SOLUTION

# %% [check ex01-1]
from vgai_lite.lab.exercises import check_potential_gradient

assert check_potential_gradient(my_potential_gradient)

# %% [markdown]
# **Exercise 01.2: the flocking cost.** Write eq. 1 for a velocity trajectory `v` of shape
# `(T, B, N, 2)`, returning one cost per swarm, shape `(B,)`.

# %% [solution ex01-2]
def my_flocking_cost(v):
    ### BEGIN SOLUTION
    # HINT: eq. 1 sums over the steps how far, on average over the agents, each velocity is from the swarm's mean velocity.
    vbar = v.mean(dim=2, keepdim=True)
    return ((v - vbar) ** 2).sum(dim=-1).mean(dim=2).sum(dim=0)
    ### END SOLUTION

# %% [check ex01-2]
from vgai_lite.lab.exercises import check_flocking_cost

assert check_flocking_cost(my_flocking_cost)

# %%
prose("""## What we have, and what comes next

* A batched simulator (`step`, `rollout`), the paper's initial conditions, the expert and the local
  heuristic, and the relative cost with safety figures.
* The expert needs the whole swarm's velocities; the local heuristic uses only present one-hop
  information and pays for it (about {ratio:.1f}× the expert's cost on the working episodes above).""",
      ratio=res_local.mean_ratio)

# %% [markdown]
# ## Key takeaways
#
# * The swarm is a batch of double integrators; the expert (eq. 2) aligns every velocity with the whole swarm's mean and pushes drones apart within $\rho$ (eq. 3).
# * The paper's text and its reference code disagree on the initial disc and on the potential's sign: we follow the code for the disc (the text's disc cannot satisfy the paper's own constraints) and the text for the potential.
# * The relative cost compares a controller with the expert on the same initial conditions. Eq. 1 is blind to collisions and mostly spent in the first steps, so the book reports closest approaches and whether the swarm flocked beside every cost.
#
# ## Next
#
# [Notebook 02](02_graph_shift_operators.ipynb) introduces the communication graph and the **delayed aggregation sequence** that lets
# an agent hear, with delay, from agents several hops away. Notebook 03 measures what it buys: a
# learned controller on the same local features without any exchange already closes much of the
# gap between Local and the expert (learning a better local rule), and notebook 03 says, by its
# intervals and the spread between training seeds, what each exchange adds.
#
# ## References
#
# * Hu, Gama, Chen, Wang, Ribeiro, Sadler. *VGAI: End-to-End Learning of Vision-Based Decentralized Controllers for Robot Swarms.* ICASSP 2021 ([arXiv:2002.02308](https://arxiv.org/abs/2002.02308)): §3.1: the flocking problem, eq. 1's cost.
# * Tolstaya, Gama, Paulos, Pappas, Kumar, Ribeiro. *Learning Decentralized Controllers for Robot Swarms with Graph Neural Networks.* CoRL 2019 ([arXiv:1903.10527](https://arxiv.org/abs/1903.10527)): the expert controller and its potential (eqs. 2-3).

# %% [markdown]
# ## Your score
#
# The checks run so far in this session, for this notebook's exercises (an instructor's grader runs
# the same checks: `python -m vgai_lite grade`, see the README).

# %%
from vgai_lite.lab.exercises import score

score("01");

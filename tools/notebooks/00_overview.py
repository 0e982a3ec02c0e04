# %% [markdown]
# # 00 · VGAI, the book: a map
#
# This book teaches and reproduces **VGAI: End-to-End Learning of Vision-Based Decentralized
# Controllers for Robot Swarms** (Hu, Gama, Chen, Wang, Ribeiro, Sadler, CoRL 2020), on a laptop CPU.
#
# **The problem.** Fifty drones fly in a plane with random initial velocities. They must agree on a
# common velocity (*flock*) without colliding. A **centralized expert** that knows every drone's
# velocity solves this easily. But a real drone sees only what its camera sees and talks only to
# drones within a radius $R$. Can it learn to act almost as well as the expert?
#
# **The paper's answer** (its figure 1, in words): every drone
#
# 1. takes a picture of its surroundings, $\mathbf H_i(t)$ (four cameras, a 360° view);
# 2. compresses it with a small **CNN** into $F$ numbers, its *visual state* $\mathbf x_i(t)$;
# 3. exchanges those numbers with its neighbours, and relays what it heard before, so that after
#    $K-1$ exchanges it holds the **delayed aggregation sequence**
#    $\mathbf z_i(t) = [\mathbf x_i(t), [\mathbf S(t)\mathbf X(t-1)]_i, \dots]$, information from up to $K-1$ hops away;
# 4. feeds $\mathbf z_i(t)$ to a small **neural network** (the same weights on every drone) that outputs
#    its acceleration $\mathbf u_i(t)$.
#
# The CNN and the network are trained **together**, end to end, by **imitating the expert**
# (with DAgger), backpropagating through the $K$ steps of delayed exchanges.
#
# ## The notebooks
#
# | notebook | what it builds | paper |
# |---|---|---|
# | **01** flocking dynamics and the expert | double integrators, initial conditions, the cost, the centralized expert, the local heuristic, the relative cost | §3.1, Implementation Details |
# | **02** graph shift operators | the communication graph, GSOs, one-hop exchanges, the delayed aggregation sequence $\mathbf Z(t)$ | §3.2, eqs. 4-6 |
# | **03** aggregation GNN | a controller trained by imitation (DAgger) on exact local features: the paper's DAGNN baseline | §3.2, eqs. 7-11 |
# | **04** rendered observations | what a drone sees: top-down and 360° egocentric images from our own renderer, checked against a pymunk ray caster; 3-D views | Fig. 4 |
# | **05** the visual CNN | residual blocks, vertical-only pooling, $F$ features | §3.3, Fig. 2 |
# | **06** VGAI | CNN and DAGNN trained jointly, K-step backpropagation through time | §3.4, Fig. 3 |
# | **07** experiments | the paper's tables regenerated, the paper's numbers beside ours | §4 |
#
# Notebook 07's tables come from one command, `python -m vgai_lite reproduce` (its results ship in
# `data/results/`).
#
# ## How to use the book
#
# * **Read** it as it is: every notebook is committed with its outputs.
# * **Run** it: each notebook builds on `vgai_lite/`, a small library beside the notebooks, one
#   module per stage of the pipeline. When a notebook calls a function, open its file: the
#   docstring carries the equation and the shapes of every tensor, with the paper's symbols
#   ($\mathbf S$, $\mathbf X$, $\mathbf Z$, $K$, $F$, $R$, $\rho$).
# * **Exercises** end each notebook: you write a real piece of the method and an automatic check
#   tells you whether it is right, and if not, on which input it went wrong; the last cell gives
#   your score. Instructors: `python -m vgai_lite student-copies` writes copies without the
#   solutions and `python -m vgai_lite grade` scores a student's notebook (see the README).
# * **Quick mode.** Setting the environment variable `VGAI_LITE_QUICK=1` shrinks every loop (fewer
#   episodes, steps and epochs) so a notebook runs in seconds; the test suite runs the book this
#   way. The library reads the variable in one place, `vgai_lite/book.py`:

# %%
import torch

import vgai_lite
from vgai_lite.book import EVAL_SEED, QUICK, pick

print(f"vgai_lite {vgai_lite.__version__}, torch {torch.__version__}")
print("quick mode" if QUICK else "full mode", "-> episodes per evaluation:", pick(full=50, quick=8))

# %% [markdown]
# ## A first look
#
# One swarm, one initial condition, the expert at work for two seconds. Notebook 01 explains every
# piece of this cell.

# %%
import matplotlib.pyplot as plt

from vgai_lite import ExpertController, FlockConfig, rollout, sample_initial_state
from vgai_lite.viz import draw_swarm

cfg = FlockConfig()
r0, v0 = sample_initial_state(cfg, 1, torch.Generator().manual_seed(EVAL_SEED))
traj = rollout(ExpertController(cfg), cfg, r0, v0)

fig, axes = plt.subplots(1, 2, figsize=(10, 4.8))
for ax, t in zip(axes, (0, cfg.T - 1)):
    draw_swarm(ax, traj.r[t], traj.v[t], cfg)
    ax.set_title(f"t = {t * cfg.Ts:.2f} s")
fig.suptitle("The centralized expert: random velocities become one common velocity")
plt.tight_layout()
plt.show()

# %% [markdown]
# Next: **01 · Flocking: the dynamics, the expert and the local heuristic**.

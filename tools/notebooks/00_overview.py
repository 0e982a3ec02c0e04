# %% [markdown]
# # 00 · VGAI, the book: a map
#
# This book teaches and reproduces **VGAI: End-to-End Learning of Vision-Based Decentralized
# Controllers for Robot Swarms** (Hu, Gama, Chen, Wang, Ribeiro, Sadler; ICASSP 2021, on arXiv;
# the full text the book follows is set in the CoRL 2020 template), on a laptop CPU.
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
# (with DAgger), backpropagating through the $K$ steps of delayed exchanges. The same pipeline as a
# picture (drawn by `vgai_lite/lab/diagrams.py`):

# %%
import matplotlib.pyplot as plt

from vgai_lite.lab.diagrams import pipeline

pipeline()
plt.show()

# %% [markdown]
# ## Notation
#
# | symbol | meaning | in the code |
# |---|---|---|
# | $N$, $R$ | agents; communication radius: $i$ hears $j$ iff $\|\mathbf r_i - \mathbf r_j\| \le R$ | `FlockConfig.N`, `.R` |
# | $\mathbf r_i, \mathbf v_i, \mathbf u_i$ | position, velocity, acceleration of agent $i$, each in $\mathbb R^2$ | `r, v, u`, shape `(B, N, 2)` |
# | $T_s$, $T$ | sampling period; steps per episode | `FlockConfig.Ts`, `.T` |
# | $\rho$, $U$ | radius and potential of collision avoidance (eq. 3) | `FlockConfig.rho`, `controllers.potential` |
# | $\mathbf u^*_i$ | the centralized expert's action (eq. 2) | `controllers.expert_control` |
# | $\mathbf x_i(t) \in \mathbb R^F$, $\mathbf X(t)$ | agent $i$'s features (its *state*, eq. 4); all agents' as rows, $N \times F$ | `X`, shape `(B, N, F)` |
# | $F$ | features per agent: 6 exact ones for the DAGNN, $F$ learned ones for VGAI (paper default 24) | `VGAITrainConfig.F` |
# | $\mathbf S(t)$ | graph shift operator, $N \times N$, nonzero only between neighbours (eq. 5) | `graphs.gso` |
# | $K$ | **taps** of the aggregation sequence: $K-1$ **exchanges** with neighbours (the paper's tables give $K-1$) | `K` (default 4) |
# | $\mathbf Z(t)$, $\mathbf z_i(t)$ | delayed aggregation sequence, $N \times KF$ (eq. 6); its row $i$ | `aggregation.aggregation_sequence` |
# | $\mathrm{NN}_\Theta$ | the MLP from $\mathbf z_i(t)$ to $\mathbf u_i(t)$, the same on every agent (eqs. 7-8) | `models.AggregationMLP` |
# | $\mathbf H_i(t)$, $\mathrm{CNN}_\Psi$ | agent $i$'s images; the CNN from them to $\mathbf x_i(t)$ (section 3.3) | `vision.camera_input`, `models.VisualCNN` |
# | $g$, $F_m$ | the book's: frames $g$ steps apart give the CNN motion; $F_m$ of its features are odd in it | `VisionConfig.motion_gap`, `VisualCNN.motion_features` |
#
# ## Glossary: the book's own terms
#
# | term | meaning | where |
# |---|---|---|
# | **relative cost** | a controller's flocking cost (eq. 1) over the expert's on the same initial conditions (expert = 1.00) | 01, `evaluate.relative_cost` |
# | **flocked** | the book's one definition: a small velocity variance late in the flight (at 5 s) and the swarm still connected | 01, `evaluate.flocked` |
# | **validation / test episodes** | initial conditions drawn from two seeds: every choice (recipe, hyperparameter, training seed) is made on the validation episodes; the reported numbers come from the test episodes, which no choice has seen | 01, `book.VALIDATION_SEED`, `book.TEST_SEED` |
# | **working episodes** | a third seed's initial conditions, held out from training, on which the chapters draw their pictures and compare designs while they teach: not a test | 01, `book.WORKING_SEED` |
# | **repair sampling** | drawing initial positions for large teams by moving the agents that break a constraint instead of redrawing the whole swarm | 03 section 9, 07 (Table 3), `FlockConfig.init_method` |
# | **DAgger round** | fly swarms with the expert and the learner mixed, label every visited state with the expert's action, add them to the data, refit | 03, `imitation.dagger_mix` |
# | **the learner flying alone** | a share of each DAgger round's swarms flown by the learner at every step, so its own drift is in the data | 06, 11, `VGAITrainConfig.learner_swarms` |
# | **prehistory** | the frames before $t = 0$, drawn from the initial velocities flown backwards, so the first motion image is not empty | 05, `VisionConfig.prehistory` |
# | **odd motion features** | CNN features that change sign when the motion channel does, so they read zero when nothing moves | 05, 06, 11, `VisualCNN.motion_features` |
# | **stage 1 / 2 / 3** | the book's VGAI training: the CNN warm-started as a state estimator, the MLP fitted on its features, then both trained together by K-step BPTT | 06, `vgai_training.train_vgai` |
# | **modular vision pilot** | the CNN trained as a state estimator feeding the DAGNN's MLP, not trained end to end: the control experiment for VGAI | 09, 11 |
#
# ## The paper and this book
#
# Where we follow the paper and where we differ, and why. The book's column is read from the code's
# configuration objects, so it says what the code does:

# %%
from vgai_lite.lab import paper_vs_book

paper_vs_book.show()

# %% [markdown]
# ## The notebooks
#
# | notebook | what it builds | paper |
# |---|---|---|
# | [**01** flocking dynamics and the expert](01_flocking_dynamics_and_expert.ipynb) | double integrators, initial conditions, the cost, the centralized expert, the local heuristic, the relative cost | §3.1, Implementation Details |
# | [**02** graph shift operators](02_graph_shift_operators.ipynb) | the communication graph, GSOs, one-hop exchanges, the delayed aggregation sequence $\mathbf Z(t)$ | §3.2, eqs. 4-6 |
# | [**03** aggregation GNN](03_aggregation_gnn.ipynb) | a controller trained by imitation (DAgger) on exact local features: the paper's DAGNN baseline | §3.2, eqs. 7-10 |
# | [**04** rendered observations](04_rendered_observations.ipynb) | what a drone sees: top-down and 360° egocentric images from our own renderer, checked against a pymunk ray caster; 3-D views | Fig. 4 |
# | [**05** the visual CNN](05_visual_state_cnn.ipynb) | residual blocks, vertical-only pooling, $F$ features, visual state estimation | §3.3, Fig. 2 |
# | [**06** VGAI](06_vgai_joint_training.ipynb) | CNN and DAGNN trained jointly, K-step backpropagation through time, evaluated on the test episodes | §3.3-3.4, Fig. 3 |
# | [**07** experiments](07_experiments.ipynb) | the paper's tables regenerated, the paper's numbers beside ours | §4 |
# | [**08** robustness](08_robustness.ipynb) | no silent NaN; noisy and dead cameras, lost and late messages, larger teams; the camera VGAI is trained through | §4 and beyond |
# | [**09** results at a glance](09_results_at_a_glance.ipynb) | every controller on the test episodes; a fair comparison with the paper; what is still open | §4-5 |
# | [**10** appendix: Ray](10_appendix_ray.ipynb) | the reproduction as Ray tasks; the full run projected on several machines | beyond |
# | [**11** case study: what makes VGAI flock](11_what_makes_vgai_flock.ipynb) | the book's departures from the paper one at a time and left out in turn, against the spread between training seeds; the paper's VGAI as described | §3.3, beyond |
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
# * **Exercises** end each notebook from 01 to 08 (09, 10 and 11 sum up or analyse, and ask nothing): you write a real piece of the method (among them the GSO's
#   normalisation, DAgger's data aggregation and the K-step BPTT loss) and an automatic check
#   tells you whether it is right, and if not, on which input it went wrong and which mistake that
#   suggests; the open-ended experiments also ask for your written conclusion; the last cell gives
#   your score. Instructors: `python -m vgai_lite student-copies` writes copies without the
#   solutions and `python -m vgai_lite grade` scores a student's notebook; the exercise cells
#   carry nbgrader's metadata, so nbgrader generates and autogrades them too (see the README).
# * **Quick mode.** Setting the environment variable `VGAI_LITE_QUICK=1` shrinks every loop (fewer
#   episodes, steps and epochs) so a notebook runs in seconds; the test suite runs the book this
#   way. The library reads the variable in one place, `vgai_lite/book.py`:

# %%
import torch

import vgai_lite
from vgai_lite.book import WORKING_SEED, QUICK, pick

print(f"vgai_lite {vgai_lite.__version__}, torch {torch.__version__}")
print("quick mode" if QUICK else "full mode", "-> episodes per evaluation:", pick(full=50, quick=8))

# %% [markdown]
# ## A first look
#
# One swarm, one initial condition, the expert at work for two seconds. Notebook 01 explains every
# piece of this cell.

# %%
from vgai_lite import ExpertController, FlockConfig, rollout, sample_initial_state
from vgai_lite.viz import draw_swarm

cfg = FlockConfig()
r0, v0 = sample_initial_state(cfg, 1, torch.Generator().manual_seed(WORKING_SEED))
traj = rollout(ExpertController(cfg), cfg, r0, v0)

fig, axes = plt.subplots(1, 2, figsize=(10, 4.8))
for ax, t in zip(axes, (0, cfg.T - 1)):
    draw_swarm(ax, traj.r[t], traj.v[t], cfg)
    ax.set_title(f"t = {t * cfg.Ts:.2f} s")
fig.suptitle("The centralized expert: random velocities become one common velocity")
plt.tight_layout()
plt.show()

# %% [markdown]
# ## References
#
# * Hu, Gama, Chen, Wang, Ribeiro, Sadler. *VGAI: End-to-End Learning of Vision-Based Decentralized
#   Controllers for Robot Swarms.* ICASSP 2021 ([arXiv:2002.02308](https://arxiv.org/abs/2002.02308);
#   the text the book follows is set in the CoRL 2020 template); the authors' code:
#   [VITA-Group/VGAI](https://github.com/VITA-Group/VGAI). To cite it:
#
# ```bibtex
# @inproceedings{hu2021vgai,
#   title     = {{VGAI}: End-to-End Learning of Vision-Based Decentralized Controllers for Robot Swarms},
#   author    = {Hu, Ting-Kuei and Gama, Fernando and Chen, Tianlong and Wang, Zhangyang and
#                Ribeiro, Alejandro and Sadler, Brian M.},
#   booktitle = {IEEE International Conference on Acoustics, Speech and Signal Processing (ICASSP)},
#   year      = {2021},
#   eprint    = {2002.02308},
#   archivePrefix = {arXiv}
# }
# ```
#
# * Tolstaya, Gama, Paulos, Pappas, Kumar, Ribeiro. *Learning Decentralized Controllers for Robot
#   Swarms with Graph Neural Networks.* CoRL 2019 ([arXiv:1903.10527](https://arxiv.org/abs/1903.10527)):
#   the expert, the local features and the DAGNN; its environment:
#   [katetolstaya/gym-flock](https://github.com/katetolstaya/gym-flock).
# * Gama, Marques, Leus, Ribeiro. *Convolutional Neural Network Architectures for Signals Supported
#   on Graphs.* IEEE Transactions on Signal Processing, 2019 ([arXiv:1805.00165](https://arxiv.org/abs/1805.00165)):
#   aggregation graph neural networks; the authors' library:
#   [alelab-upenn/graph-neural-networks](https://github.com/alelab-upenn/graph-neural-networks).
# * Ross, Gordon, Bagnell. *A Reduction of Imitation Learning and Structured Prediction to No-Regret
#   Online Learning.* AISTATS 2011 ([arXiv:1011.0686](https://arxiv.org/abs/1011.0686)): DAgger.
# * He, Zhang, Ren, Sun. *Deep Residual Learning for Image Recognition.* CVPR 2016
#   ([arXiv:1512.03385](https://arxiv.org/abs/1512.03385)): the residual blocks of the CNN.
#
# ## Key takeaways
#
# * Flocking is velocity consensus without collisions; the expert solves it with everyone's
#   velocities, a drone has only its images and its neighbours' messages.
# * VGAI is a pipeline of three learned-or-fixed stages per drone: CNN (images to features),
#   delayed aggregation (features from up to $K-1$ hops), MLP (features to acceleration), trained
#   together by imitating the expert.
# * Where the paper is silent, the book chooses, says why, and keeps the choice in one config object.
#
# Next: [**01 · Flocking: the dynamics, the expert and the local heuristic**](01_flocking_dynamics_and_expert.ipynb).

# %% [markdown]
# # 02 · Graph shift operators and the delayed aggregation sequence
#
# *Paper: section 3.2, eqs. 4-6.*
#
# The expert of notebook 01 needs every drone's velocity. A real drone talks only to the drones
# within radius $R$. This notebook builds the language in which a decentralized controller is
# written:
#
# 1. the **communication graph** $\mathcal G(t)$ and its **graph shift operators** (GSOs) $\mathbf S(t)$;
# 2. why $\mathbf S\mathbf X$ costs exactly one exchange with one-hop neighbours;
# 3. $k$-hop neighbourhoods;
# 4. the **delayed aggregation sequence** $\mathbf Z(t)$ (eq. 6), how each drone builds it, and why
#    the information it holds is *late*.
#
# **Learning objectives.** After this notebook you can build the communication graph and its graph
# shift operators; show that S X needs one exchange with one-hop neighbours; say which information the
# delayed aggregation sequence holds, and how late.
#
# **You implement** the delayed aggregation sequence Z(t) of eq. 6 (exercise 02.1) and the symmetric
# normalised GSO (exercise 02.2); an automatic check tells you at once whether each is right, and the
# last cell gives your score.

# %%
import matplotlib.pyplot as plt
import numpy as np
import torch
from IPython.display import Markdown, display
from matplotlib.collections import LineCollection

from vgai_lite import ExpertController, FlockConfig, rollout, sample_initial_state
from vgai_lite.aggregation import AggregationBuffer, aggregation_sequence
from vgai_lite.book import WORKING_SEED, QUICK, pick, threads
from vgai_lite.graphs import GSO_KINDS, adjacency, gso, k_hop_reach
from vgai_lite.viz import draw_swarm

torch.set_num_threads(threads())  # 2, or VGAI_LITE_THREADS (vgai_lite.book)
cfg = FlockConfig()
r0, v0 = sample_initial_state(cfg, pick(20, 4), torch.Generator().manual_seed(WORKING_SEED))
print("quick mode" if QUICK else "full mode", f"| {len(r0)} swarms of N = {cfg.N}")

# %% [markdown]
# ## 1. The communication graph
#
# Agents $i$ and $j$ can talk at time $t$ iff $\|\mathbf r_i(t) - \mathbf r_j(t)\| \le R$. The graph
# changes as the drones move: $\mathcal G(t)$, $\mathcal N_i(t)$, $\mathbf S(t)$ all carry a time index.
# `adjacency(r, R)` returns the binary matrix $\mathbf A(t)$, shape `(B, N, N)`, without self-loops.

# %%
A = adjacency(r0, cfg.R)
deg = A.sum(-1)
fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
draw_swarm(axes[0], r0, cfg=cfg)
axes[0].set_title(f"the graph at t = 0: {int(A[0].sum()) // 2} links")
axes[1].hist(deg.flatten().numpy(), bins=np.arange(0, int(deg.max()) + 2) - 0.5, color="0.45")  # gray: no controller
axes[1].set_xlabel("number of neighbours |N_i|"), axes[1].set_ylabel("agents")
axes[1].set_title(f"degrees over {len(r0)} initial swarms (every agent has >= 2)")
plt.tight_layout()
plt.show()

# %% [markdown]
# ## 2. Graph shift operators
#
# A GSO is any matrix $\mathbf S(t)$ with $[\mathbf S(t)]_{ij} \neq 0$ only if $j$ is a neighbour of $i$
# (or $j = i$). The paper lists the adjacency, the Laplacian and their normalisations. With
# $\mathbf D = \operatorname{diag}(|\mathcal N_i|)$:
#
# | `kind` | $\mathbf S$ | spectrum | $[\mathbf S\mathbf X]_i$ is |
# |---|---|---|---|
# | `adjacency` | $\mathbf A$ | $[-d_{max}, d_{max}]$ | the **sum** of the neighbours' values |
# | `row_normalized` | $\mathbf D^{-1}\mathbf A$ | $[-1, 1]$ | the **mean** of the neighbours' values |
# | `sym_normalized` | $\mathbf D^{-1/2}\mathbf A\mathbf D^{-1/2}$ | $[-1, 1]$ | a degree-weighted sum |
# | `laplacian` | $\mathbf D - \mathbf A$ | $[0, 2 d_{max}]$ | $\sum_j (x_i - x_j)$: a local difference |
# | `spectral_normalized` | $\mathbf A / \lambda_{max}(\mathbf A)$ | $[-1, 1]$ | a sum scaled by a *global* number |
#
# The paper does not say which GSO its DAGNN uses; the public reference code averages
# (`row_normalized`, "mean pooling"). **Our default is `sym_normalized`**, chosen by measurement in
# notebook 03 (section 9, on validation episodes, where the verdicts are computed): summing
# (`adjacency`) lets the aggregated features grow with the number of neighbours, which matters in
# the denser teams of larger $N'$, and no other GSO costs less than the symmetric normalisation
# there. The normalised operators keep repeated shifts $\mathbf S^k\mathbf X$ bounded
# (spectrum in $[-1, 1]$); the plain adjacency does not. (`spectral_normalized` is as stable, but
# $\lambda_{max}$ is a property of the whole graph: no drone can compute it locally.)

# %%
fig, ax = plt.subplots(figsize=(8, 4))
for kind in GSO_KINDS:
    eig = torch.linalg.eigvals(gso(A[:1], kind)).real.sort().values[0]
    ax.plot(eig.numpy(), ".", ms=4, label=kind)
ax.set_xlabel("eigenvalue index (sorted)"), ax.set_ylabel("eigenvalue")
ax.set_yscale("symlog", linthresh=1)
ax.set_title("spectra of the five GSOs of one graph")
ax.legend()
plt.show()

# %% [markdown]
# ## 3. $\mathbf S\mathbf X$ is one round of exchanges
#
# Stack one feature vector per agent, row by row, in the state matrix
#
# \begin{equation*}
# \mathbf X(t) = \begin{bmatrix} \mathbf x_1^\top(t) \\ \vdots \\ \mathbf x_N^\top(t) \end{bmatrix} \in \mathbb R^{N\times F}. \tag{4}
# \end{equation*}
#
# Because $\mathbf S$ is zero off the graph,
#
# $$[\mathbf S(t)\mathbf X(t)]_{if} = \sum_{j\in\mathcal N_i(t)} s_{ij}(t)\,[\mathbf x_j(t)]_f \tag{5}$$
#
# for each feature $f$: agent $i$ needs only the values its neighbours send it. The matrix product is a *description* of
# what every drone computes in parallel from its own inbox. Let us check it for one agent, computing
# from its inbox only:

# %%
S = gso(A, "row_normalized")
X = v0  # any per-agent feature: here the velocities (F = 2)
i = 0
inbox = [(S[0, i, j], X[0, j]) for j in range(cfg.N) if A[0, i, j] > 0]  # messages agent i receives
from_inbox = sum(w * x for w, x in inbox)
print(f"agent {i} hears {len(inbox)} neighbours; [S X]_i from the matrix: {(S @ X)[0, i].tolist()}")
print(f"                       from its inbox alone:   {from_inbox.tolist()}")

# %%
fig, ax = plt.subplots(figsize=(5.5, 5.5))
draw_swarm(ax, r0, v0, cfg, color="0.6")
p = r0[0].numpy()
nbrs = A[0, i].bool().numpy()
ax.add_collection(LineCollection([(p[i], p[j]) for j in np.nonzero(nbrs)[0]], colors="tab:orange", lw=2))
ax.scatter(*p[nbrs].T, s=40, color="tab:orange", zorder=4, label="neighbours: they send x_j")
ax.scatter(*p[i], s=90, color="tab:red", marker="*", zorder=5, label=f"agent {i}: computes [S X]_i")
ax.add_patch(plt.Circle(p[i], cfg.R, fill=False, color="tab:red", ls="--"))
ax.legend(loc="lower left", fontsize=8)
ax.set_title("one exchange: every agent sends to the agents within R")
plt.show()

# %% [markdown]
# ## 4. $k$-hop neighbourhoods
#
# Repeating the exchange $k$ times spreads information $k$ hops: the support of row $i$ of
# $\mathbf S^k$ is the set of agents at most $k$ hops from $i$. A few hops cover much of the swarm:

# %%
fig, axes = plt.subplots(1, 4, figsize=(16, 4.2))
for k, ax in enumerate(axes):
    reach = k_hop_reach(A[:1], k)[0, i].numpy()
    ax.scatter(*p[~reach].T, s=10, color="0.75")
    ax.scatter(*p[reach].T, s=16, color="tab:blue")
    ax.scatter(*p[i], s=90, color="tab:red", marker="*")
    ax.set_aspect("equal"), ax.set_xticks([]), ax.set_yticks([])
    ax.set_title(f"within {k} hops of agent {i}: {reach.sum()} agents")
plt.tight_layout()
plt.show()
hops = torch.stack([k_hop_reach(A, k).double().sum(-1).mean() for k in range(6)])
print("mean number of agents within k hops, k = 0..5:", [round(h, 1) for h in hops.tolist()])

# %% [markdown]
# ## 5. The delayed aggregation sequence (eq. 6)
#
# A drone cannot do $K-1$ exchanges *instantly*: each exchange takes one time step, and the graph
# moves in between. So the paper builds, with $K$ taps,
#
# $$\mathbf Z(t) = \big[\mathbf X(t),\ \mathbf S(t)\mathbf X(t-1),\ \mathbf S(t)\mathbf S(t-1)\mathbf X(t-2),\ \dots,\ \mathbf S(t)\cdots\mathbf S(t-K+2)\,\mathbf X(t-K+1)\big] \in \mathbb R^{N\times KF}. \tag{6}$$
#
# Block $k$ holds what agents $k$ hops away measured $k$ steps ago. It obeys a one-step recursion,
# $\mathbf Z_k(t) = \mathbf S(t)\,\mathbf Z_{k-1}(t-1)$: at every step each agent sends its neighbours the
# first $K-1$ blocks it held at the previous step, and sums what it receives. That is all the
# communication there is: $(K-1)\cdot F$ numbers per agent per step.
#
# `vgai_lite.aggregation` implements eq. 6 twice: `AggregationBuffer` step by step (how a controller
# runs), and `aggregation_sequence` unrolled over a window (how training will backpropagate through
# it, notebook 06). They agree:

# %%
K, T = 4, 30
traj = rollout(ExpertController(cfg), cfg.replace(T=T), r0, v0)
S_seq = torch.stack([gso(adjacency(traj.r[t], cfg.R)) for t in range(T)], dim=1)  # (B, T, N, N)
X_seq = traj.v.transpose(0, 1)  # (B, T, N, 2): velocities as the features
buf = AggregationBuffer(K)
stepwise = torch.stack([buf.push(X_seq[:, t], S_seq[:, t]) for t in range(T)], dim=1)
unrolled = aggregation_sequence(X_seq, S_seq, K)
print("Z shape (B, T, N, K, F):", tuple(unrolled.shape))
print("largest difference between the two forms:", (stepwise - unrolled).abs().max().item())

# %% [markdown]
# **Information arrives late.** Give one agent $j$ a unit "ping" at $t = 0$ and nothing ever after;
# where does it show up in agent $i$'s sequence? In block $k$ at time $t = k$ only, and only if $j$ is
# exactly reachable in $k$ steps of the *time-varying* graph. A drone several hops away is heard a few
# steps late, and a drone too far away is never heard at all.

# %%
j_far = int(torch.nonzero(k_hop_reach(A[:1], 3)[0, i] & ~k_hop_reach(A[:1], 2)[0, i])[0])
ping = torch.zeros(1, T, cfg.N, 1)
ping[0, 0, j_far] = 1.0
Zp = aggregation_sequence(ping, S_seq[:1], K)[0, :8, i, :, 0]  # (t, k) for agent i
fig, ax = plt.subplots(figsize=(6, 3))
im = ax.imshow(Zp.T.numpy(), cmap="Blues", aspect="auto")
ax.set_xlabel("time step t"), ax.set_ylabel("block k of z_i(t)")
ax.set_title(f"a ping from agent {j_far} (3 hops away) reaches agent {i}")
fig.colorbar(im, ax=ax, label="weight")
plt.tight_layout()
plt.show()

# %% [markdown]
# The locality is a property of the construction, not of a trained network: the tests in
# `tests/test_graphs_aggregation.py` check it, including a simulation in which each agent keeps
# *only* the messages it received and still reproduces $\mathbf Z(t)$ exactly.
#
# **What it costs.** Each agent transmits $(K-1)\cdot F$ numbers per step. In float32:

# %%
rows = [f"| {F} | {K - 1} | {(K - 1) * F * 4} | {(K - 1) * F * 4 * 100 / 1000:.1f} |"
        for F in (6, 24) for K in (2, 3, 4)]
display(Markdown("| F | exchanges K-1 | bytes per agent per step | kB/s at 100 Hz |\n|---|---|---|---|\n" + "\n".join(rows)))

# %% [markdown]
# ## 6. Exercise 02.1: build $\mathbf Z(t)$ by hand
#
# Given the features `X` of shape `(T, N, F)` and the GSOs `S` of shape `(T, N, N)` of one swarm at
# times $0, \dots, T-1$ (nothing before $0$), return $\mathbf Z(T-1)$ of shape `(N, K, F)`, block
# $k$ being $\mathbf S(t)\mathbf S(t-1)\cdots\mathbf S(t-k+1)\mathbf X(t-k)$ (zero if $t - k < 0$).

# %% [solution ex02-1]
def my_aggregation_sequence(X, S, K):
    ### BEGIN SOLUTION
    # HINT: what an agent hears k exchanges late is k steps old, and it travelled through every graph since, the oldest first.
    T = X.shape[0]
    t = T - 1
    blocks = []
    for k in range(K):
        if t - k < 0:
            blocks.append(torch.zeros_like(X[0]))
            continue
        block = X[t - k]
        for s in range(t - k + 1, t + 1):  # apply S(t-k+1) first, S(t) last
            block = S[s] @ block
        blocks.append(block)
    return torch.stack(blocks, dim=1)
    ### END SOLUTION

# %% [check ex02-1]
from vgai_lite.lab.exercises import check_aggregation_sequence

assert check_aggregation_sequence(my_aggregation_sequence)

# %% [markdown]
# ## 7. Exercise 02.2: the symmetric normalised GSO
#
# Write the book's default graph shift operator for a batch of adjacency matrices `A` of shape
# `(B, N, N)` (0/1, symmetric, no self-loops): $\mathbf S = \mathbf D^{-1/2}\mathbf A\mathbf D^{-1/2}$
# with $\mathbf D$ the diagonal matrix of the degrees $d_i = \sum_j A_{ij}$, so that
# $S_{ij} = A_{ij} / \sqrt{d_i d_j}$. A drone with no neighbour ($d_i = 0$) hears nothing: its row and
# column of $\mathbf S$ are zero, and nothing in $\mathbf S$ may be NaN or infinite. The check feeds
# random graphs of mixed density, each with an isolated drone.

# %% [solution ex02-2]
def my_sym_gso(A):
    ### BEGIN SOLUTION
    # HINT: an isolated agent has degree 0: decide what 1/√d means there before you divide.
    d = A.sum(dim=-1)
    inv_sqrt = torch.where(d > 0, d.clamp(min=1).rsqrt(), torch.zeros_like(d))
    return inv_sqrt[..., :, None] * A * inv_sqrt[..., None, :]
    ### END SOLUTION

# %% [check ex02-2]
from vgai_lite.lab.method_exercises import check_sym_gso

assert check_sym_gso(my_sym_gso)

# %% [markdown]
# ## Key takeaways
#
# * A graph shift operator $\mathbf S(t)$ respects the communication graph, so $\mathbf S\mathbf X$ costs one exchange with one-hop neighbours (eq. 5).
# * The delayed aggregation sequence $\mathbf Z(t)$ (eq. 6) gathers information from up to $K-1$ hops, each hop one step older: local by construction.
# * The GSO's normalisation decides how aggregated features scale when the team gets denser.
#
# ## Next
#
# [Notebook 03](03_aggregation_gnn.ipynb) feeds $\mathbf z_i(t)$, built from six exact local features, to a small neural network
# shared by all agents, and trains it to imitate the expert: the paper's DAGNN baseline.
#
# ## References
#
# * Hu, Gama, Chen, Wang, Ribeiro, Sadler. *VGAI: End-to-End Learning of Vision-Based Decentralized Controllers for Robot Swarms.* ICASSP 2021 ([arXiv:2002.02308](https://arxiv.org/abs/2002.02308)): section 3.2: the delayed aggregation sequence, eq. 6.
# * Gama, Marques, Leus, Ribeiro. *Convolutional Neural Network Architectures for Signals Supported on Graphs.* IEEE Transactions on Signal Processing, 2019 ([arXiv:1805.00165](https://arxiv.org/abs/1805.00165)): aggregation graph neural networks.
# * Tolstaya, Gama, Paulos, Pappas, Kumar, Ribeiro. *Learning Decentralized Controllers for Robot Swarms with Graph Neural Networks.* CoRL 2019 ([arXiv:1903.10527](https://arxiv.org/abs/1903.10527)): the delayed aggregation in a swarm.

# %% [markdown]
# ## Your score
#
# The checks run so far in this session, for this notebook's exercises (an instructor's grader runs
# the same checks: `python -m vgai_lite grade`, see the README).

# %%
from vgai_lite.lab.exercises import score

score("02");

# %% [markdown]
# # 05 · The visual state estimator: a CNN that keeps the bearings
#
# *Paper: section 3.3 and figure 2.*
#
# In VGAI each drone compresses what it sees, $\mathbf H_i(t)$, into $F$ numbers,
# $\mathbf x_i(t) = \mathrm{CNN}_\Psi(\mathbf H_i(t))$, which it then exchanges with its neighbours
# exactly as the DAGNN exchanged its six exact features. The paper's CNN has **four residual blocks and
# two fully connected layers**, and one task-specific twist: it **pools only along the vertical
# axis**, because all the drones fly at the same height.
#
# This notebook: the architecture and its cost; why vertical-only pooling; what the CNN can learn
# from one frame and from two (visual state estimation); where it looks.
#
# **Learning objectives.** After this notebook you can explain the visual state estimator's
# architecture and cost; say why it pools along the vertical axis only; show what one frame and two
# frames can tell about neighbours.
#
# **You implement** a residual block with vertical-only pooling (exercise 05.1) and the
# state-estimation loss of stage 1 (exercise 05.3), and run an open-ended experiment with a
# convolution that wraps around the panorama (exercise 05.2); an automatic check tells you at once
# whether your code is right, and the last cell gives your score.

# %%
import time

import matplotlib.pyplot as plt
import torch
from IPython.display import Markdown, display

from vgai_lite import ExpertController, FlockConfig, load_controller, rollout, sample_initial_state
from vgai_lite.book import DATA_DIR, WORKING_SEED, QUICK, pick, prose, threads
from vgai_lite.features import FEATURE_NAMES, local_features
from vgai_lite.models import VisualCNN
from vgai_lite.render import CAMERAS
from vgai_lite.lab.runs import book_estimator
from vgai_lite.state_estimation import estimator_quality, train_state_estimator
from vgai_lite.vision import VisionConfig, stored_images

torch.set_num_threads(threads())  # 2, or VGAI_LITE_THREADS (vgai_lite.book)
cfg, vision = FlockConfig(), VisionConfig()
print("quick mode" if QUICK else "full mode")
print(vision)

# %% [markdown]
# The rows of notebook 00's paper-vs-book table that concern this notebook (read from the configs):

# %%
from vgai_lite.lab import paper_vs_book

paper_vs_book.show(["observation", "motion", "CNN", "training"])

# %% [markdown]
# ## 1. The input
#
# Each drone's CNN sees its 360° panorama from notebook 04 at a reduced **12 × 128** (four cameras of
# 12 × 32; the drones sit on the horizon and the depth channel already gives their distance, so half
# the rows cost half the compute and lose little), with two channels (gray, depth), paired with the
# frame of $g = 5$ steps earlier as $[\mathbf I(t),\ 5(\mathbf I(t) - \mathbf I(t-g))]$: 4 channels in all.
# Why two frames is the subject of section 3.

# %%
r0, v0 = sample_initial_state(cfg, pick(8, 2), torch.Generator().manual_seed(WORKING_SEED))
traj = rollout(ExpertController(cfg), cfg, r0, v0)
t = 10
img = stored_images(vision, cfg, traj.r, traj.v, torch.arange(len(r0)), torch.full((len(r0),), t))  # (B, N, 4, 12, 128)
print("CNN input of one swarm at t = 10:", tuple(img[0].shape), "(N, C, H, W)")
fig, axes = plt.subplots(4, 1, figsize=(12, 4.2))
rc = vision.render
for k, (ax, title) in enumerate(zip(axes, ("gray I(t)", "depth I(t)", "5 (gray difference)", "5 (depth difference)"))):
    shown = ax.imshow(img[0, 0, k], cmap="gray" if k < 2 else "RdBu", vmin=0 if k < 2 else -1, vmax=1, aspect="auto")
    ax.set_ylabel(title, rotation=0, ha="right", fontsize=9), ax.set_yticks([])
    ax.set_xticks([(c + 0.5) * rc.view_width for c in range(4)], CAMERAS if k == 3 else [])
    for c in range(1, 4):  # where one camera's view ends and the next begins
        ax.axvline(c * rc.view_width - 0.5, color="tab:orange", lw=0.8)
    fig.colorbar(shown, ax=ax, fraction=0.015, pad=0.01, label=("brightness", "depth code", "difference", "difference")[k])
plt.tight_layout()
plt.show()

# %% [markdown]
# ### What a real camera delivers
#
# The renderer draws the ideal frame. A camera delivers it through a lens, an exposure and a noisy
# sensor (`vgai_lite/camera.py`):
#
# $$\mathbf I_{\text{cam}} = \operatorname{clip}\big(a\,(G_b * \mathbf I) + c + \sigma\,\mathbf n,\ 0,\ 1\big),
# \qquad \mathbf n \sim \mathcal N(0, 1) \text{ per pixel and frame},$$
#
# with $G_b$ a Gaussian blur of $b$ degrees of view (so that a setting means the same at every
# resolution: a column here is 90°/32 = 2.8° wide on average, a row 5° tall), $a$ and $c$ the exposure's gain
# and offset, and a dead camera showing 0 on its quarter of the panorama. Exposure and sensor noise
# are photometric: they act on the gray channel. The book's depth channel $D = 0.2/d$ would come
# from a range sensor, whose error is a share $\varepsilon$ of the distance it measures:
#
# $$D_{\text{cam}} = \min\big(1,\ (G_b * D)\, e^{-\varepsilon\, n'}\big), \qquad n' \sim \mathcal N(0, 1) \text{ per pixel},$$
#
# and no return stays 0. (Adding $\sigma$ to $D$ as to an intensity would be a range error of
# $\sigma / D$: 50% at 2 m for $\sigma$ = 0.05, where a commodity depth camera errs by about 2%.) The noise of a frame is
# drawn from its own time, so the frame of $t - g$ that the motion channel pairs with the frame of
# $t$ is the one the drone really saw then. The authors' released test script (not the paper) flies their VGAI
# with $\sigma$ = 10/255 and a 5 × 5 box blur at 144 × 256, about 0.5°. Below, drone 0's front camera (gray channel
# and the motion channel) at a few settings: the motion channel is where the noise hurts, since it
# is a difference of two noisy frames, amplified by the same gain that makes the small motions
# readable. A training can draw these settings per flight (`VGAITrainConfig.camera`, a
# `CameraRanges`): the book's VGAI is trained that way (`BOOK_CAMERA`), and notebook 08 measures
# what it buys.

# %%
from vgai_lite.camera import Camera, CameraRanges
from vgai_lite.vision import camera_input, positions_before

sigmas, blurs = (0.0, 10 / 255, 0.05, 0.1), (0.0, 0.5, 1.4, 2.8)
e0, t0 = torch.tensor([0]), torch.tensor([t])
fig, axes = plt.subplots(len(sigmas), len(blurs), figsize=(12, 4.6))
for i, sigma in enumerate(sigmas):
    for j, blur in enumerate(blurs):
        cam = Camera(CameraRanges(noise=(sigma, sigma), blur_deg=(blur, blur)), vision.render, 1, cfg.N,
                     torch.Generator().manual_seed(0))
        seen = camera_input(vision, cfg, traj.r[t, e0], positions_before(vision, cfg, traj.r, traj.v, e0, t0),
                            cam.at(t))[0, 0]  # drone 0: (4, H, W)
        front = seen[:, :, :rc.view_width]
        axes[i, j].imshow(torch.cat((front[0], 0.5 + 0.5 * front[2].clamp(-1, 1)), dim=1), cmap="gray",
                          vmin=0, vmax=1, aspect="auto")
        axes[i, j].set_xticks([]), axes[i, j].set_yticks([])
        if i == 0:
            axes[i, j].set_title(f"blur {blur:g}°", fontsize=9)
        if j == 0:
            axes[i, j].set_ylabel(f"σ = {sigma:.3g}", fontsize=9)
fig.suptitle("drone 0's front camera: gray I(t) (left half) and the motion channel (right half, grey = 0)", fontsize=10)
plt.tight_layout()
plt.show()

# %% [markdown]
# ## 2. The architecture
#
# | stage | operation | output |
# |---|---|---|
# | stem | 3×3 convolution, 4 → 8 channels, stride 2 along rows only | 8 × 6 × 128 |
# | block 1 | residual block, 3×3, then average **all 6 rows** into one | 8 × 1 × 128 |
# | blocks 2-4 | residual blocks along the columns (1×3), 8 → 16 → 16 → 16 | 16 × 1 × 128 |
# | fc | 2048 → 64 → $F$ = 24 | 24 |
#
# A residual block is $y = \mathrm{pool}_{rows}(\mathrm{relu}(\mathrm{conv}_2(\mathrm{relu}(\mathrm{conv}_1(x))) + \mathrm{skip}(x)))$.
# Until the fully connected layers, column $k$ of every feature map still means "the bearing of
# column $k$".

# %%
C, H, W = vision.image_shape()
cnn = VisualCNN(C, H, W, F=24)
print(cnn)
n_params = sum(p.numel() for p in cnn.parameters() if p.requires_grad)
print(f"parameters: {n_params:,} (of which {24 * 6 + 6} in the warm-start head); "
      f"{cnn.flops_per_image() / 1e6:.1f} MFLOP per image")
x = torch.randn(pick(1600, 200), C, H, W)
t0 = time.perf_counter()
with torch.no_grad():
    cnn(x)
fwd = len(x) / (time.perf_counter() - t0)
t0 = time.perf_counter()
cnn(x).sum().backward()
fb = len(x) / (time.perf_counter() - t0)
print(f"throughput on this CPU: {fwd:,.0f} images/s forward, {fb:,.0f} images/s forward + backward")

# %% [markdown]
# **Why pool only along the vertical axis.** All drones fly at one altitude: in every image they
# sit on the horizon, and the vertical axis carries only how tall a drone looks, i.e. how near it is,
# which the rows can give up after one block. The horizontal axis is the bearing: where a neighbour
# is. Pooling columns would blur exactly the quantity the controller needs (the direction of the
# repulsion, the direction of a neighbour's motion), so the columns survive until the fully connected
# layers, whose weights can then be different for every bearing. A test checks the trunk's output:
# all rows pooled away, all 128 columns kept.

# %%
with torch.no_grad():
    maps = cnn.blocks[0](torch.relu(cnn.stem(img[0, :1])))  # block 1's output for agent 0
print("after block 1:", tuple(maps.shape), "-> one row per channel, 128 bearings")

# %% [markdown]
# ## 3. Visual state estimation
#
# What should $\mathbf x_i(t)$ contain? A good start is what the DAGNN used: the six exact local
# features (relative velocities and the two repulsion sums). We train the CNN, through a small linear
# head on its $F = 24$ outputs, to **regress the six features** from images of expert flights: the
# "visual state estimation" stage, and the first stage of VGAI's training in notebook 06.
#
# The book ships two estimators trained for 3,000 steps (8 swarm states, i.e. 400 images, per step)
# on 40 expert episodes: one sees **two frames** (the default), one a **single frame**. Regenerate
# them with `python -m vgai_lite train-vgai --estimators --retrain` (each one's time is printed below). In quick
# mode we also train a miniature one from scratch:

# %%
if QUICK:
    tiny, losses, sec = train_state_estimator(cfg.replace(T=20), vision, steps=3, states=1, episodes=1, progress=False)
    print(f"miniature estimator: {len(losses)} steps in {sec:.1f} s")

estimators = {"two frames (g = 5)": book_estimator("estimator_motion", progress=False),
              "single frame": book_estimator("estimator_single", progress=False)}
for name, (_, _, meta) in estimators.items():
    print(f"{name}: {meta['steps']} gradient steps in {meta['seconds'] / 60:.0f} min, on cores it may have shared (its "
          "record does not say; notebook 06 times the recipe's stage 1 alone)")

# %% [markdown]
# The two-frame estimator is exactly stage 1 of the VGAI with the paper's CNN, action loss and DAgger
# mixture but the book's sensor and warm starts (the same CNN, steps, states, episodes and seed: the
# first row of notebook 11's ablation (section 1), which is not the paper's VGAI: notebook 11 flies that one too, section 2).
# (The book's recipe changes stage 1 in three ways: synthetic relative velocities and odd motion
# features, which notebook 11 adds and measures one at a time, and the camera of notebook 08,
# through which it sees every frame.)

# %% [markdown]
# How well does each estimate each feature? Correlation with the exact features on held-out expert
# flights, at a few time steps:

# %%
rows = []
for name, (est, vis, _) in estimators.items():
    quality = estimator_quality(est, vis, cfg, episodes=pick(8, 2), seed=WORKING_SEED)
    for t, q in quality.items():
        rows.append(f"| {name} | {t} | " + " | ".join(f"{x:.2f}" for x in q) + " |")
display(Markdown("| estimator | step t | " + " | ".join(FEATURE_NAMES) + " |\n|---|---|" + "---|" * 6 + "\n" + "\n".join(rows)))

# %% [markdown]
# Read the table by columns. The repulsion features (where the neighbours are) are visible in a single
# frame, and both estimators get them almost exactly. The relative velocities
# $\sum_j (\mathbf v_i - \mathbf v_j)$ are another matter. A single frame cannot show motion, so the
# single-frame estimator can only *infer* velocities from the configuration: in an expert flight that
# becomes possible after a while (neighbours that came close are being pushed apart), but not at the
# start of an episode, exactly when the expert acts hardest and most of eq. 1 accrues. With two frames
# the motion of every neighbour is in the image from the first step (the frames before $t = 0$ are
# drawn from the initial state flown backwards, `VisionConfig.prehistory`), and the velocity features
# are estimated from the start. Later, as the swarm settles (and once it has flocked), relative
# velocities become tiny and hard to see in either case; they add little to eq. 1 then, but whether the swarm *stays*
# flocked depends on them (notebook 11).

# %%
est, vis, _ = estimators["two frames (g = 5)"]
t = 20
imgs = stored_images(vis, cfg, traj.r, traj.v, torch.arange(len(r0)), torch.full((len(r0),), t))
with torch.no_grad():
    pred = est.estimate_local_features(imgs.flatten(0, 1))
exact = local_features(traj.r[t], traj.v[t], cfg.R).flatten(0, 1)
fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
for ax, k in zip(axes, (0, 2, 4)):
    ax.scatter(exact[:, k], pred[:, k], s=5, alpha=0.5)
    lim = [exact[:, k].min().item(), exact[:, k].max().item()]
    ax.plot(lim, lim, color="0.5", lw=0.8)
    ax.set_xlabel(f"exact {FEATURE_NAMES[k]}"), ax.set_ylabel("estimated from images")
fig.suptitle(f"two-frame estimator at t = {t}, held-out expert flights")
plt.tight_layout()
plt.show()

# %% [markdown]
# ## 4. Where it looks
#
# The gradient of an estimated feature with respect to the input image shows which pixels it
# depends on (a saliency map). Below, for the relative-velocity feature $\sum_j (v_i - v_j)_x$, on
# all four channels; the sentence under the figure says how much of it lies in the columns that
# show a neighbour (a non-empty depth channel) and how much elsewhere.

# %%
agent = 0
x_img = imgs[0, agent:agent + 1].clone().requires_grad_(True)
est.estimate_local_features(x_img)[0, 0].backward()
sal = x_img.grad[0].abs()
fig, axes = plt.subplots(5, 1, figsize=(12, 5.5))
shown = axes[0].imshow(imgs[0, agent, 0], cmap="gray", vmin=0, vmax=1, aspect="auto")
axes[0].set_ylabel("gray", rotation=0, ha="right"), fig.colorbar(shown, ax=axes[0], fraction=0.015, pad=0.01, label="brightness")
for k, ax in enumerate(axes[1:]):
    shown = ax.imshow(sal[k], cmap="hot", aspect="auto", vmin=0, vmax=float(sal.max()))
    ax.set_ylabel(("gray", "depth", "Δ gray", "Δ depth")[k] + " saliency", rotation=0, ha="right", fontsize=9)
    fig.colorbar(shown, ax=ax, fraction=0.015, pad=0.01, label="|∂ feature / ∂ pixel|")
for k, ax in enumerate(axes):
    ax.set_yticks([]), ax.set_xticks([(c + 0.5) * vision.render.view_width for c in range(4)], CAMERAS if k == 4 else [])
    for c in range(1, 4):
        ax.axvline(c * vision.render.view_width - 0.5, color="tab:cyan", lw=0.6)
plt.tight_layout()
plt.show()
seen = imgs[0, agent, 1].amax(dim=0) > 0  # the columns whose depth channel shows a neighbour
on_seen = (sal[..., seen].sum() / sal.sum()).item()
display(prose("{share:.0%} of the saliency lies in the {cols:.0%} of the columns that show a neighbour: {verdict}. "
              "{diff:.0%} of it is on the two difference channels.", share=on_seen, cols=seen.float().mean().item(),
              verdict=("it gathers where the neighbours are" if on_seen > 2 * seen.float().mean().item() else
                       "it spreads well beyond the neighbours' columns, into empty view (the CNN's fully "
                       "connected layer sees every column)"),
              diff=(sal[2:].sum() / sal.sum()).item()))

# %% [markdown]
# ## 5. Exercise 05.1: a residual block that pools rows only
#
# Write `MyResidualBlock(c_in, c_out, pool)`: two 3×3 convolutions (padding 1) with a ReLU between,
# a skip connection (a 1×1 convolution when `c_in != c_out`), a ReLU, then average pooling of `pool`
# rows into one, leaving the columns untouched. Input `(M, c_in, H, W)`, output `(M, c_out, H / pool, W)`.

# %% [solution ex05-1]
from torch import nn



class MyResidualBlock(nn.Module):
    def __init__(self, c_in, c_out, pool):
        super().__init__()
        ### BEGIN SOLUTION
        # HINT: pool the rows only: the columns are bearings, and the CNN must keep every one.
        self.conv1 = nn.Conv2d(c_in, c_out, 3, padding=1)
        self.conv2 = nn.Conv2d(c_out, c_out, 3, padding=1)
        self.skip = nn.Conv2d(c_in, c_out, 1) if c_in != c_out else nn.Identity()
        self.pool = nn.AvgPool2d((pool, 1))
        ### END SOLUTION

    def forward(self, x):
        ### BEGIN SOLUTION
        # HINT: the skip path joins before the last ReLU, and the pooling comes last.
        y = self.conv2(torch.relu(self.conv1(x)))
        return self.pool(torch.relu(y + self.skip(x)))
        ### END SOLUTION

# %% [check ex05-1]
from vgai_lite.lab.method_exercises import check_residual_block

assert check_residual_block(MyResidualBlock)

# %% [markdown]
# ## 6. Exercise 05.2, an open-ended experiment: a panorama that wraps around
#
# The panorama is a circle: its last column sits right beside its first. The CNN's 1×3 convolutions
# along the columns pad with zeros at both ends, as if the world stopped at the seam behind the
# drone's left camera. Write `MyCircularConv(c_in, c_out)`, a 1×3 convolution along the columns whose
# padding wraps around; the check tests that rolling the panorama rolls its output exactly.

# %% [solution ex05-2]
from torch import nn



class MyCircularConv(nn.Module):
    def __init__(self, c_in, c_out):
        super().__init__()
        ### BEGIN SOLUTION
        # HINT: the panorama's first and last columns are neighbours; its top and bottom rows are not.
        self.conv = nn.Conv2d(c_in, c_out, (1, 3), padding=(0, 1), padding_mode="circular")
        ### END SOLUTION

    def forward(self, x):
        ### BEGIN SOLUTION
        return self.conv(x)
        ### END SOLUTION

# %% [check ex05-2]
from vgai_lite.lab.experiment_exercises import check_circular_conv

assert check_circular_conv(MyCircularConv)

# %% [markdown]
# **The experiment.** Turning the world by 180° rolls every panorama by half its width and negates
# all six local features (they are sums of vectors). A CNN that respects the panorama's circle would
# see that exactly: $\mathrm{est}(\text{roll}(\mathbf H)) = -\mathrm{est}(\mathbf H)$. No padding gives
# the estimator that symmetry by construction: circular padding makes the convolutional trunk roll
# exactly with the panorama, but the fully connected layers after it weigh every column with its
# own weights, so the symmetry, if any, is learned. The question is whether removing the seam
# helps the training learn it. Below, two
# estimators are trained the same short way (a few hundred steps, from the same seed), one with the
# book's zero padding and one whose column convolutions are your `MyCircularConv`, and each is scored
# on held-out expert flights: its correlation with the exact features and how far it is from that
# symmetry. Try more steps, the quarter turn (a roll by one camera, with x and y swapped and one of them negated), or the
# default VGAI's recipe; then decide whether the book should switch.

# %%
from vgai_lite.imitation import EpisodeStore
from vgai_lite.models import ResidualBlock
from vgai_lite.vgai_training import fit_state_estimator
from vgai_lite.vgai_config import VGAITrainConfig
from vgai_lite.lab.exercises import RESULTS

if not RESULTS.get("05.2"):
    print("The experiment runs once MyCircularConv above passes its check (exercise 05.2).")
else:
    steps = pick(400, 3)
    tc = VGAITrainConfig(F=24, motion_features=0, vision=vision, warm_steps=steps, warm_states=8)
    gen = torch.Generator().manual_seed(0)
    store = EpisodeStore()
    store.fly(None, cfg, *sample_initial_state(cfg, pick(20, 1), gen), 0.0, gen)
    flights = store.groups()  # the expert's flights, of one configuration (cfg)


    def circular(cnn):
        for block in cnn.blocks:
            if isinstance(block, ResidualBlock) and block.conv1.kernel_size == (1, 3):
                block.conv1 = MyCircularConv(block.conv1.in_channels, block.conv1.out_channels)
                block.conv2 = MyCircularConv(block.conv2.in_channels, block.conv2.out_channels)
        return cnn


    rows, measured, half = [], {}, vision.render.panorama_width // 2
    for label, make in (("zero padding (the book's)", lambda c: c), ("circular padding (yours)", circular)):
        torch.manual_seed(0)
        cnn = make(tc.new_model().cnn)
        t0 = time.perf_counter()
        fit_state_estimator(cnn, cfg, tc, flights, torch.Generator().manual_seed(1), progress=False)
        with torch.no_grad():
            est = cnn.estimate_local_features(imgs.flatten(0, 1))
            turned = cnn.estimate_local_features(torch.roll(imgs.flatten(0, 1), half, dims=-1))
        exact_now = local_features(traj.r[20], traj.v[20], cfg.R).flatten(0, 1)
        corr = [float(torch.corrcoef(torch.stack((est[:, k], exact_now[:, k])))[0, 1]) for k in range(6)]
        asym = float((turned + est).abs().mean() / est.abs().mean())
        rows.append(f"| {label} | {' | '.join(f'{c:.2f}' for c in corr)} | {asym:.3f} | {time.perf_counter() - t0:.0f} s |")
        measured[label] = (sum(corr) / len(corr), asym)
    display(Markdown("| estimator | " + " | ".join(FEATURE_NAMES) + " | distance from the 180° symmetry | training |\n"
                     "|---|" + "---|" * 8 + "\n" + "\n".join(rows)))
    (c0, a0), (c1, a1) = measured.values()
    display(prose("Read off this run: with circular padding the distance from the 180° symmetry {went} ({a0:.3f} → "
                  "{a1:.3f}) and the mean correlation with the exact features moved from {c0:.2f} to {c1:.2f}.",
                  went="fell" if a1 < a0 else "rose", a0=a0, a1=a1, c0=c0, c1=c1))

# %% [markdown]
# **Your conclusion (graded by the instructor).** Should the book's CNN switch to circular padding?
# Answer in a few sentences in the cell below, from your table and any run you add: what changed in
# the correlations and in the distance from the 180° symmetry, whether that difference is larger
# than what two trainings of the same estimator with different seeds would give, and what you would
# need to see before switching.

# %% [markdown answer ex05-2 2]
# *Model answer.* Compare the two rows column by column, as the reading under the table does (it is
# computed from the run, so it says which way this run went). Circular padding removes the seam
# from the convolutions only: the fully connected layers still weigh each column differently, so a
# turned world is not seen as its mirror image by construction, and the distance from the symmetry
# can move either way in one short training; the correlations move little, since the seam touches
# only the columns next to it. One short training per variant does not separate a small difference
# from training noise: the same
# estimator trained with another seed moves these numbers too, so a fair comparison repeats each
# variant over a few seeds (and at the full length of stage 1) and switches only if circular
# padding is better on average by more than the spread between seeds. It costs nothing at run time
# (the same convolutions, padded differently), so a switch needs only that evidence.

# %% [markdown]
# ## 7. Exercise 05.3: the state-estimation loss
#
# Stage 1 teaches the CNN to see: a linear head reads its features X and is scored against the six
# exact local features of each agent. Those features have very different sizes (a repulsion sum
# reaches hundreds, a velocity difference a few metres per second), so the head reads them
# *standardised*, each minus its mean over the training flights and divided by its spread. Write
# `my_estimation_loss(X, head, x_exact, mean, std)`: X (M, F), the head F → 6, x_exact (M, 6),
# mean and std (6,); return the L1 loss in standardised units, the mean over agents and features,
# differentiable down to X (the CNN learns through it). The library's `estimation_loss` is this loss;
# the check runs your function on random features of very different sizes.

# %% [solution ex05-3]
import torch.nn.functional as nnf


def my_estimation_loss(X, head, x_exact, mean, std):
    ### BEGIN SOLUTION
    # HINT: compare in the units the head reads, so that no feature drowns the others by its size alone.
    return nnf.l1_loss(head(X), (x_exact - mean) / std)
    ### END SOLUTION


# %% [check ex05-3]
from vgai_lite.lab.training_exercises import check_estimation_loss

assert check_estimation_loss(my_estimation_loss)

# %% [markdown]
# ## Key takeaways
#
# * The CNN pools rows only, so every column's bearing survives to its last layers.
# * Regressing the DAGNN's exact features (visual state estimation) shows what the CNN can see: relative positions well; relative velocities from the first step with two frames, and from a single frame only once the formation betrays them; small ones poorly either way.
#
# ## Next
#
# [Notebook 06](06_vgai_joint_training.ipynb) puts the CNN in front of the DAGNN's aggregation and trains both together, end to end,
# by imitation of the expert with K-step backpropagation through time.

# %% [markdown]
# ## References
#
# * Hu, Gama, Chen, Wang, Ribeiro, Sadler. *VGAI: End-to-End Learning of Vision-Based Decentralized Controllers for Robot Swarms.* ICASSP 2021 ([arXiv:2002.02308](https://arxiv.org/abs/2002.02308)): section 3.3 and figure 2: the CNN.
# * He, Zhang, Ren, Sun. *Deep Residual Learning for Image Recognition.* CVPR 2016 ([arXiv:1512.03385](https://arxiv.org/abs/1512.03385)): residual blocks.
#
# ## Your score
#
# The checks run so far in this session, for this notebook's exercises (an instructor's grader runs
# the same checks: `python -m vgai_lite grade`, see the README).

# %%
from vgai_lite.lab.exercises import score

score("05");

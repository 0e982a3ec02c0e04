# %% [markdown]
# # 04 · What a drone sees: rendered observations
#
# *Paper: figure 4 and its caption; "Implementation Details".*
#
# VGAI's drones do not know their neighbours' positions and velocities: they see them. In the paper
# each drone carries four AirSim cameras (front-centre, front-left, front-right, back) whose images
# are concatenated into one full field of view, and all drones fly at the same height. We cannot run
# AirSim on a laptop CPU, so the book renders its own images, from a camera model written out in
# `vgai_lite/render.py`, fast enough to train on, and checks them against an independent reference,
# the pymunk physics engine's ray caster.
#
# This notebook: the camera model; a drone's 360° panorama and its top-down alternative; motion in
# images; the pymunk cross-checks; a 3-D view of a flight; speed.
#
# **Learning objectives.** After this notebook you can render a drone's 360° panorama and its top-down
# alternative; relate a drone's bearing and distance to its column and apparent height; cross-check
# the renderer against pymunk's ray caster.
#
# **You implement** the pinhole model: the column and apparent height of a drone in the panorama
# (exercise 04.1); an automatic check tells you at once whether it is right, and the last cell gives
# your score.

# %%
import math
import time

import matplotlib.pyplot as plt
import numpy as np
import torch
from IPython.display import HTML, Markdown, display

from vgai_lite import ExpertController, FlockConfig, LocalController, rollout, sample_initial_state
from vgai_lite.book import WORKING_SEED, QUICK, pick, prose, threads
from vgai_lite.physics import raycast_depth, rollout_pymunk
from vgai_lite.render import (CAMERAS, RenderConfig, bearing_to_column, column_layers, egocentric_depth,
                              render_egocentric, render_topdown, with_motion)
from vgai_lite.vision import VisionConfig
from vgai_lite.viz import animate_views, animation_image, draw_swarm

torch.set_num_threads(threads())  # 2, or VGAI_LITE_THREADS (vgai_lite.book)
cfg = FlockConfig()
rcfg = VisionConfig().render  # exactly what VGAI's CNN sees (RenderConfig(), 12 x 32 per camera)
r0, v0 = sample_initial_state(cfg, pick(20, 3), torch.Generator().manual_seed(WORKING_SEED))
print("quick mode" if QUICK else "full mode")
print(rcfg)

# %% [markdown]
# The rows of notebook 00's paper-vs-book table that concern this notebook (read from the configs):

# %%
from vgai_lite.lab import paper_vs_book

paper_vs_book.show(["simulator", "observation", "motion"])

# %% [markdown]
# ## 1. The camera model
#
# Drones do not yaw in this problem, so the cameras' axes stay fixed to the world. Four pinhole
# cameras with a 90° horizontal field of view each cover the full circle, in the order **front
# (+x), right (−y), back (−x), left (+y)**. Within a camera, columns run left to right, i.e.
# clockwise seen from above. A point at angle $\phi$ to the right of camera $c$'s axis lands at the
# continuous column
#
# $$u = cW + \tfrac W2 + f\tan\phi, \qquad f = \frac{W/2}{\tan 45°} = \frac W2 \text{ pixels},$$
#
# and a body of height $h$ whose near side is at distance $t$ spans $2 f_v \frac{h/2}{t}$ rows around
# the horizon, with $f_v = \frac{H/2}{\tan(\text{vfov}/2)}$. Every drone is a small vertical cylinder
# (radius 5 cm, height 10 cm): its silhouette spans the bearings $\theta \pm \arcsin(\rho_b/d)$.

# %%
theta = torch.linspace(-math.pi, math.pi, 721, dtype=torch.float64)
u = bearing_to_column(theta, rcfg)
fig, ax = plt.subplots(figsize=(8, 3.2))
ax.plot(np.degrees(theta.numpy()), u.numpy(), ".", ms=2)
for c in range(1, 4):
    ax.axhline(c * rcfg.view_width, color="0.8", lw=0.8)
ax.set_xlabel("bearing θ [°] (counter-clockwise from +x)"), ax.set_ylabel("panorama column u")
ax.set_yticks([(c + 0.5) * rcfg.view_width for c in range(4)], CAMERAS)
ax.set_title("where a bearing lands in the panorama (tan-shaped within each 90° camera)")
plt.show()

# %% [markdown]
# ## 2. One drone's view
#
# The panorama (`render_egocentric`, shape `(B, N, C, H, 4W)`) has two channels by default: a
# camera-like **gray** image (sky, ground, drones darker the nearer they are) and a **depth**
# channel (0.2 m / distance on the drones, 0 elsewhere). `render_topdown` is the simpler
# alternative: a bird's-eye crop centred on the drone, north up, covering ±R.

# %%
agent = 0
img = render_egocentric(r0, cfg, rcfg)[0, agent]
crop = render_topdown(r0, cfg, rcfg)[0, agent, 0]
fig = plt.figure(figsize=(14, 6.5))
ax = fig.add_axes([0.0, 0.05, 0.3, 0.9])
draw_swarm(ax, r0, cfg=cfg, links=False)
p = r0[0, agent].numpy()
for c, ang in enumerate((0, -90, 180, 90)):  # camera axes
    a = math.radians(ang)
    ax.annotate(CAMERAS[c], p + 0.9 * np.array([math.cos(a), math.sin(a)]), color="tab:orange", ha="center")
    for edge in (a - math.pi / 4, a + math.pi / 4):
        ax.plot(*zip(p, p + 3 * np.array([math.cos(edge), math.sin(edge)])), color="tab:orange", lw=0.5)
ax.scatter(*p, s=120, marker="*", color="tab:red", zorder=5)
ax.set_title(f"agent {agent} (star) and its cameras' boundaries")
for k, (ch, cmap) in enumerate((("gray", "gray"), ("depth", "magma"))):
    axi = fig.add_axes([0.33, 0.66 - 0.3 * k, 0.65, 0.26])
    im = axi.imshow(img[k], cmap=cmap, vmin=0, vmax=1)
    fig.colorbar(im, ax=axi, fraction=0.02, pad=0.01, label=("brightness" if ch == "gray" else "depth code"))
    axi.set_xticks([(c + 0.5) * rcfg.view_width for c in range(4)], CAMERAS if k else []), axi.set_yticks([])
    for c in range(1, 4):
        axi.axvline(c * rcfg.view_width - 0.5, color="tab:orange", lw=0.8)
    axi.set_title(f"{ch} channel ({rcfg.view_height} x {rcfg.panorama_width})", fontsize=10)
axt = fig.add_axes([0.33, 0.0, 0.2, 0.24])
axt.imshow(crop, cmap="gray_r", vmin=0, vmax=1), axt.set_xticks([]), axt.set_yticks([])
axt.set_title("top-down crop (±R)", fontsize=10)
plt.show()

# %% [markdown]
# Three properties are tested in `tests/test_render_physics.py`: a single drone at bearing $\theta$ and
# distance $d$ appears in the right camera with exactly the silhouette edges, width and height the
# pinhole model predicts; a nearer drone hides a farther one; and no agent sees itself. A few numbers
# for the drone above:

# %%
layers = column_layers(r0[:1], rcfg)
visible = (layers.cover1[0, agent] > 0).sum().item()
print(f"columns showing some drone: {visible} of {rcfg.panorama_width}")
d = (r0[0] - r0[0, agent]).norm(dim=-1)
d[agent] = math.inf
print(f"nearest neighbour {d.min():.2f} m away: about {2 * rcfg.focal * rcfg.body_radius / d.min():.1f} columns wide, "
      f"{2 * rcfg.focal_vertical * rcfg.body_height / 2 / (d.min() - rcfg.body_radius):.1f} rows tall")

# %% [markdown]
# **Anti-aliasing.** Bodies are small: a neighbour at the communication radius (1.5 m) is about one
# column wide. A renderer that snapped bodies to whole pixels would make them jump between columns
# and hide slow motion. Ours computes the exact share of each column (and row) a body covers: in
# 0.01 s a neighbour 1 m away moving sideways at 3 m/s shifts by about half a column, and the image
# changes accordingly.
#
# ## 3. Motion
#
# One frame shows where the neighbours are, not how fast they move, and the expert's action is
# dominated by velocity alignment. `with_motion` stacks a frame with an earlier one, or with the
# scaled difference of the two (the book's choice); notebook 05 measures what the second frame buys
# (one frame against two).

# %%
gap = 5
traj = rollout(LocalController(cfg), cfg.replace(T=20), r0[:1], v0[:1])
now = render_egocentric(traj.r[gap * 2], cfg, rcfg)[0, agent]
before = render_egocentric(traj.r[gap], cfg, rcfg)[0, agent]
pair_img = with_motion(now, before, mode="difference", scale=5.0)
fig, axes = plt.subplots(3, 1, figsize=(12, 5.5))
for ax, im, title, kw in ((axes[0], now[0], f"I(t), t = {gap * 2} steps", dict(cmap="gray", vmin=0, vmax=1)),
                          (axes[1], before[0], f"I(t - {gap})", dict(cmap="gray", vmin=0, vmax=1)),
                          (axes[2], pair_img[2], "5 (I(t) - I(t-g)), gray channel", dict(cmap="RdBu", vmin=-1, vmax=1))):
    shown = ax.imshow(im, **kw)
    ax.set_title(title, fontsize=10), ax.set_yticks([])
    ax.set_xticks([(c + 0.5) * rcfg.view_width for c in range(4)], CAMERAS if ax is axes[2] else [])
    for c in range(1, 4):
        ax.axvline(c * rcfg.view_width - 0.5, color="tab:orange", lw=0.8)
    fig.colorbar(shown, ax=ax, fraction=0.02, pad=0.01, label="difference" if ax is axes[2] else "brightness")
plt.tight_layout()
plt.show()

# %% [markdown]
# ## 4. pymunk, the independent reference
#
# **Ray casting.** pymunk knows nothing of our camera model's code. We place a circle body of the
# drones' radius at every drone, and for every agent and panorama column cast one ray
# (`segment_query_first`) along the column's centre bearing, computed from the pinhole formula
# written out separately in `physics.column_bearings`, with the agent's own `ShapeFilter` group so
# its rays ignore its own body. Our renderer's depth strip (`egocentric_depth`) must agree:

# %%
errors, hits, t_py, t_ours = [], 0, 0.0, 0.0
for b in range(len(r0)):
    r64 = r0[b:b + 1].double()
    t0 = time.perf_counter()
    ref = raycast_depth(r64[0], rcfg)
    t_py += time.perf_counter() - t0
    t0 = time.perf_counter()
    ours = egocentric_depth(r64, rcfg)[0].numpy()
    t_ours += time.perf_counter() - t0
    assert np.array_equal(np.isfinite(ref), np.isfinite(ours)), "the two disagree on which columns hit a drone"
    hit = np.isfinite(ref)
    hits += hit.sum()
    errors.append(np.abs(ref[hit] - ours[hit]))
errors = np.concatenate(errors)
print(f"{len(r0)} swarms x {cfg.N} agents x {rcfg.panorama_width} columns: {hits} rays hit a drone in both; "
      f"the same columns hit, largest depth difference {errors.max():.1e} m")
print(f"time: pymunk {t_py:.2f} s, torch {t_ours:.3f} s")

fig, ax = plt.subplots(figsize=(10, 3))
ax.plot(ref[agent], "o", ms=5, mfc="none", label="pymunk ray cast")
ax.plot(ours[agent], ".", ms=4, label="render.egocentric_depth")
ax.set_yscale("log"), ax.set_xlabel("panorama column"), ax.set_ylabel("depth [m]")
ax.set_title(f"agent {agent}'s depth strip in the last swarm (gaps: rays that hit nothing)"), ax.legend()
plt.show()

# %% [markdown]
# **Physics.** The same world can fly a whole episode: each drone is a unit-mass disc, the commanded
# acceleration becomes a force, and pymunk resolves contacts between bodies (two drones touch when
# their centres are closer than 10 cm: two body radii; notebook 01 reports this share beside the
# 0.05 m it calls a crash, bodies half into each other). Without contacts the flight
# matches our simulator's `step` exactly (a test checks it to 1e-9 m); with contacts, pymunk counts
# them. Drones that do not steer at all collide, of course:

# %%
rows, touching, with_contact = [], {}, {}
no_control = lambda r, v: torch.zeros_like(r)  # every drone keeps its initial velocity
for name, ctrl in (("Centralized", ExpertController(cfg)), ("Local", LocalController(cfg)), ("none (u = 0)", no_control)):
    contacts, gaps = [], []
    traj = rollout(ctrl, cfg, r0.double(), v0.double())
    touching[name] = int((traj.min_distance.min(0).values < 2 * rcfg.body_radius).sum())
    for b in range(len(r0)):
        ref = rollout_pymunk(ctrl, cfg, r0[b].double().numpy(), v0[b].double().numpy(), rcfg=rcfg)
        contacts.append(ref.contacts)
        if ref.contacts == 0:
            gaps.append(np.abs(ref.r - traj.r[:, b].numpy()).max())
    contacts = np.array(contacts)
    with_contact[name] = int((contacts > 0).sum())
    gap = f"{max(gaps):.1e}" if gaps else "— (every episode had a contact)"
    rows.append(f"| {name} | {(contacts > 0).mean():.0%} | {contacts.sum()} | {gap} |")
display(Markdown("| controller | episodes with a contact | contacts in all | largest position gap to `step` without contact [m] |\n"
                 "|---|---|---|---|\n" + "\n".join(rows)))

# %% [markdown]
# **Close calls, measured two ways.** The same episodes as the table above, by our simulator's
# closest approaches (a pair closer than two body radii: the bodies touch) against pymunk's contacts:

# %%
E, d = len(r0), 2 * rcfg.body_radius
agree = all(touching[n] == with_contact[n] for n in touching)
prose("In these {E} episodes (the first {E} of the working episodes; notebook 01's close calls fall among its others) the expert brings a pair closer than {d:g} m in {k} of them by our simulator's "
      "closest approaches, and pymunk counts a contact in {c}. {verdict}",
      E=E, d=d, k=touching["Centralized"], c=with_contact["Centralized"],
      verdict=("They differ for some controller: pymunk resolves a contact inside a step, while the simulator "
               "reads distances at the sampling instants only." if not agree else
               "The two agree for every controller; under the expert no pair's bodies touch in these episodes "
               "(the table above counts the others' contacts)."
               if touching["Centralized"] == 0 else
               "The two agree for every controller: these are real contacts, which notebook 01 counts among "
               "its close calls."))

# %% [markdown]
# ## 5. A flight in 3-D
#
# meshcat draws the swarm at a common altitude, with each drone's trail and the communication links
# of the last frame. The view below is a standalone page (no server, no network): drag to rotate,
# and use "Open Controls" → Animations to replay.

# %%
from vgai_lite.lab.viz3d import iframe, swarm_scene_html

flight = rollout(ExpertController(cfg), cfg, r0[:1], v0[:1])
scene = swarm_scene_html(flight, cfg, every=pick(4, 50))
HTML(iframe(scene, height=420))

# %% [markdown]
# And the same kind of flight seen by one drone: its panorama and top-down crop beside the swarm.

# %%
anim = animate_views(flight, cfg, rcfg, agent=agent, every=pick(8, 100))
animation_image(anim)

# %% [markdown]
# ## 6. Speed
#
# Training a CNN on images rendered on the fly needs a fast renderer. Agent-images per second for
# 64 swarms of 50 drones at the default resolution (`python -m vgai_lite benchmark` prints the same
# with longer timing):

# %%
from vgai_lite.lab.benchmark import run_render

for row in run_render(swarms=pick(64, 4), min_seconds=pick(1.0, 0.1)):
    print(f"{row['renderer']:32s} {row['agent_images_per_s']:10,.0f} agent-images/s")

# %% [markdown]
# The renderer never loops over agents or pixels in Python: for every pair of drones it finds the
# few columns the farther one touches, keeps the two nearest bodies per column, and composites each
# column's rows in one vectorised pass.

# %% [markdown]
# ## 7. A worked example, then exercise 04.1
#
# A drone 1.5 m away, 20° to the left of straight ahead ($\theta$ = 20°, counter-clockwise from +x).
# The front camera looks along +x and covers $\theta \in [-45°, 45°]$, so it sees the drone. Columns
# run clockwise, so the angle to the right of the camera's axis is $\phi = -\theta$, and the
# continuous column is $u = 0 \cdot W + W/2 + f\tan\phi$ (camera 0, the front). The body's near side
# is $d - $ `body_radius` away, which sets its apparent height. Step by step, against the library:

# %%
theta, d = math.radians(20), 1.5
phi = -theta                                     # to the right of the front camera's axis
u = 0 * rcfg.view_width + rcfg.view_width / 2 + rcfg.focal * math.tan(phi)
height = 2 * rcfg.focal_vertical * (rcfg.body_height / 2) / (d - rcfg.body_radius)
print(f"focal length f = {rcfg.focal:.1f} px, so u = {rcfg.view_width / 2:.1f} + {rcfg.focal:.1f} × tan({math.degrees(phi):.0f}°)"
      f" = {u:.3f}; the library: {bearing_to_column(torch.tensor(theta), rcfg).item():.3f}")
print(f"apparent height = 2 × {rcfg.focal_vertical:.1f} × {rcfg.body_height / 2} / ({d} - {rcfg.body_radius}) = {height:.2f} rows")

# %% [markdown]
# The exercise does this for every bearing, so it must first find which of the four cameras sees
# the drone (front, right, back, left, clockwise from the front camera's left edge at +45°).
#
# **Exercise 04.1: the pinhole model.**
#
# Write `my_pinhole(theta, d, rcfg)` returning `(u, height)`: the continuous panorama column of a
# drone at bearing `theta` (radians, counter-clockwise from +x) and centre distance `d`, and its
# apparent height in rows (the centre ray meets its near side at `d - rcfg.body_radius`). Use
# `rcfg.view_width`, `rcfg.focal`, `rcfg.focal_vertical` and `rcfg.body_height`.

# %% [solution ex04-1]
def my_pinhole(theta, d, rcfg):
    ### BEGIN SOLUTION
    # HINT: first find which of the four 90° cameras sees the bearing; the column follows from the angle off that camera's axis.
    psi = (math.pi / 4 - theta) % (2 * math.pi)  # clockwise from the front camera's left edge
    cam = min(int(psi // (math.pi / 2)), 3)
    phi = psi - cam * math.pi / 2 - math.pi / 4  # angle to the right of camera cam's axis
    u = cam * rcfg.view_width + rcfg.view_width / 2 + rcfg.focal * math.tan(phi)
    height = 2 * rcfg.focal_vertical * (rcfg.body_height / 2) / (d - rcfg.body_radius)
    return u, height
    ### END SOLUTION

# %% [check ex04-1]
from vgai_lite.lab.exercises import check_pinhole

assert check_pinhole(my_pinhole)

# %% [markdown]
# ## Key takeaways
#
# * A drone sees its neighbours as bodies in a 360° panorama of four pinhole cameras; our renderer is batched in torch and checked against a pymunk ray caster.
# * An image carries bearings (columns) and distances (the depth channel); velocities show only across frames.
#
# ## Next
#
# [Notebook 05](05_visual_state_cnn.ipynb) builds the paper's visual state estimator: a CNN with residual blocks that pools only
# along the vertical axis, so that the bearing of every drone in these panoramas survives to its
# last layers.

# %% [markdown]
# ## References
#
# * Hu, Gama, Chen, Wang, Ribeiro, Sadler. *VGAI: End-to-End Learning of Vision-Based Decentralized Controllers for Robot Swarms.* ICASSP 2021 ([arXiv:2002.02308](https://arxiv.org/abs/2002.02308)): Fig. 4 (the drones' four cameras, in the implementation details of §3.4).
# * pymunk, a 2D physics library ([pymunk.org](https://www.pymunk.org)): the reference physics and ray caster.

# %% [markdown]
# ## Your score
#
# The checks run so far in this session, for this notebook's exercises (an instructor's grader runs
# the same checks: `python -m vgai_lite grade`, see the README).

# %%
from vgai_lite.lab.exercises import score

score("04");

"""What a drone sees (notebook 04): pinhole geometry of the panorama, occlusion, anti-aliasing,
the top-down crop, the pymunk ray caster and rigid-body reference, and the meshcat view."""

import base64
import math
import re
import subprocess

import numpy as np
import pytest
import torch

from vgai_lite import ExpertController, FlockConfig, rollout, sample_initial_state
from vgai_lite.physics import raycast_depth, rollout_pymunk
from vgai_lite.render import (RenderConfig, bearing_to_column, column_layers, column_to_bearing,
                              egocentric_depth, render_egocentric, render_topdown, with_motion)

CFG = FlockConfig()
RC = RenderConfig(channels=("gray", "depth"))


def pair(theta, d):
    """Agent 0 at the origin, agent 1 at bearing theta, distance d: r (1, 2, 2) float64."""
    return torch.tensor([[[0.0, 0.0], [d * math.cos(theta), d * math.sin(theta)]]], dtype=torch.float64)


def pinhole(theta, d, rc=RC):
    """Expected camera, centre column and apparent size from the pinhole model, written out."""
    psi = (math.pi / 4 - theta) % (2 * math.pi)  # clockwise from the front camera's left edge
    cam = min(int(psi // (math.pi / 2)), 3)
    phi = psi - cam * math.pi / 2 - math.pi / 4  # angle to the right of that camera's axis
    W, f = rc.view_width, rc.view_width / 2
    alpha = math.asin(rc.body_radius / d)
    left, right = f * math.tan(phi - alpha), f * math.tan(phi + alpha)
    t = d - rc.body_radius  # the centre ray meets the cylinder's near side
    height = 2 * rc.focal_vertical * (rc.body_height / 2) / t
    return cam, cam * W + W / 2 + left, cam * W + W / 2 + right, height


@pytest.mark.parametrize("theta_deg, d", [(0, 1.0), (20, 0.6), (-70, 1.4), (100, 0.8), (180, 1.3), (-125, 1.2)])
def test_a_single_drone_appears_where_the_pinhole_model_says(theta_deg, d):
    theta = math.radians(theta_deg)
    r = pair(theta, d)
    layers = column_layers(r, RC)
    cover = layers.cover1[0, 0]  # agent 0: share of each panorama column the drone covers
    cam, u_left, u_right, height = pinhole(theta, d)
    assert int(cover.argmax()) // RC.view_width == cam                      # the right camera
    seen = torch.nonzero(cover).flatten()
    k_l, k_r = int(seen[0]), int(seen[-1])
    assert k_r > k_l                                                         # (spans 2+ columns here)
    assert abs((k_l + 1 - cover[k_l]) - u_left) < 1e-9                       # left edge, sub-column
    assert abs((k_r + cover[k_r]) - u_right) < 1e-9                          # right edge, sub-column
    assert abs(cover.sum() - (u_right - u_left)) < 1e-9                      # apparent width
    # in the rendered depth channel, the centre column's rows: vertical coverage of each row
    centre = int(cover.argmax())
    depth_img = render_egocentric(r, CFG, RC)[0, 0, 1]
    full = cover[centre] * min(1.0, RC.depth_scale / layers.depth1[0, 0, centre].item())
    rows = depth_img[:, centre] / full
    assert abs(rows.sum() - height) < 0.03 * height                          # apparent height
    assert torch.allclose(rows, rows.flip(0))                                # centred on the horizon


def test_apparent_size_shrinks_with_distance():
    widths = [render_egocentric(pair(0.0, d), CFG, RC)[0, 0, 1].amax(0).gt(0).sum().item() for d in (0.3, 0.6, 1.2)]
    assert widths[0] > widths[1] > widths[2]


def test_bearing_and_column_maps_invert_each_other():
    theta = torch.linspace(-math.pi + 1e-6, math.pi - 1e-6, 1000, dtype=torch.float64)
    torch.testing.assert_close(column_to_bearing(bearing_to_column(theta, RC), RC), theta)
    u = torch.linspace(0, RC.panorama_width - 1e-6, 1000, dtype=torch.float64)
    torch.testing.assert_close(bearing_to_column(column_to_bearing(u, RC), RC), u)


def test_a_nearer_drone_occludes_a_farther_one():
    r = torch.tensor([[[0.0, 0.0], [0.6, 0.0], [2.0, 0.0]]], dtype=torch.float64)
    depth = egocentric_depth(r, RC)[0, 0]
    front = depth[RC.view_width // 2 - 1: RC.view_width // 2 + 1]  # the two columns around +x
    assert (front < 0.6).all()                                       # the near drone is what they see
    alone = egocentric_depth(r[:, [0, 2]], RC)[0, 0]
    assert (alone[RC.view_width // 2 - 1: RC.view_width // 2 + 1] > 1.9).all()  # the far one, unblocked


def test_no_agent_sees_itself():
    far = pair(0.3, 1e4)  # the only other drone is out of sight (far below a pixel)
    img = render_egocentric(far, CFG, RC)[0, 0]
    assert img[1].max() < 1e-3                            # no body anywhere in the depth channel
    assert torch.isinf(egocentric_depth(far, RC)[0, 0]).all()


def test_anti_aliasing_shows_sub_column_motion():
    a = render_egocentric(pair(0.3, 1.0), CFG, RC)
    b = render_egocentric(pair(0.3 + 0.25 / RC.focal * 0.5, 1.0), CFG, RC)  # about an eighth of a column
    assert (a - b).abs().max() > 0.01


@pytest.mark.parametrize("renderer", [render_egocentric, render_topdown])
def test_renderers_are_permutation_equivariant(renderer):
    r, _ = sample_initial_state(CFG, 2, torch.Generator().manual_seed(0), dtype=torch.float64)
    perm = torch.randperm(CFG.N, generator=torch.Generator().manual_seed(1))
    torch.testing.assert_close(renderer(r[:, perm], CFG, RC), renderer(r, CFG, RC)[:, perm])


def test_topdown_draws_discs_of_the_body_radius_where_they_are():
    rc = RenderConfig(topdown_size=64, topdown_half_width=1.0, body_radius=0.1)
    img = render_topdown(pair(0.0, 0.5), CFG, rc)[0, 0, 0]  # agent 0's crop
    px = 2 * 1.0 / 64
    assert abs(img.sum() - math.pi * (0.1 / px) ** 2 * 1.5) < 2.0  # a full disc + a half-intensity self
    assert img[32, 32 + int(0.5 / px)] == 1.0                      # the neighbour, east of the centre
    assert img[31:33, 31:33].max() == 0.5                          # the agent itself, marked
    assert img[: 32 - 5].sum() == 0                                # nothing north


def test_motion_option_stacks_or_differences_frames():
    a, b = torch.rand(2, 3, 2, 4, 8), torch.rand(2, 3, 2, 4, 8)
    assert with_motion(a, b, "stack").shape == (2, 3, 4, 4, 8)
    torch.testing.assert_close(with_motion(a, b, "difference", scale=2.0)[:, :, 2:], 2.0 * (a - b))
    with pytest.raises(ValueError, match="mode"):
        with_motion(a, b, "blend")


def test_pymunk_ray_caster_agrees_with_the_rendered_depth():
    r, _ = sample_initial_state(CFG, 3, torch.Generator().manual_seed(5), dtype=torch.float64)
    ours = egocentric_depth(r, RC).numpy()
    for b in range(3):
        ref = raycast_depth(r[b], RC)
        assert np.array_equal(np.isfinite(ref), np.isfinite(ours[b]))       # same columns hit
        hit = np.isfinite(ref)
        assert hit.sum() > 1000
        assert np.abs(ref[hit] - ours[b][hit]).max() < 1e-6                 # same distances


def test_pymunk_rollout_matches_step_without_contacts_and_counts_contacts():
    cfg = CFG.replace(T=120)
    r, v = sample_initial_state(cfg, 6, torch.Generator().manual_seed(0), dtype=torch.float64)
    traj = rollout(ExpertController(cfg), cfg, r, v)
    checked = 0
    for b in range(6):
        ref = rollout_pymunk(ExpertController(cfg), cfg, r[b].numpy(), v[b].numpy(), rcfg=RC)
        touched = traj.min_distance[:, b].min().item() < 2 * RC.body_radius
        if not touched:
            assert ref.contacts == 0
            assert np.abs(ref.r - traj.r[:, b].numpy()).max() < 1e-9
            checked += 1
    assert checked >= 3
    # drones flying head-on with no controller collide, and pymunk counts it
    r2 = np.array([[0.0, 0.0], [1.0, 0.0]])
    v2 = np.array([[2.0, 0.0], [-2.0, 0.0]])
    ref = rollout_pymunk(lambda r, v: torch.zeros_like(r), cfg.replace(N=2, T=50, min_neighbours=1), r2, v2, rcfg=RC)
    assert ref.contacts == 1 and np.abs(ref.r[-1, 0, 0] - ref.r[-1, 1, 0]) >= 2 * RC.body_radius - 5e-3


def _meshcat_servers():
    out = subprocess.run(["ps", "-eo", "args"], capture_output=True, text=True).stdout
    return [line for line in out.splitlines() if "meshcat.servers" in line]


def test_meshcat_view_is_standalone_html_and_leaves_no_server_behind():
    from vgai_lite.lab.viz3d import swarm_scene_html

    cfg = CFG.replace(N=8, T=20)
    r, v = sample_initial_state(cfg, 1, torch.Generator().manual_seed(0))
    before = len(_meshcat_servers())
    html = swarm_scene_html(rollout(ExpertController(cfg), cfg, r, v), cfg, every=5)
    assert html.lstrip().lower().startswith("<!doctype html")
    scene = b"".join(base64.b64decode(chunk) for chunk in re.findall(r"base64,([A-Za-z0-9+/=]+)", html))
    assert b"drone_007" in scene and b"set_animation" in scene  # the scene and its animation are inlined
    assert "MeshCat.Viewer" in html and 'src="http' not in html   # the viewer too: nothing to fetch
    assert len(_meshcat_servers()) == before


def test_drawing_each_drones_nearest_is_the_full_renderer_on_those_drones():
    """RenderConfig.nearest: a team larger than the book's draws, for each drone, exactly what the
    full renderer draws of a swarm made of that drone and its ``nearest`` nearest drones."""
    cfg = FlockConfig(N=60)
    r, _ = sample_initial_state(cfg, 2, torch.Generator().manual_seed(1), dtype=torch.float64)
    k = 12
    culled = render_egocentric(r, cfg, RenderConfig(nearest=k))
    full = render_egocentric(r, cfg, RC)
    assert culled.shape == full.shape
    assert not torch.allclose(culled, full)  # the farther drones were drawn by the full renderer
    for b, i in ((0, 0), (0, 37), (1, 59)):
        d = (r[b] - r[b, i]).norm(dim=-1)
        d[i] = math.inf
        keep = torch.cat((torch.tensor([i]), d.argsort()[:k]))
        alone = render_egocentric(r[b, keep][None], cfg, RC)[0, 0]
        assert torch.allclose(culled[b, i], alone, atol=1e-12)


def test_drawing_the_nearest_changes_nothing_when_they_are_every_drone():
    r, _ = sample_initial_state(CFG, 3, torch.Generator().manual_seed(2), dtype=torch.float64)
    full = render_egocentric(r, CFG, RC)
    for k in (CFG.N - 1, CFG.N + 10):
        assert torch.equal(render_egocentric(r, CFG, RenderConfig(nearest=k)), full)


@pytest.mark.parametrize("bad", [0, -3, 2.5, True, "49"])
def test_nearest_must_be_a_whole_number_of_drones(bad):
    with pytest.raises(ValueError, match="nearest must be a whole number"):
        RenderConfig(nearest=bad)

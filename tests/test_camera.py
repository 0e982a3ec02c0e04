"""The camera model (camera.py): what a real camera does to the rendered frame, and a training that sees
through it."""

import dataclasses
import math

import pytest
import torch

from vgai_lite import FlockConfig, VGAIController, rollout, sample_initial_state
from vgai_lite.camera import (Camera, CameraRanges, blur_degrees, dead_camera, degrees_per_pixel, draw_camera,
                              sensor_noise)
from vgai_lite.models import AggregationMLP, VGAIModel, VisualCNN
from vgai_lite.render import RenderConfig, render_egocentric
from vgai_lite.vgai_config import VGAITrainConfig
from vgai_lite.vgai_training import train_vgai
from vgai_lite.vision import VisionConfig

CFG = FlockConfig(N=12)


def _frames(render=RenderConfig(), B=2, seed=0):
    r, _ = sample_initial_state(CFG, B, torch.Generator().manual_seed(seed))
    return render_egocentric(r, CFG, render)


def test_sensor_noise_has_the_standard_deviation_asked_and_stays_in_the_sensors_range():
    img = torch.full((4, 12, 2, 12, 128), 0.5)
    noisy = sensor_noise(img, 0.05, torch.Generator().manual_seed(0))
    assert abs(float((noisy - img).std()) - 0.05) < 0.002 and abs(float((noisy - img).mean())) < 0.002
    assert sensor_noise(torch.zeros(3, 4), 0.3, torch.Generator().manual_seed(0)).min() == 0  # clipped, not negative
    per_swarm = sensor_noise(img, torch.tensor([0.0, 0.1, 0.0, 0.02]), torch.Generator().manual_seed(0))
    assert torch.equal(per_swarm[0], img[0]) and abs(float((per_swarm[1] - img[1]).std()) - 0.1) < 0.005


def test_a_frame_keeps_its_noise_when_seen_again_and_frames_differ():
    """The frame of t - g, paired with the frame of t, is the very frame the drone saw at t - g."""
    cam = Camera(CameraRanges(noise=(0.05, 0.05)), RenderConfig(), 2, CFG.N, torch.Generator().manual_seed(1))
    img = _frames()
    seen_then = cam.at(10)(img, 0)       # at step 10, the frame of now
    seen_later = cam.at(15)(img, 5)      # at step 15, the frame of 5 steps before
    assert torch.equal(seen_then, seen_later)
    assert not torch.equal(cam.at(11)(img, 0), seen_then)  # another frame: other noise


def test_blur_in_degrees_means_the_same_at_every_resolution():
    """A point of light blurred by 2° spreads over 2° of view at 32 and at 64 columns per camera."""
    spreads = []
    for width in (32, 64):
        render = RenderConfig(view_height=12, view_width=width)
        img = torch.zeros(1, 1, 1, 12, 4 * width)
        img[..., 6, 2 * width] = 1.0
        row = blur_degrees(img, 2.0, render)[0, 0, 0, 6]
        cols = torch.arange(4 * width, dtype=torch.float32) * degrees_per_pixel(render)[0]
        mean = (row * cols).sum() / row.sum()
        spreads.append(float(((row * (cols - mean) ** 2).sum() / row.sum()).sqrt()))
    assert spreads[0] == pytest.approx(2.0, rel=0.05) and spreads[1] == pytest.approx(2.0, rel=0.05)
    img = _frames()
    assert torch.equal(blur_degrees(img, 0.0, RenderConfig()), img)  # no blur: the frame itself


def test_a_dead_camera_blacks_out_exactly_its_quarter_of_the_panorama():
    img = torch.rand(2, 3, 2, 12, 128) + 0.1
    dead = torch.tensor([[0, -1, 3], [2, 2, -1]])
    out = dead_camera(img, dead)
    for b in range(2):
        for n in range(3):
            black = (out[b, n] == 0).all(dim=(0, 1))
            want = torch.zeros(128, dtype=torch.bool)
            if dead[b, n] >= 0:
                want[32 * dead[b, n]:32 * (dead[b, n] + 1)] = True
            assert torch.equal(black, want)


def test_camera_ranges_refuse_what_no_camera_does():
    with pytest.raises(ValueError, match="noise"):
        CameraRanges(noise=(0.1, 0.05))
    with pytest.raises(ValueError, match="dead_share"):
        CameraRanges(dead_share=1.5)
    assert draw_camera(CameraRanges(), RenderConfig(), 2, 5, torch.Generator()) is None  # the ideal camera: no draw


def test_a_controller_with_a_camera_sees_its_noise_and_without_one_the_clean_frames():
    vision = VisionConfig(render=RenderConfig(view_height=8, view_width=16))
    C, H, W = vision.image_shape()
    torch.manual_seed(0)
    c = VGAIController(VGAIModel(VisualCNN(C, H, W, 6, (4, 8), 16), AggregationMLP(3, 6, (16,))).eval(), CFG, vision)
    cfg = CFG.replace(T=6)
    r0, v0 = sample_initial_state(cfg, 2, torch.Generator().manual_seed(3))
    clean = rollout(c, cfg, r0, v0).u
    c.camera = Camera(CameraRanges(noise=(0.1, 0.1)), vision.render, 2, cfg.N, torch.Generator().manual_seed(4))
    noisy = rollout(c, cfg, r0, v0).u
    again = rollout(c, cfg, r0, v0).u
    assert not torch.allclose(noisy, clean) and torch.equal(noisy, again)  # seeded: a flight is reproducible


def test_a_training_through_the_camera_runs_every_stage_and_returns_a_clean_eyed_controller():
    vision = VisionConfig(render=RenderConfig(view_height=8, view_width=16))
    tcfg = VGAITrainConfig(F=6, K=3, hidden=(8,), cnn_widths=(2, 4), cnn_hidden=8, vision=vision, warm_starts=True,
                           expert_episodes=2, dagger_rounds=1, episodes_per_round=2, warm_steps=2, warm_states=1,
                           mlp_epochs=1, joint_steps=2, windows=2, early_steps=10,
                           camera=CameraRanges(noise=(0.0, 0.1), blur_deg=(0.0, 2.0), gain=(0.8, 1.2),
                                               offset=(-0.1, 0.1), dead_share=0.2))
    cfg = FlockConfig(N=10, T=15)
    ctrl, hist = train_vgai(cfg, tcfg, progress=False, check_episodes=1)
    clean, _ = train_vgai(cfg, dataclasses.replace(tcfg, camera=CameraRanges()), progress=False, check_episodes=1)
    assert ctrl.camera is None and VGAITrainConfig.from_dict(ctrl.meta["train_config"]) == tcfg
    assert hist["warm_loss"] != clean.meta["history"]["warm_loss"]  # stage 1 saw other images


def test_exposure_and_sensor_noise_touch_the_intensity_and_a_depth_channel_errs_in_proportion_to_distance():
    """A depth camera: photometric noise and exposure act on "gray" only; the depth channel's error is a
    share of the distance (D = depth_scale / d, so D exp(-share n)), and the sky gives no return."""
    render = RenderConfig()
    img = _frames(render)                                              # (B, N, [gray, depth], H, W)
    gen = lambda: torch.Generator().manual_seed(0)  # noqa: E731
    noisy = sensor_noise(img, 0.05, gen(), render.channels)
    assert torch.equal(noisy[:, :, 1], img[:, :, 1]) and not torch.equal(noisy[:, :, 0], img[:, :, 0])
    assert torch.equal(sensor_noise(img[:, :, :1], 0.05, gen(), ("gray",)), sensor_noise(img[:, :, :1], 0.05, gen()))
    cam = Camera(CameraRanges(gain=(1.2, 1.2), offset=(0.05, 0.05), depth_noise=(0.03, 0.03)), render, 2, CFG.N,
                 torch.Generator().manual_seed(2))
    seen = cam.frame(img, 7)
    assert torch.allclose(seen[:, :, 0], (1.2 * img[:, :, 0] + 0.05).clamp(0, 1))
    D, Dc = img[:, :, 1], seen[:, :, 1]
    body = (D > 0) & (D < 0.5)                                         # bodies, below the channel's cap
    assert body.sum() > 100 and torch.equal(Dc[D == 0], D[D == 0])
    rel = torch.log(D[body] / Dc[body])
    assert abs(float(rel.std()) - 0.03) < 0.005 and abs(float(rel.mean())) < 0.005
    with pytest.raises(ValueError, match="channels"):
        sensor_noise(img, 0.05, gen(), ("gray",))


def test_cameras_without_a_range_error_draw_what_they_drew_before_it_existed():
    """Trainings through a camera recorded before ``depth_noise``: the same settings, the same frames."""
    ranges = CameraRanges(noise=(0.0, 0.1), blur_deg=(0.0, 2.0), dead_share=0.3)
    a = Camera(ranges, RenderConfig(), 3, CFG.N, torch.Generator().manual_seed(5))
    g = torch.Generator().manual_seed(5)
    noise, blur = torch.rand(3, generator=g) * 0.1, torch.rand(3, generator=g) * 2.0
    assert torch.equal(a.noise, noise) and torch.equal(a.blur_deg, blur) and torch.equal(a.depth_noise, torch.zeros(3))


def test_the_papers_rgb_camera_tells_how_far_a_body_is_from_how_much_of_a_pixel_it_fills():
    """RGB, the paper's sensor (``render.PALETTE``): each colour channel shows the gray channel's scene in its
    own colours, gray is the same whether colour is rendered beside it or not, and the camera's exposure and
    noise act on every colour channel (not on depth). The point of colour: in gray, a near body filling little
    of a pixel and a farther one filling more can give the same value; in colour, one pixel's three values
    give both the coverage a and the fog f = exp(-d / fog_distance), hence the distance d."""
    from vgai_lite.render import PALETTE
    render = RenderConfig(channels=("red", "green", "blue", "gray", "depth"))
    img = _frames(render)
    assert torch.equal(img[:, :, 3:4], _frames(RenderConfig(channels=("gray",))))
    assert torch.equal(img[:, :, 3:], _frames(RenderConfig()))
    H, W = render.view_height, render.view_width
    row = H // 2 - 1                                                   # the sky's side of the horizon
    y = (row + 0.5 - H / 2) / (H / 2)
    sky, top_row = torch.tensor([PALETTE[c][0] + PALETTE[c][1] * y for c in ("red", "green", "blue")]), 0
    assert torch.allclose(img[:, :, :3, top_row].amax(-1).amax((0, 1)),
                          torch.tensor([PALETTE[c][0] - PALETTE[c][1] * (1 - 1 / H) for c in ("red", "green", "blue")]))
    horizon = torch.tensor([PALETTE[c][4] for c in ("red", "green", "blue")])
    body = torch.tensor([PALETTE[c][5] for c in ("red", "green", "blue")])
    A = torch.stack((horizon - sky, body - horizon), dim=1)           # p - sky = a (horizon - sky) + a f (body - horizon)
    for d, shift in ((0.6, 0.3), (1.0, 0.5), (1.7, 0.45), (3.0, 0.6)):
        theta = -math.atan(shift / render.focal)                       # within column W/2 of the front camera
        r = torch.tensor([[[0.0, 0.0], [d * math.cos(theta), d * math.sin(theta)]]])
        p = render_egocentric(r, CFG, render)[0, 0, :3, row, W // 2]
        a, af = torch.linalg.lstsq(A, (p - sky)[:, None]).solution.flatten()
        assert 0.05 < float(a) <= 1.0
        d_seen = -render.fog_distance * math.log(float(af / a))
        assert abs(d_seen - (d - render.body_radius)) < 0.02, (d, d_seen)
    # in gray, coverage and fog trade off: two (a, f) with one gray value, told apart in colour
    g = PALETTE["gray"]
    g_sky, g_h, g_b = g[0] + g[1] * y, g[4], g[5]
    a1, f1, f2 = 0.5, 0.9, 0.6
    p1 = a1 * (g_h - g_sky) + a1 * f1 * (g_b - g_h)
    a2 = p1 / ((g_h - g_sky) + f2 * (g_b - g_h))
    assert 0 < a2 <= 1
    c1, c2 = a1 * A[:, 0] + a1 * f1 * A[:, 1], a2 * A[:, 0] + a2 * f2 * A[:, 1]
    assert float((c1 - c2).abs().max()) > 0.01   # a few hundredths: fog is a weak cue, next to a noise of 0.05
    gen = lambda: torch.Generator().manual_seed(0)  # noqa: E731
    noisy = sensor_noise(img, 0.05, gen(), render.channels)
    assert all(not torch.equal(noisy[:, :, c], img[:, :, c]) for c in range(4))
    assert torch.equal(noisy[:, :, 4], img[:, :, 4])
    seen = Camera(CameraRanges(gain=(1.2, 1.2)), render, 2, CFG.N, torch.Generator().manual_seed(2)).frame(img, 3)
    assert torch.allclose(seen[:, :, :4], (1.2 * img[:, :, :4]).clamp(0, 1)) and torch.equal(seen[:, :, 4], img[:, :, 4])

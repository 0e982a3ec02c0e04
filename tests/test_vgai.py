"""VGAI (sections 3.3-3.4): the CNN's vertical-only pooling, pure vision, locality, any N, checkpoints."""

import pytest
import torch

from vgai_lite import FlockConfig, rollout, sample_initial_state
from vgai_lite.checkpoints import load_controller, save_controller
from vgai_lite.models import (AggregationMLP, ResidualBlock, VGAIController, VGAIModel, VisionConfig,
                              VisualCNN)
from vgai_lite.render import RenderConfig

CFG = FlockConfig(N=20)
VISION = VisionConfig(render=RenderConfig(view_height=8, view_width=16))


def make_vgai(cfg=CFG, vision=VISION, F=6, K=3, seed=0):
    torch.manual_seed(seed)
    C, H, W = vision.image_shape(cfg)
    model = VGAIModel(VisualCNN(C, H, W, F, (4, 8), 16), AggregationMLP(K, F, (16,))).double().eval()
    return VGAIController(model, cfg, vision)


def test_residual_block_pools_rows_only():
    block = ResidualBlock(3, 5, (3, 3), pool=4)
    assert block(torch.randn(2, 3, 8, 40)).shape == (2, 5, 2, 40)


def test_the_cnn_keeps_every_column_until_the_fully_connected_layers():
    cnn = VisualCNN(4, 12, 128, F=24)
    trunk = cnn.blocks(torch.relu(cnn.stem(torch.randn(3, 4, 12, 128))))
    assert trunk.shape == (3, 16, 1, 128)          # all rows pooled away, all 128 bearings kept
    assert cnn(torch.randn(3, 4, 12, 128)).shape == (3, 24)
    assert cnn.flops_per_image() > 0
    with pytest.raises(ValueError, match="expects images"):
        cnn(torch.randn(3, 4, 12, 64))


def test_vgai_sees_only_images_not_velocities():
    c = make_vgai()
    r, v = sample_initial_state(CFG, 2, torch.Generator().manual_seed(0), dtype=torch.float64)
    c.reset()
    u1 = c(r, v)
    c.reset()
    u2 = c(r, torch.randn_like(v) * 10)
    torch.testing.assert_close(u1, u2)


def test_vgai_is_permutation_equivariant_over_a_rollout():
    c = make_vgai()
    cfg = CFG.replace(T=8)
    r, v = sample_initial_state(cfg, 2, torch.Generator().manual_seed(1), dtype=torch.float64)
    perm = torch.randperm(cfg.N, generator=torch.Generator().manual_seed(2))
    a = rollout(c, cfg, r, v)
    b = rollout(c, cfg, r[:, perm], v[:, perm])
    torch.testing.assert_close(b.u, a.u[:, :, perm])


def test_vgai_flies_any_team_size_and_round_trips_through_a_checkpoint(tmp_path):
    c = make_vgai()
    c.model.float()
    path = save_controller(tmp_path / "v.pt", c, meta={"x": 1})
    c2 = load_controller(path)
    assert c2.vision == VISION and c2.meta == {"x": 1}
    for N in (20, 35):
        cfg = CFG.replace(N=N, T=6)
        c.cfg = c2.cfg = cfg
        r, v = sample_initial_state(cfg, 2, torch.Generator().manual_seed(0))
        torch.testing.assert_close(rollout(c2, cfg, r, v).u, rollout(c, cfg, r, v).u)


def test_motion_frames_change_the_input_only_when_something_moves():
    vision = VISION
    c = make_vgai(vision=vision)
    r, _ = sample_initial_state(CFG, 1, torch.Generator().manual_seed(0), dtype=torch.float64)
    c.reset()
    for _ in range(vision.motion_gap + 1):
        X_still = c.features(r)
    C0 = len(vision.render.channels)
    img = vision.combine(vision.frame(r, CFG), vision.frame(r, CFG))
    assert img.shape[2] == 2 * C0 and img[:, :, C0:].abs().max() == 0  # difference channels empty
    shifted = c.features(r + 0.5)  # the whole swarm translated: every view, hence X, is the same
    torch.testing.assert_close(shifted, X_still)
    moved = r.clone()
    moved[:, 3] += 0.1  # one drone moves: the others see it
    assert not torch.allclose(c.features(moved), X_still)


def test_bad_vision_configs_are_refused():
    with pytest.raises(ValueError, match="view"):
        VisionConfig(view="fisheye")
    with pytest.raises(ValueError, match="motion_gap"):
        VisionConfig(motion_gap=-1)
    c = make_vgai()
    with pytest.raises(ValueError, match="vision config produces"):
        VGAIController(c.model, CFG, VisionConfig(motion_gap=0, render=VISION.render))

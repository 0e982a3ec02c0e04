"""The perturbed worlds of notebook 08: each does what it says, at size 0 nothing, and every draw is seeded."""

import pytest
import torch

from vgai_lite.aggregation import AggregationBuffer
from vgai_lite.book import DATA_DIR
from vgai_lite.checkpoints import load_controller
from vgai_lite.config import FlockConfig
from vgai_lite.controllers import LocalController
from vgai_lite.flocking import rollout, sample_initial_state
from vgai_lite.lab.perturbations import (Blur, DeadCamera, DelayedBuffer, DroppedLinks, ImageNoise, MessageDelay,
                                         PositionNoise, World, perturbed)
from vgai_lite.lab.robustness import RobustnessConfig, curve, find, plan, run

CFG = FlockConfig()


@pytest.fixture(scope="module")
def pilots():
    return {"DAGNN": load_controller(DATA_DIR / "dagnn" / "dagnn_K4.pt"),
            "VGAI": load_controller(DATA_DIR / "vgai" / "vgai_F24.pt")}


@pytest.fixture(scope="module")
def start():
    return sample_initial_state(CFG, 2, torch.Generator().manual_seed(8))


def test_size_zero_is_bit_identical_to_the_clean_flight(pilots, start):
    r, v = start
    zero = {"DAGNN": (DroppedLinks(0.0), MessageDelay(0), PositionNoise(0.0)),
            "VGAI": (DroppedLinks(0.0), MessageDelay(0), ImageNoise(0.0), Blur(0.0))}
    for name, c in pilots.items():
        clean = rollout(c, CFG, r, v, steps=12)
        world = rollout(perturbed(c, *zero[name], seed=5), CFG, r, v, steps=12)
        assert torch.equal(clean.r, world.r) and torch.equal(clean.u, world.u), name


def test_every_draw_is_seeded(pilots, start):
    r, v = start
    worlds = {"DAGNN": (DroppedLinks(0.3), PositionNoise(0.05)),
              "VGAI": (ImageNoise(0.05), DroppedLinks(0.3), DeadCamera())}
    for name, c in pilots.items():
        a = rollout(perturbed(c, *worlds[name], seed=1), CFG, r, v, steps=8)
        b = rollout(perturbed(c, *worlds[name], seed=1), CFG, r, v, steps=8)
        other = rollout(perturbed(c, *worlds[name], seed=2), CFG, r, v, steps=8)
        clean = rollout(c, CFG, r, v, steps=8)
        assert torch.equal(a.u, b.u), name
        assert not torch.equal(a.u, other.u) and not torch.equal(a.u, clean.u), name


def test_wrappers_compose_and_refuse_what_cannot_reach_the_controller(pilots):
    twice = perturbed(perturbed(pilots["VGAI"], ImageNoise(0.1), seed=3), DroppedLinks(0.2))
    assert [type(p) for p in twice.perturbations] == [ImageNoise, DroppedLinks] and twice.world.seed == 3
    assert twice.controller is pilots["VGAI"]
    with pytest.raises(ValueError, match="VGAI sees only images"):
        perturbed(pilots["VGAI"], PositionNoise(0.1))
    with pytest.raises(ValueError, match="camera frames"):
        perturbed(pilots["DAGNN"], ImageNoise(0.1))
    with pytest.raises(ValueError, match="learned controller"):
        perturbed(LocalController(CFG), DroppedLinks(0.1))
    for bad in (lambda: ImageNoise(-0.1), lambda: DroppedLinks(1.5), lambda: MessageDelay(-1),
                lambda: ImageNoise(float("nan"))):
        with pytest.raises(ValueError):
            bad()


def test_all_links_dropped_leaves_only_the_agents_own_features(pilots, start):
    """p = 1: no message arrives, so every block of Z(t) but the first is zero (eq. 6 with S = 0)."""
    r, v = start
    c = perturbed(pilots["DAGNN"], DroppedLinks(1.0))
    c.reset()
    for _ in range(4):
        c(r, v)
    Z = c.buffer.Z
    assert Z[:, :, 1:].abs().max() == 0 and Z[:, :, 0].abs().max() > 0
    world = perturbed(pilots["DAGNN"], DroppedLinks(0.5), seed=4).world
    A = torch.ones(200, 50, 50)
    assert abs(world.links(A).mean().item() - 0.5) < 0.01


def test_message_delay_shifts_the_neighbours_blocks_by_one_more_step():
    """One step of extra delay: Z_k(t) = S Z_{k-1}(t - 2), so Z_1(4) = S X(2) and Z_2(4) = S S X(0),
    against S X(3) and S S X(2) without (eq. 6)."""
    g = torch.Generator().manual_seed(0)
    X = [torch.randn(1, 3, 2, generator=g) for _ in range(5)]
    S = torch.rand(1, 3, 3, generator=g)
    late, prompt, none = DelayedBuffer(3, 1), AggregationBuffer(3), DelayedBuffer(3, 0)
    for t in range(5):
        Zl, Zp, Z0 = late.push(X[t], S), prompt.push(X[t], S), none.push(X[t], S)
    assert torch.equal(Z0, Zp)  # no delay is eq. 6
    assert torch.allclose(Zp[:, :, 1], S @ X[3]) and torch.allclose(Zp[:, :, 2], S @ S @ X[2])
    assert torch.allclose(Zl[:, :, 1], S @ X[2]) and torch.allclose(Zl[:, :, 2], S @ S @ X[0])
    assert torch.equal(Zl[:, :, 0], X[4])


def test_camera_perturbations_do_what_they_say():
    img = torch.rand(2, 3, 4, 12, 128)
    world = World((DeadCamera(),), seed=0)
    dark = world.camera(img, 0)
    black = (dark == 0).all(dim=(2, 3))  # (B, N, W): columns all black
    assert (black.sum(-1) == 32).all()  # exactly one camera of 32 columns per drone
    blocks = black.view(2, 3, 4, 32).all(-1)
    assert (blocks.sum(-1) == 1).all()
    assert torch.equal(world.camera(img, 0), dark)  # the same camera all episode
    noisy = World((ImageNoise(0.1),), seed=0)
    noisy.t = 7
    now = noisy.camera(img, 0)
    noisy.t = 12
    assert torch.equal(noisy.camera(img, 5), now)  # the frame of step 7, seen again 5 steps later
    assert now.min() >= 0 and now.max() <= 1 and not torch.equal(now, img)
    flat = torch.full((1, 1, 1, 12, 128), 0.5)
    assert torch.allclose(World((Blur(2.0),), 0).camera(flat, 0), flat)  # a blur keeps constant images
    spike = torch.zeros(1, 1, 1, 12, 128)
    spike[..., 6, 0] = 1.0
    blurred = World((Blur(1.0),), 0).camera(spike, 0)
    assert blurred[..., 6, 127] > 0  # the panorama wraps around
    assert torch.isclose(blurred.sum(), torch.tensor(1.0), atol=1e-5)


def test_quick_sweep_writes_every_cell_and_resumes(tmp_path):
    rc = RobustnessConfig.quick_sweep()
    res = run(rc, out=tmp_path, progress=False)
    assert len(res["cells"]) == len(plan(rc)) and res["cells_computed_now"] == len(plan(rc))
    again = run(rc, out=tmp_path, progress=False)
    assert again["cells_computed_now"] == 0
    sizes, recs = curve(res, "VGAI", "links")
    assert sizes == [0.0, 0.2] and recs[0] == find(res, "VGAI")
    for c in res["cells"]:
        lo, hi = c["relative_cost_mean_ci95"]
        assert 0 < lo <= c["relative_cost_mean"] <= hi and 0 <= c["share_connected_at_end"] <= 1
        assert c["controller"] in ("Local", "DAGNN", "VGAI")


def test_image_noise_falls_on_the_intensity_and_depth_noise_on_the_depth_channel(pilots):
    """The shipped VGAI sees gray and depth: ImageNoise is a photosite's noise, DepthNoise a range error."""
    from vgai_lite.lab.perturbations import DepthNoise, World

    vgai = pilots["VGAI"]
    channels = vgai.vision.render.channels
    assert channels == ("gray", "depth") and perturbed(vgai, ImageNoise(0.05)).world.channels == channels
    img = torch.rand(2, 5, 2, 12, 128) * (torch.rand(2, 5, 2, 12, 128) > 0.5)
    world = World((ImageNoise(0.05), DepthNoise(0.05)), seed=3, channels=channels)
    gray = ImageNoise(0.05).frame(img, 4, world, 0)
    depth = DepthNoise(0.05).frame(img, 4, world, 1)
    assert torch.equal(gray[:, :, 1], img[:, :, 1]) and not torch.equal(gray[:, :, 0], img[:, :, 0])
    assert torch.equal(depth[:, :, 0], img[:, :, 0]) and not torch.equal(depth[:, :, 1], img[:, :, 1])
    assert torch.equal(depth[img == 0], img[img == 0])  # no return stays no return

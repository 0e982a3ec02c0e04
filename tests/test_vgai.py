"""VGAI (sections 3.3-3.4): the CNN's vertical-only pooling, pure vision, locality, any N, checkpoints."""

import dataclasses

import pytest
import torch

from vgai_lite import ExpertController as vl_expert
from vgai_lite import FlockConfig, rollout, sample_initial_state, saturate
from vgai_lite.checkpoints import load_controller, save_controller
from vgai_lite.aggregation import aggregation_sequence
from vgai_lite.checkpoints import load_estimator, save_estimator
from vgai_lite.graphs import adjacency, gso
from vgai_lite.learned_controllers import VGAIController
from vgai_lite.models import AggregationMLP, OddMotionCNN, ResidualBlock, VGAIModel, VisualCNN, cnn_from_spec
from vgai_lite.render import RenderConfig
from vgai_lite.camera import CameraRanges
from vgai_lite.vgai_config import VGAITrainConfig
from vgai_lite.lab.stage1_cache import cached, stage1_file
from vgai_lite.vgai_training import (bptt_loss, joint_loss, sample_windows, synthetic_velocities, train_vgai,
                                     window_batch)
from vgai_lite.vision import VisionConfig, camera_input, stored_images

CFG = FlockConfig(N=20)
VISION = VisionConfig(render=RenderConfig(view_height=8, view_width=16))


def make_vgai(cfg=CFG, vision=VISION, F=6, K=3, seed=0):
    torch.manual_seed(seed)
    C, H, W = vision.image_shape()
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
    from torch.utils.flop_counter import FlopCounterMode

    with FlopCounterMode(display=False) as counted:  # torch's own count of one image's convolutions and matmuls
        cnn(torch.randn(1, 4, 12, 128))
    assert cnn.flops_per_image() == counted.get_total_flops()
    with pytest.raises(ValueError, match="expects images"):
        cnn(torch.randn(3, 4, 12, 64))


def test_vgai_sees_only_images_not_velocities():
    """After an episode's first call (where the camera model draws the frames recorded before t = 0),
    the velocities passed to the controller never matter; without prehistory, never at all."""
    r, v = sample_initial_state(CFG, 2, torch.Generator().manual_seed(0), dtype=torch.float64)
    for prehistory in (True, False):
        c = make_vgai(vision=dataclasses.replace(VISION, prehistory=prehistory))
        actions = []
        for noise in (0.0, 10.0):
            c.reset()
            c(r, v if prehistory else v + noise)
            actions.append(torch.stack([c(r + 0.01 * k, v + noise * torch.randn_like(v)) for k in range(1, 4)]))
        torch.testing.assert_close(actions[0], actions[1])


def test_prehistory_frames_are_the_initial_state_flown_backwards():
    vision = VISION
    cfg = CFG.replace(T=8)
    r0, v0 = sample_initial_state(cfg, 1, torch.Generator().manual_seed(3), dtype=torch.float64)
    traj = rollout(make_vgai(vision=vision), cfg, r0, v0)
    img = stored_images(vision, cfg, traj.r, traj.v, torch.tensor([0]), torch.tensor([2]))
    now, earlier = vision.frame(traj.r[2], cfg), vision.frame(r0 + (2 - vision.motion_gap) * cfg.Ts * v0, cfg)
    torch.testing.assert_close(img, torch.cat((now, vision.motion_scale * (now - earlier)), dim=2), atol=1e-5, rtol=1e-5)


def test_the_controller_and_the_bptt_window_compute_the_same_actions():
    """One pipeline: along a flight, the controller's action at step t (step by step, its own frame
    memory and aggregation buffer) is the action the training's window of t gives (``window_batch``,
    stored flight, unrolled eq. 6), the form K-step BPTT differentiates."""
    c = make_vgai(K=3)
    cfg = CFG.replace(T=9)
    r0, v0 = sample_initial_state(cfg, 2, torch.Generator().manual_seed(4), dtype=torch.float64)
    traj = rollout(c, cfg, r0, v0)
    tcfg = VGAITrainConfig(F=6, K=3, vision=VISION)
    t, e = torch.tensor([1, 8]), torch.tensor([0, 1])  # a window that starts before t = 0, and one inside the flight
    w = window_batch(cfg, tcfg, traj.r, traj.v, traj.u, e, t)
    mask = w["valid"].double()[:, :, None, None]
    X = c.model.cnn(w["images"].flatten(0, 2)).view(2, 3, cfg.N, -1) * mask
    u_window = c.model.mlp(aggregation_sequence(X, w["S"] * mask, 3)[:, -1])
    torch.testing.assert_close(saturate(u_window, cfg), traj.u[t, e])


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
    X_still = c.features(r, r)  # hovering: the frame of now and of g steps ago are the same
    C0 = len(vision.render.channels)
    img = camera_input(vision, CFG, r, r)
    assert img.shape[2] == 2 * C0 and img[:, :, C0:].abs().max() == 0  # difference channels empty
    shifted = c.features(r + 0.5, r + 0.5)  # the whole swarm translated: every view, hence X, is the same
    torch.testing.assert_close(shifted, X_still)
    moved = r.clone()
    moved[:, 3] += 0.1  # one drone moved since g steps ago: the others see it
    assert not torch.allclose(c.features(moved, r), X_still)


def test_reading_the_features_has_no_side_effect_only_a_step_advances_the_frame_memory():
    """``features`` may be called any number of times in a step (a plot, a probe): the actions of a
    flight are the same, because only ``observe`` (once per step) advances the frame memory."""
    cfg = CFG.replace(T=8)
    r0, v0 = sample_initial_state(cfg, 2, torch.Generator().manual_seed(5), dtype=torch.float64)
    plain, probed = make_vgai(), make_vgai()

    class Probe:
        name, K = "probed", probed.K

        def reset(self):
            probed.reset()

        def __call__(self, r, v):
            before = probed.seen[0] if probed.seen else r
            for _ in range(3):
                probed.features(r, before)
            return probed(r, v)

    torch.testing.assert_close(rollout(Probe(), cfg, r0, v0).u, rollout(plain, cfg, r0, v0).u)


def test_a_vision_config_written_without_a_field_is_refused_not_defaulted():
    d = VISION.to_dict()
    assert VisionConfig.from_dict(d) == VISION
    del d["prehistory"]
    with pytest.raises(ValueError, match="prehistory"):
        VisionConfig.from_dict(d)


def test_bad_vision_configs_are_refused():
    with pytest.raises(ValueError, match="view"):
        VisionConfig(view="fisheye")
    with pytest.raises(ValueError, match="motion_gap"):
        VisionConfig(motion_gap=-1)
    c = make_vgai()
    with pytest.raises(ValueError, match="vision config produces"):
        VGAIController(c.model, CFG, VisionConfig(motion_gap=0, render=VISION.render))


MINI = VGAITrainConfig(F=6, K=3, hidden=(8,), cnn_widths=(2, 4), cnn_hidden=8, vision=VISION, warm_starts=True,
                       expert_episodes=2, dagger_rounds=1, episodes_per_round=1, warm_steps=3,
                       warm_states=1, mlp_epochs=1, joint_steps=2, windows=2, early_steps=10)


def test_a_miniature_vgai_training_changes_both_networks_and_saves_what_it_learned(tmp_path):
    """Every stage runs and learns: stage 1 and stage 3 move the CNN, stages 2 and 3 the MLP, and the
    checkpoint holds the trained weights and the full configuration."""
    cfg = FlockConfig(N=12, T=20)
    ctrl, hist = train_vgai(cfg, MINI, checkpoint=tmp_path / "v.pt", progress=False, check_episodes=1)
    assert len(hist["warm_loss"]) == 3 and len(hist["joint_loss"]) == 2 and len(hist["rounds"]) == 2
    with torch.random.fork_rng():
        torch.manual_seed(MINI.seed)
        fresh = MINI.new_model()  # the weights the training started from
    for part in ("cnn", "mlp"):
        before, after = getattr(fresh, part).state_dict(), getattr(ctrl.model, part).state_dict()
        assert any(not torch.equal(before[k], after[k]) for k in before if before[k].is_floating_point())
    loaded = load_controller(tmp_path / "v.pt")
    assert loaded.meta["finished"] and loaded.K == 3
    assert VGAITrainConfig.from_dict(loaded.meta["train_config"]) == MINI
    for k, t in ctrl.model.state_dict().items():
        torch.testing.assert_close(loaded.model.state_dict()[k], t)


def test_a_training_says_where_its_minutes_go():
    """seconds_by_phase: every phase of the book's training timed, each positive, together no more than
    the whole training (they do not overlap) and most of it (nothing slow left out)."""
    cfg = FlockConfig(N=12, T=20)
    _, hist = train_vgai(cfg, MINI, progress=False, check_episodes=1)
    phases = hist["seconds_by_phase"]
    assert set(phases) == {"round 0: the expert's flights", "stage 1: state estimation",
                           "stage 2: the MLP on the CNN's features", "stage 3: rendering the windows",
                           "stage 3: forward (CNN, aggregation, MLP)", "stage 3: backward and Adam step",
                           "DAgger flights (rendering, CNN, physics)", "round checks (flights of the learner)"}
    assert all(s > 0 for s in phases.values())
    assert 0.8 * hist["seconds"] <= sum(phases.values()) <= hist["seconds"]


def test_the_papers_vgai_learns_only_by_joint_bptt_from_random_weights(tmp_path):
    """warm_starts False (the paper's): no stage 1 or 2; joint BPTT on the expert's flights (round 0),
    then after each DAgger round; both networks move, and the MLP keeps its identity normalisation."""
    cfg = FlockConfig(N=12, T=20)
    tcfg = dataclasses.replace(MINI, warm_starts=False)
    ctrl, hist = train_vgai(cfg, tcfg, checkpoint=tmp_path / "p.pt", progress=False, check_episodes=1)
    assert hist["warm_loss"] == [] and hist["mlp_loss"] == [] and "stage1_seconds" not in hist
    assert len(hist["joint_loss"]) == (1 + tcfg.dagger_rounds) * tcfg.joint_steps
    assert [r["stage"] for r in hist["rounds"]] == ["after joint training on the expert's flights", "DAgger round 1"]
    assert hist["rounds"][0]["episodes"] == tcfg.expert_episodes
    with torch.random.fork_rng():
        torch.manual_seed(tcfg.seed)
        fresh = tcfg.new_model()
    for part in ("cnn", "mlp"):
        before, after = getattr(fresh, part).state_dict(), getattr(ctrl.model, part).state_dict()
        assert any(not torch.equal(before[k], after[k]) for k in before if before[k].is_floating_point())
    assert torch.equal(ctrl.model.mlp.z_mean, torch.zeros_like(ctrl.model.mlp.z_mean))
    assert VGAITrainConfig.from_dict(load_controller(tmp_path / "p.pt").meta["train_config"]) == tcfg


def test_the_papers_vgai_is_configured_as_the_paper_describes_it():
    """PAPER: one gray frame (no depth, no motion channel), F = 24, K - 1 = 3, the CNN of Fig. 2 from
    random weights, eq. 10 alone, DAgger's mixture p = 0.33, Adam at 1e-3; BOOK departs from it in
    exactly BOOK_RECIPE, and a file written before ``warm_starts`` existed reads as warm-started."""
    from vgai_lite.vgai_config import BOOK, BOOK_RECIPE, PAPER
    assert PAPER == VGAITrainConfig()
    assert PAPER.vision.render.channels == ("gray",) and PAPER.vision.motion_gap == 0
    assert PAPER.vision.image_shape()[0] == 1
    assert (PAPER.F, PAPER.K, PAPER.p_learner, PAPER.lr) == (24, 4, 0.33, 1e-3)
    assert not PAPER.warm_starts and PAPER.motion_features == 0 and PAPER.aux_weight == 0
    assert PAPER.synthetic_share == 0 and PAPER.learner_swarms == 0 and PAPER.camera == CameraRanges()
    differ = {f.name for f in dataclasses.fields(VGAITrainConfig) if getattr(PAPER, f.name) != getattr(BOOK, f.name)}
    assert differ == set(BOOK_RECIPE)
    old = {k: v for k, v in BOOK.to_dict().items() if k != "warm_starts"}
    assert VGAITrainConfig.from_dict(old) == BOOK


def _unrolled_eq10(cnn, mlp, images, S, u_star, valid):
    """Eq. 6 written out term by term for each window's last step, then eq. 10: an independent
    computation of what bptt_loss must give (no aggregation_sequence, no batching over windows)."""
    M, K, N = images.shape[:3]
    losses = []
    for m in range(M):
        X = [cnn(images[m, k]) * float(valid[m, k]) for k in range(K)]  # (N, F) per step, 0 before the flight
        Ss = [S[m, k] * float(valid[m, k]) for k in range(K)]
        taps, prod = [], torch.eye(N, dtype=images.dtype)
        for k in range(K):  # tap k: S(t) S(t-1) ... S(t-k+1) X(t-k)
            taps.append(prod @ X[K - 1 - k])
            prod = prod @ Ss[K - 1 - k]
        losses.append((mlp(torch.stack(taps, dim=1)) - u_star[m]).abs())  # (N, 2)
    return torch.stack(losses).mean()


def test_bptt_loss_is_eq_10_of_the_unrolled_aggregation_and_reaches_every_step():
    """bptt_loss (figure 3) against eq. 6 unrolled by hand: the same value and the same gradients on
    every step's images, with and without windows that begin before the flight."""
    torch.manual_seed(0)
    M, K, N, D, F = 3, 4, 7, 5, 3
    cnn = torch.nn.Sequential(torch.nn.Linear(D, F), torch.nn.Tanh()).double()
    mlp = torch.nn.Sequential(torch.nn.Flatten(-2), torch.nn.Linear(K * F, 2)).double()
    model = torch.nn.Module()
    model.cnn, model.mlp = cnn, mlp
    images = torch.randn(M, K, N, D, dtype=torch.float64, requires_grad=True)
    A = (torch.rand(M, K, N, N) < 0.5).double()
    S = gso((((A + A.transpose(-1, -2)) > 0).double() * (1 - torch.eye(N, dtype=torch.float64))).flatten(0, 1))
    S = S.view(M, K, N, N)
    u_star = torch.randn(M, N, 2, dtype=torch.float64)
    for valid in (torch.ones(M, K, dtype=torch.bool), torch.tensor([[False, False, True, True]] * M)):
        got = bptt_loss(model, images, S, u_star, valid)
        want = _unrolled_eq10(cnn, mlp, images, S, u_star, valid)
        torch.testing.assert_close(got, want)
        (g_got,) = torch.autograd.grad(got, images)
        (g_want,) = torch.autograd.grad(want, images)
        torch.testing.assert_close(g_got, g_want)
        per_step = g_got.abs().sum(dim=(0, 2, 3))
        assert ((per_step > 0) == valid[0]).all()  # every step inside the flight gets gradient, none before


def test_the_training_step_is_bptt_loss_plus_the_weighted_state_estimation_loss():
    """The joint step of stage 3 computes eq. 10 exactly as bptt_loss does (aux_weight 0), and adds
    aux_weight times stage 1's loss on the same images otherwise."""
    cfg = FlockConfig(N=12, T=20)
    r0, v0 = sample_initial_state(cfg, 2, torch.Generator().manual_seed(2))
    traj = rollout(vl_expert(cfg), cfg, r0, v0)
    model = dataclasses.replace(MINI, motion_features=2).new_model()
    e, t_end = sample_windows(cfg.T, 2, MINI, torch.Generator().manual_seed(3))
    w = window_batch(cfg, MINI, traj.r, traj.v, traj.u, e, t_end)
    plain = bptt_loss(model, w["images"], w["S"], w["u_star"], w["valid"])
    torch.testing.assert_close(joint_loss(model, MINI, w), plain)
    weighted = dataclasses.replace(MINI, aux_weight=2.0)
    aux = joint_loss(model, weighted, w) - plain
    assert aux > 0
    from vgai_lite.vgai_training import estimation_loss, window_features
    torch.testing.assert_close(aux, 2.0 * estimation_loss(model.cnn, window_features(model.cnn, w["images"]),
                                                           w["x_exact"]))


def test_a_cached_stage_one_continues_exactly_like_the_run_that_trained_it(tmp_path):
    """The K = 2, 3, 4 runs share stage 1 (visual state estimation): a run reading it from the cache
    must end with the same weights as a run training it, and a run of another K must reuse it."""
    cfg = FlockConfig(N=12, T=20)
    tcfg = VGAITrainConfig(F=6, K=3, hidden=(8,), cnn_widths=(2, 4), cnn_hidden=8, vision=VISION, warm_starts=True,
                           expert_episodes=2, dagger_rounds=1, episodes_per_round=1, warm_steps=3,
                           warm_states=1, mlp_epochs=1, joint_steps=2, windows=2, early_steps=10)
    plain, _ = train_vgai(cfg, tcfg, progress=False, check_episodes=1)
    first, h1 = train_vgai(cfg, tcfg, progress=False, check_episodes=1, stage1=cached(tmp_path))
    assert stage1_file(tmp_path, cfg, tcfg).is_file() and "stage1_cached" not in h1
    again, h2 = train_vgai(cfg, tcfg, progress=False, check_episodes=1, stage1=cached(tmp_path))
    assert h2["stage1_cached"] == stage1_file(tmp_path, cfg, tcfg).name
    assert h2["warm_loss"] == h1["warm_loss"]
    for a, b, c in zip(plain.model.state_dict().values(), first.model.state_dict().values(),
                       again.model.state_dict().values()):
        assert torch.equal(a, b) and torch.equal(b, c)
    # K does not enter stage 1, F does
    assert stage1_file(tmp_path, cfg, dataclasses.replace(tcfg, K=2)) == stage1_file(tmp_path, cfg, tcfg)
    assert stage1_file(tmp_path, cfg, dataclasses.replace(tcfg, F=12)) != stage1_file(tmp_path, cfg, tcfg)
    assert stage1_file(tmp_path, cfg.replace(R=2.0), tcfg) != stage1_file(tmp_path, cfg, tcfg)


def test_gradients_reach_the_cnn_through_every_step_of_the_window():
    """K-step BPTT: the action at the window's end depends on the images of all K steps."""
    c = make_vgai(K=3)
    cfg = CFG.replace(T=3)
    r0, v0 = sample_initial_state(cfg, 1, torch.Generator().manual_seed(0), dtype=torch.float64)
    r = rollout(c, cfg, r0, v0).r[:, 0]  # (K, N, 2)
    imgs = torch.stack([camera_input(VISION, cfg, r[k:k + 1], r[:1])[0] for k in range(3)]).requires_grad_(True)  # (K, N, C, H, W)
    X = c.model.cnn(imgs.flatten(0, 1)).view(1, 3, cfg.N, -1)
    S = gso(adjacency(r, cfg.R)).unsqueeze(0)
    u = c.model.mlp(aggregation_sequence(X, S, 3)[:, -1])
    u.abs().sum().backward()
    per_step = imgs.grad.abs().sum(dim=(1, 2, 3, 4))
    assert (per_step > 0).all()  # the images of t-2, t-1 and t all receive gradient


def test_state_estimator_files_round_trip(tmp_path):
    C, H, W = VISION.image_shape()
    cnn = VisualCNN(C, H, W, 6, (2, 4), 8)
    path = save_estimator(tmp_path / "e.pt", cnn, VISION, {"steps": 1})
    cnn2, vision2, meta = load_estimator(path)
    assert vision2 == VISION and meta == {"steps": 1}
    x = torch.randn(2, C, H, W)
    torch.testing.assert_close(cnn2(x), cnn.eval()(x))


def test_synthetic_velocities_span_the_disagreements_late_and_early_flights_have():
    SYNTHETIC_SPEEDS = VGAITrainConfig().synthetic_speeds
    v = torch.zeros(400, 30, 2) + torch.tensor([2.0, -1.0])
    vs = synthetic_velocities(v, SYNTHETIC_SPEEDS, torch.Generator().manual_seed(0))
    spread = (vs - vs.mean(1, keepdim=True)).std(dim=(1, 2))  # one scale per swarm
    assert vs.shape == v.shape
    assert SYNTHETIC_SPEEDS[0] / 2 < spread.min() < 3 * SYNTHETIC_SPEEDS[0] and spread.max() > SYNTHETIC_SPEEDS[1] / 2
    torch.testing.assert_close(vs.mean(dim=(0, 1)), torch.tensor([2.0, -1.0]), atol=0.1, rtol=0)
    torch.testing.assert_close(synthetic_velocities(v, SYNTHETIC_SPEEDS, torch.Generator().manual_seed(0)), vs)


def test_motion_features_vanish_when_nothing_moves_and_flip_with_the_motion():
    """OddMotionCNN(motion_features=F_m): the last F_m features are odd in the motion channels, the
    others even; a swarm moving as one (every drone's motion frame 0) gives exactly 0 on them, and
    so does the aux head's velocity estimate. The controller flying such a CNN: the same."""
    C, H, W = VISION.image_shape()
    torch.manual_seed(0)
    cnn = OddMotionCNN(C, H, W, 6, (2, 4), 8, motion_features=2).double()
    x = torch.randn(3, C, H, W, dtype=torch.float64)
    mirrored = torch.cat((x[:, :C // 2], -x[:, C // 2:]), 1)
    torch.testing.assert_close(cnn(mirrored)[:, :4], cnn(x)[:, :4])
    torch.testing.assert_close(cnn(mirrored)[:, 4:], -cnn(x)[:, 4:])
    assert cnn(x)[:, 4:].abs().min() > 0
    # a rigidly translating swarm: the images of now and of g steps ago agree, the motion features are 0
    r, _ = sample_initial_state(CFG, 2, torch.Generator().manual_seed(1), dtype=torch.float64)
    still = camera_input(VISION, CFG, r + 0.3, r)
    X = cnn(still.flatten(0, 1))
    assert X[:, 4:].abs().max() < 1e-9 and X[:, :4].abs().min() > 0  # 0 up to rounding of the offsets
    assert cnn.estimate_local_features(still.flatten(0, 1))[:, :2].abs().max() < 1e-9
    with pytest.raises(ValueError, match="motion_features"):
        OddMotionCNN(C, H, W, 6, motion_features=7)
    with pytest.raises(ValueError, match="motion frame"):
        VGAITrainConfig(motion_features=2, vision=dataclasses.replace(VISION, motion_gap=0))


def test_stack_pairing_reads_motion_as_the_change_of_one_frames_reading():
    """OddMotionCNN(pairing="stack") on [I(t), I(t-g)]: the trunk reads each frame alone (a stem of half
    the channels); swapping the frames keeps the even features and negates the odd ones; equal frames
    (a swarm moving as one) give exactly 0 on the odd ones; and the odd features ARE the change of the
    trunk's reading times the motion scale, s (psi(I(t)) - psi(I(t-g))). A configuration in the 'stack' mode
    builds it with its vision's s, and its spec rebuilds it."""
    vision = dataclasses.replace(VISION, motion_mode="stack")
    C, H, W = vision.image_shape()
    torch.manual_seed(0)
    cnn = OddMotionCNN(C, H, W, 6, (2, 4), 8, motion_features=2, pairing="stack", motion_scale=3.0).double()
    assert cnn.stem.in_channels == C // 2
    x = torch.randn(3, C, H, W, dtype=torch.float64)
    swapped = torch.cat((x[:, C // 2:], x[:, :C // 2]), 1)
    torch.testing.assert_close(cnn(swapped)[:, :4], cnn(x)[:, :4])
    torch.testing.assert_close(cnn(swapped)[:, 4:], -cnn(x)[:, 4:])
    psi_now, psi_before = cnn.trunk(x[:, :C // 2]), cnn.trunk(x[:, C // 2:])
    torch.testing.assert_close(cnn(x)[:, 4:], 3.0 * (psi_now - psi_before)[:, 4:])
    torch.testing.assert_close(cnn(x)[:, :4], (psi_now + psi_before)[:, :4] / 2)
    r, _ = sample_initial_state(CFG, 2, torch.Generator().manual_seed(1), dtype=torch.float64)
    still = camera_input(vision, CFG, r + 0.3, r)
    assert cnn(still.flatten(0, 1))[:, 4:].abs().max() < 1e-9
    moved = camera_input(vision, CFG, r + 0.3 * torch.randn_like(r), r)
    assert cnn(moved.flatten(0, 1))[:, 4:].abs().max() > 1e-6
    model = VGAITrainConfig(motion_features=2, F=6, K=3, hidden=(16,), vision=vision).new_model()
    assert model.cnn.pairing == "stack" and model.cnn.stem.in_channels == C // 2 and model.cnn.motion_scale == 5.0
    with pytest.raises(ValueError, match="pairing"):
        OddMotionCNN(C, H, W, 6, motion_features=2, pairing="sum")
    rebuilt = cnn_from_spec(cnn.spec(), 6)
    assert (rebuilt.pairing, rebuilt.motion_scale, rebuilt.odd_gain) == ("stack", 3.0, 3.0)
    assert cnn_from_spec({k: v for k, v in cnn.spec().items() if k != "pairing"}, 6).pairing == "difference"


def test_a_cnn_with_motion_features_round_trips_through_both_file_kinds(tmp_path):
    C, H, W = VISION.image_shape()
    torch.manual_seed(0)
    cnn = OddMotionCNN(C, H, W, 6, (2, 4), 8, motion_features=2).eval()
    cnn2, _, _ = load_estimator(save_estimator(tmp_path / "e.pt", cnn, VISION, {}))
    assert cnn2.motion_features == 2
    c = VGAIController(VGAIModel(cnn, AggregationMLP(3, 6, (16,))).eval(), CFG, VISION)
    c2 = load_controller(save_controller(tmp_path / "c.pt", c))
    assert c2.model.cnn.motion_features == 2
    r, v = sample_initial_state(CFG, 2, torch.Generator().manual_seed(0))
    c.reset(), c2.reset()
    torch.testing.assert_close(c2(r, v), c(r, v))


def test_the_default_vgai_is_the_training_seed_chosen_on_validation_episodes():
    """data/vgai/vgai_F24.pt is one of the three shipped training seeds: among those that flocked on the
    validation episodes (never the test seed), the one with the lowest relative cost, as
    runs.VGAI_F24_SEED says."""
    import json

    from vgai_lite.book import DATA_DIR, VALIDATION_SEED
    from vgai_lite.lab.runs import VGAI_F24_SEED, VGAI_RUNS, VGAI_SEED_RUNS

    choice = json.loads((DATA_DIR / "vgai" / "seeds" / "choice.json").read_text())
    assert choice["validation_seed"] == VALIDATION_SEED and set(choice["candidates"]) == set(VGAI_SEED_RUNS)
    from vgai_lite.evaluate import FLOCKED_CONNECTED, FLOCKED_VARIANCE

    cands = choice["candidates"]
    for n, c in cands.items():  # each candidate's label agrees with its own figures
        assert c["flocked"] == (c["variance_5s"] <= FLOCKED_VARIANCE and c["share_connected_at_end"] >= FLOCKED_CONNECTED), n
    pool = [n for n in cands if cands[n]["flocked"]] or list(cands)
    best = min(pool, key=lambda n: cands[n]["relative_cost_mean"])
    assert choice["chosen"] == best and VGAI_SEED_RUNS[best].seed == VGAI_F24_SEED
    assert VGAI_RUNS["vgai_F24"] == VGAI_SEED_RUNS[best]
    shipped = torch.load(DATA_DIR / "vgai" / "vgai_F24.pt", weights_only=True)
    chosen = torch.load(DATA_DIR / "vgai" / "seeds" / f"{best}.pt", weights_only=True)
    assert all(torch.equal(shipped["state_dict"][k], chosen["state_dict"][k]) for k in chosen["state_dict"])


def test_the_seed_rule_prefers_a_flock_to_a_lower_cost():
    """A cheaper training whose swarm does not settle is not chosen; with no flock, the cheapest is."""
    from vgai_lite.lab.runs import pick_seed

    c = {"a": {"relative_cost_mean": 1.38, "flocked": False}, "b": {"relative_cost_mean": 1.50, "flocked": True},
         "c": {"relative_cost_mean": 1.57, "flocked": True}}
    assert pick_seed(c) == "b"
    assert pick_seed({k: {**v, "flocked": False} for k, v in c.items()}) == "a"
    with pytest.raises(ValueError, match="at least one"):
        pick_seed({})


def test_how_a_training_ran_says_alone_or_sharing_from_its_provenance():
    from vgai_lite.lab.runs import how_trained

    def rec(threads, load):
        return {"provenance": {"training": {"torch_threads": threads, "load_average_mean": load}}}

    assert how_trained(rec(2, 2.2)) == "2 threads, alone"
    assert how_trained(rec(1, 2.0)) == "1 thread, sharing the cores"  # one of two trainings side by side
    assert how_trained(rec(1, 1.1)) == "1 thread, alone"
    assert how_trained({}) is None


def test_a_vgai_training_over_teams_and_radii_learns_from_every_group_with_as_many_images_per_step(tmp_path, monkeypatch):
    """teams/radii: round 0 and every DAgger round fly groups of several N and R; stage 1's states and
    stage 3's windows come from every group, in batches scaled by 1 / N (``per_team``), each window's
    GSO and local features of its own group's N and R; the controller it returns flies the training's cfg."""
    import vgai_lite.vgai_training as vt
    cfg = FlockConfig(N=12, T=20)
    tcfg = dataclasses.replace(MINI, teams=(6, 12), radii=(1.0, 2.0), group_swarms=1, expert_episodes=6,
                               episodes_per_round=3, warm_steps=12, joint_steps=12, warm_states=2)
    states, windows = [], []
    batch, window = vt.estimation_batch, vt.window_batch

    def record_states(c, t, r, v, gen, n=None):
        img, x = batch(c, t, r, v, gen, n)
        states.append((c.N, c.R, img.shape[:2]))
        return img, x

    def record_windows(c, t, r, v, u, e, t_end, camera=None):
        w = window(c, t, r, v, u, e, t_end, camera)
        windows.append((c.N, c.R, len(e)))
        assert w["S"].shape[-1] == c.N and torch.equal(w["S"][:, -1], gso(adjacency(r[t_end, e], c.R), t.gso))
        return w

    monkeypatch.setattr(vt, "estimation_batch", record_states)
    monkeypatch.setattr(vt, "window_batch", record_windows)
    ctrl, hist = train_vgai(cfg, tcfg, checkpoint=tmp_path / "t.pt", progress=False, check_episodes=1)
    assert len({n for n, _, _ in states}) == 2 and len({n for n, _, _ in windows}) == 2
    assert len({r for _, r, _ in windows}) > 2 and all(1.0 <= r <= 2.0 for _, r, _ in windows)
    assert all(shape == (2 * 12 // n, n) for n, _, shape in states)  # 2 swarms of 12 = 4 of 6 drones' images
    assert all(m == 2 * 12 // n for n, _, m in windows)
    assert ctrl.cfg == cfg and ctrl.camera is None
    assert VGAITrainConfig.from_dict(load_controller(tmp_path / "t.pt").meta["train_config"]) == tcfg


def test_a_vgai_training_without_teams_or_radii_is_read_from_files_written_before_them():
    stored = {k: v for k, v in MINI.to_dict().items() if k not in ("teams", "radii", "group_swarms")}
    assert VGAITrainConfig.from_dict(stored) == MINI and VGAITrainConfig.read_stored(stored) == MINI.to_dict()


@pytest.mark.parametrize("bad, match", [({"teams": (1,)}, "teams must be whole numbers"),
                                        ({"teams": (50.0,)}, "teams must be whole numbers"),
                                        ({"radii": (2.0, 1.0)}, "radii must be"), ({"radii": (1.0,)}, "radii must be"),
                                        ({"group_swarms": 0}, "group_swarms")])
def test_teams_and_radii_are_checked(bad, match):
    with pytest.raises(ValueError, match=match):
        dataclasses.replace(MINI, **bad)


def test_stored_flights_are_joined_per_configuration_and_never_across_them():
    from vgai_lite.imitation import EpisodeStore
    store, gen = EpisodeStore(), torch.Generator().manual_seed(0)
    a, b = FlockConfig(N=6, T=3), FlockConfig(N=8, T=3)
    for c in (a, b, a):
        store.fly(None, c, *sample_initial_state(c, 2, gen), 0.0, gen)
    groups = store.groups()
    assert [g.cfg for g in groups] == [a, b] and [g.r.shape for g in groups] == [(3, 4, 6, 2), (3, 2, 8, 2)]
    torch.testing.assert_close(groups[0].u[:, 2:], store.u[2])
    with pytest.raises(ValueError, match="groups()"):
        store.tensors()


def test_with_feature_means_the_cnn_learns_to_read_the_means_in_stage_one_and_in_stage_three():
    from vgai_lite.features import local_features
    from vgai_lite.imitation import EpisodeStore
    from vgai_lite.vgai_training import estimation_batch
    cfg, tcfg = FlockConfig(N=12, T=20), dataclasses.replace(MINI, feature_means=True)
    store, gen = EpisodeStore(), torch.Generator().manual_seed(0)
    store.fly(None, cfg, *sample_initial_state(cfg, 2, gen), 0.0, gen)
    r, v, u = store.tensors()
    e, t = torch.tensor([0, 1]), torch.tensor([3, 15])
    w = window_batch(cfg, tcfg, r, v, u, e, t)
    torch.testing.assert_close(w["x_exact"][:, -1], local_features(r[t, e], v[t, e], cfg.R, per_neighbour=True))
    _, x = estimation_batch(cfg, tcfg, r, v, torch.Generator().manual_seed(1))
    _, x_sums = estimation_batch(cfg, MINI, r, v, torch.Generator().manual_seed(1))
    assert x.shape == x_sums.shape and not torch.allclose(x, x_sums)
    assert torch.all((x * x_sums) >= -1e-9)  # a mean has its sum's sign


def test_with_the_local_readout_the_mlp_reads_the_cnns_estimate_of_the_six_local_features(tmp_path):
    """readout "local": x_i(t) is the aux head's estimate of the 6 local features in their units (what the DAGNN's
    MLP reads exactly), in the controller, in stage 2's rows and in stage 3's loss; the file keeps it."""
    torch.manual_seed(0)
    C, H, W = VISION.image_shape()
    cnn = VisualCNN(C, H, W, 12, (4, 8), 16)
    cnn.aux_mean.copy_(torch.linspace(-1, 1, 6)), cnn.aux_std.copy_(torch.linspace(0.5, 3, 6))
    model = VGAIModel(cnn, AggregationMLP(3, 6, (16,)), readout="local").eval()
    images = torch.rand(2, CFG.N, C, H, W)
    torch.testing.assert_close(model.features(images), cnn.estimate_local_features(images.flatten(0, 1)).view(2, CFG.N, 6))
    c = VGAIController(model, CFG, VISION)
    c2 = load_controller(save_controller(tmp_path / "v.pt", c))
    assert c2.model.readout == "local" and c2.model.cnn.F == 12 and c2.model.mlp.F == 6
    r, v = sample_initial_state(CFG.replace(T=6), 2, torch.Generator().manual_seed(0))
    torch.testing.assert_close(rollout(c2, CFG.replace(T=6), r, v).u, rollout(c, CFG.replace(T=6), r, v).u)
    # the action loss reaches the CNN through the aux head, and only the aux head's 6 outputs matter
    M, K = 2, 3
    imgs, S = torch.rand(M, K, CFG.N, C, H, W), torch.rand(M, K, CFG.N, CFG.N)
    loss = bptt_loss(model, imgs, S, torch.randn(M, CFG.N, 2))
    loss.backward()
    assert cnn.aux.weight.grad.abs().sum() > 0 and cnn.stem.weight.grad.abs().sum() > 0


def test_a_readout_and_an_mlp_that_do_not_fit_are_refused():
    C, H, W = VISION.image_shape()
    cnn = VisualCNN(C, H, W, 12, (4, 8), 16)
    with pytest.raises(ValueError, match="F=12 features per tap but the CNN gives F=6"):
        VGAIModel(cnn, AggregationMLP(3, 12, (16,)), readout="local")
    with pytest.raises(ValueError, match="readout 'estimates'"):
        VGAIModel(cnn, AggregationMLP(3, 6, (16,)), readout="estimates")
    with pytest.raises(ValueError, match="readout one of"):
        VGAITrainConfig(readout="estimates")
    assert VGAITrainConfig(readout="local", F=12).new_model().mlp.F == 6


def test_a_miniature_training_with_the_local_readout_fits_the_mlp_on_six_estimates_per_tap(tmp_path):
    cfg, tcfg = FlockConfig(N=12, T=20), dataclasses.replace(MINI, readout="local", F=12)
    ctrl, hist = train_vgai(cfg, tcfg, checkpoint=tmp_path / "v.pt", progress=False, check_episodes=1)
    assert ctrl.model.cnn.F == 12 and ctrl.model.mlp.F == 6 and ctrl.model.mlp.z_mean.shape[-1] == 6 * tcfg.K
    loaded = load_controller(tmp_path / "v.pt")
    assert VGAITrainConfig.from_dict(loaded.meta["train_config"]).readout == "local" and loaded.model.readout == "local"


def test_a_training_that_starts_its_mlp_as_a_dagnns_takes_its_weights_and_refuses_one_that_reads_otherwise(tmp_path):
    """mlp_start: stage 2 copies the DAGNN's MLP (weights and normalisation) instead of fitting one, and a DAGNN whose
    taps, widths, GSO or features differ from what the VGAI's MLP reads is refused before anything is trained."""
    from vgai_lite.learned_controllers import DAGNNController
    from vgai_lite.vgai_training import mlp_from_dagnn
    torch.manual_seed(3)
    dagnn = AggregationMLP(3, 6, (8,))
    dagnn.set_normalization(torch.randn(50, 3, 6) * 2 + 1)
    path = save_controller(tmp_path / "d.pt", DAGNNController(dagnn, CFG))
    tcfg = dataclasses.replace(MINI, readout="local", F=12, mlp_start=str(path))
    model = tcfg.new_model()
    assert mlp_from_dagnn(model, tcfg) == []
    for k, t in dagnn.state_dict().items():
        torch.testing.assert_close(model.mlp.state_dict()[k], t)
    with pytest.raises(ValueError, match="expected a DAGNN of"):
        mlp_from_dagnn(model, dataclasses.replace(tcfg, hidden=(16,)))
    with pytest.raises(ValueError, match=r"'per_neighbour'\), got .*'none'\)"):
        mlp_from_dagnn(model, dataclasses.replace(tcfg, feature_means=True))  # the CNN reads means, the DAGNN sums
    path3 = save_controller(tmp_path / "d3.pt", DAGNNController(dagnn, CFG, feature_transform="per_neighbour"))
    means = dataclasses.replace(tcfg, feature_means=True, mlp_start=str(path3))
    assert mlp_from_dagnn(model, means) == []
    with pytest.raises(ValueError, match=r"'none'\), got .*'per_neighbour'\)"):
        mlp_from_dagnn(model, dataclasses.replace(tcfg, mlp_start=str(path3)))  # the CNN reads sums, the DAGNN means
    path2 = save_controller(tmp_path / "d2.pt", DAGNNController(dagnn, CFG, feature_transform="signed_log"))
    with pytest.raises(ValueError, match="'signed_log'"):
        mlp_from_dagnn(model, dataclasses.replace(tcfg, mlp_start=str(path2)))
    with pytest.raises(ValueError, match="needs readout 'local'"):
        VGAITrainConfig(mlp_start=str(path))
    cfg = FlockConfig(N=12, T=20)
    ctrl, hist = train_vgai(cfg, tcfg, progress=False, check_episodes=1)
    assert hist["mlp_loss"] == [] and len(hist["joint_loss"]) == 2


def test_with_joint_mlp_off_stage_three_trains_the_cnn_through_the_mlp_stage_two_left(tmp_path):
    from vgai_lite.learned_controllers import DAGNNController
    torch.manual_seed(4)
    dagnn = AggregationMLP(3, 6, (8,))
    dagnn.set_normalization(torch.randn(50, 3, 6))
    path = save_controller(tmp_path / "d.pt", DAGNNController(dagnn, CFG))
    tcfg = dataclasses.replace(MINI, readout="local", F=12, mlp_start=str(path), joint_mlp=False)
    ctrl, hist = train_vgai(FlockConfig(N=12, T=20), tcfg, progress=False, check_episodes=1)
    for k, t in dagnn.state_dict().items():  # the MLP is the DAGNN's, untouched by stage 3
        torch.testing.assert_close(ctrl.model.mlp.state_dict()[k], t)
    fresh = tcfg.new_model()
    assert len(hist["joint_loss"]) == 2 and not torch.equal(ctrl.model.cnn.stem.weight, fresh.cnn.stem.weight)
    with pytest.raises(ValueError, match="needs warm_starts"):
        VGAITrainConfig(joint_mlp=False)

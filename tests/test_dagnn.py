"""The DAGNN baseline (eqs. 7-10): locality, equivariance, any N, checkpoints, DAgger."""

import pytest
import torch

from vgai_lite import ExpertController, FlockConfig, rollout, sample_initial_state
from vgai_lite.checkpoints import load_controller, save_controller
from vgai_lite.features import local_features
from vgai_lite.graphs import adjacency, k_hop_reach
from vgai_lite.dagnn_training import DAGNNTrainConfig, collect, train_dagnn
from vgai_lite.learned_controllers import DAGNNController
from vgai_lite.models import AggregationMLP


def make_controller(K=3, seed=0, cfg=None):
    torch.manual_seed(seed)
    cfg = cfg or FlockConfig()
    model = AggregationMLP(K, 6, (16, 16)).double().eval()
    for p in model.parameters():  # larger random weights so that every input matters
        p.data.normal_(0, 0.5)
    return DAGNNController(model, cfg)


def replay(controller, r_seq, v_seq):
    """Feed a fixed sequence of states to a controller, return its actions at every step."""
    controller.reset()
    return torch.stack([controller(r, v) for r, v in zip(r_seq, v_seq)])


def expert_states(cfg, B=1, T=6, seed=0):
    r0, v0 = sample_initial_state(cfg, B, torch.Generator().manual_seed(seed), dtype=torch.float64)
    traj = rollout(ExpertController(cfg), cfg.replace(T=T), r0, v0)
    return traj.r, traj.v


def test_local_features_are_eq_sums_over_neighbours():
    cfg = FlockConfig(N=6)
    r, v = (x[0] for x in expert_states(cfg, T=1))
    X = local_features(r, v, cfg.R)
    i = 2
    nbrs = [j for j in range(6) if j != i and (r[0, i] - r[0, j]).norm() <= cfg.R]
    rij = torch.stack([r[0, i] - r[0, j] for j in nbrs])
    d = rij.norm(dim=-1, keepdim=True)
    expected = torch.cat((sum(v[0, i] - v[0, j] for j in nbrs), (rij / d ** 4).sum(0), (rij / d ** 2).sum(0)))
    torch.testing.assert_close(X[0, i], expected)


def test_dagnn_is_permutation_equivariant():
    cfg = FlockConfig(N=30)
    r_seq, v_seq = expert_states(cfg, B=2)
    perm = torch.randperm(cfg.N, generator=torch.Generator().manual_seed(1))
    c = make_controller(K=4)
    u = replay(c, r_seq, v_seq)
    u_perm = replay(c, r_seq[:, :, perm], v_seq[:, :, perm])
    torch.testing.assert_close(u_perm, u[:, :, perm])


def test_an_agent_beyond_the_reach_of_K_minus_1_exchanges_does_not_change_the_action():
    """K-1 exchanges carry features from K-1 hops away, and each feature x_j is measured from j's
    own neighbours (one more hop): agent i's action depends only on agents within K hops."""
    cfg = FlockConfig(N=50)
    K, T = 2, 6
    r_seq, v_seq = expert_states(cfg, T=T, seed=4)
    A_any = (adjacency(r_seq[:, 0], cfg.R).sum(0) > 0).double().unsqueeze(0)  # links at any step
    reach = k_hop_reach(A_any, K)[0]
    i = 0
    far = (~reach[i]).nonzero().flatten()
    near = (A_any[0, i] > 0).nonzero().flatten()
    assert len(far) > 0 and len(near) > 0
    c = make_controller(K=K)
    u = replay(c, r_seq, v_seq)
    v_far = v_seq.clone()
    v_far[:, :, far] += 1.0  # change far agents' velocities (the graph stays the same)
    torch.testing.assert_close(replay(c, r_seq, v_far)[:, :, i], u[:, :, i])
    v_near = v_seq.clone()
    v_near[:, :, near[0]] += 1.0  # a neighbour's change does reach agent i
    assert not torch.allclose(replay(c, r_seq, v_near)[:, :, i], u[:, :, i])


def test_dagnn_runs_on_any_team_size():
    c = make_controller(K=4)
    for N in (10, 50, 75):
        cfg = FlockConfig(N=N, T=5, init_method="repair")
        c.cfg = cfg
        r0, v0 = sample_initial_state(cfg, 2, torch.Generator().manual_seed(0), dtype=torch.float64)
        traj = rollout(c, cfg, r0, v0)
        assert traj.u.shape == (5, 2, N, 2) and traj.u.abs().max() <= cfg.u_max


def test_checkpoint_round_trip_gives_identical_actions(tmp_path):
    cfg = FlockConfig(N=20)
    c = make_controller(K=4, cfg=cfg)
    c.model.float()
    path = save_controller(tmp_path / "c.pt", c, meta={"note": "test"})
    c2 = load_controller(path)
    assert c2.meta == {"note": "test"} and c2.K == 4 and c2.cfg == cfg
    r_seq, v_seq = expert_states(cfg)
    torch.testing.assert_close(replay(c2, r_seq.float(), v_seq.float()), replay(c, r_seq.float(), v_seq.float()))
    c3 = load_controller(path, cfg=cfg.replace(N=75))
    assert c3.cfg.N == 75 and c3.trained_config.N == 20


def test_bad_checkpoints_give_clear_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="no checkpoint"):
        load_controller(tmp_path / "missing.pt")
    (tmp_path / "junk.pt").write_bytes(b"not a checkpoint")
    with pytest.raises(ValueError, match="not a readable"):
        load_controller(tmp_path / "junk.pt")
    torch.save({"format": "something else"}, tmp_path / "other.pt")
    with pytest.raises(ValueError, match="not a vgai-lite controller"):
        load_controller(tmp_path / "other.pt")
    c = make_controller(K=4)
    path = save_controller(tmp_path / "c.pt", c)
    payload = torch.load(path, weights_only=True)
    payload["spec"]["K"] = 2  # architecture no longer matches the weights
    torch.save(payload, tmp_path / "bad.pt")
    with pytest.raises(ValueError, match="do not match"):
        load_controller(tmp_path / "bad.pt")


def test_loading_never_executes_code(tmp_path):
    class Evil:
        def __reduce__(self):
            return (print, ("executed!",))

    torch.save({"format": "vgai-lite-controller/1", "x": Evil()}, tmp_path / "evil.pt")
    with pytest.raises(ValueError, match="not a readable"):
        load_controller(tmp_path / "evil.pt")


def test_dagger_collection_with_p0_labels_the_expert_trajectory():
    cfg = FlockConfig(N=10, T=15)
    r0, v0 = sample_initial_state(cfg, 2, torch.Generator().manual_seed(0))
    c = make_controller(K=3, cfg=cfg)
    c.model.float()
    Z, U = collect(c, cfg, r0, v0, p_learner=0.0, generator=torch.Generator().manual_seed(0))
    traj = rollout(ExpertController(cfg), cfg, r0, v0)
    assert Z.shape == (15 * 2 * 10, 3, 6) and U.shape == (300, 2)
    torch.testing.assert_close(U, traj.u.reshape(-1, 2))  # rows are (t, b, i) in order
    # with p = 1 the swarm follows the learner: the labels differ from the expert's trajectory
    _, U1 = collect(c, cfg, r0, v0, p_learner=1.0, generator=torch.Generator().manual_seed(0))
    assert not torch.allclose(U1, U)


def test_a_short_dagger_run_lowers_the_imitation_loss(tmp_path):
    cfg = FlockConfig(N=20, T=40)
    tcfg = DAGNNTrainConfig(K=2, hidden=(16,), rounds=3, episodes_per_round=4, epochs_per_round=3,
                            batch_size=256)
    ctrl, hist = train_dagnn(cfg, tcfg, checkpoint=tmp_path / "d.pt", progress=False, check_episodes=2)
    assert hist["loss"][2] < hist["loss"][0]  # three epochs on round 0's data
    assert len(hist["rounds"]) == 3 and (tmp_path / "d.pt").is_file()
    assert load_controller(tmp_path / "d.pt").meta["finished"]


def test_a_training_over_teams_and_radii_flies_groups_drawn_from_them():
    """flight_groups: without teams and radii every swarm flies the training's configuration (and draws
    nothing, so such a training is the one it always was); with them, groups of ``group_swarms`` whose
    N comes from ``teams``, R from the range, large teams drawn as the book's evaluation draws them."""
    from vgai_lite.imitation import LARGE_TEAM, flight_groups
    from vgai_lite.lab.reproduce import ReproduceConfig

    assert LARGE_TEAM == ReproduceConfig().repair_from
    cfg, gen = FlockConfig(), torch.Generator().manual_seed(0)
    state = gen.get_state()
    assert flight_groups(cfg, DAGNNTrainConfig(), 40, gen) == [(cfg, 40)]
    assert torch.equal(gen.get_state(), state)
    tcfg = DAGNNTrainConfig(teams=(20, 80), radii=(1.0, 2.0), group_swarms=3)
    groups = flight_groups(cfg, tcfg, 40, gen)
    assert [n for _, n in groups] == [3] * 13 + [1]
    assert {g.N for g, _ in groups} == {20, 80}
    assert all(1.0 <= g.R <= 2.0 for g, _ in groups) and len({g.R for g, _ in groups}) == len(groups)
    assert all(g.init_method == ("repair" if g.N >= LARGE_TEAM else "reject") for g, _ in groups)
    assert all(g.replace(N=cfg.N, R=cfg.R, init_method=cfg.init_method) == cfg for g, _ in groups)


def test_a_short_training_over_teams_and_radii_learns_from_every_group(tmp_path):
    cfg = FlockConfig(N=20, T=30)
    tcfg = DAGNNTrainConfig(K=2, hidden=(8,), rounds=2, episodes_per_round=4, epochs_per_round=1,
                            batch_size=256, teams=(12, 30), radii=(1.2, 2.0), group_swarms=2)
    ctrl, hist = train_dagnn(cfg, tcfg, progress=False, check_episodes=1)
    assert ctrl.cfg == cfg  # the controller returned flies the training's configuration
    assert hist["rounds"][0]["rows"] > 0 and len(hist["rounds"]) == 2


@pytest.mark.parametrize("bad", [{"teams": (50, 1)}, {"teams": (50.0,)}, {"radii": (2.0, 1.0)}, {"radii": (1.0,)},
                                 {"radii": (0.0, 1.0)}, {"group_swarms": 0}])
def test_teams_and_radii_must_be_drones_and_a_range(bad):
    with pytest.raises(ValueError, match="DAGNNTrainConfig"):
        DAGNNTrainConfig(**bad)


def test_local_features_per_neighbour_are_the_sums_divided_by_the_degree_and_do_not_grow_with_density():
    """per_neighbour: each of eq. 4's sums over N_i divided by |N_i| (1 for a drone without neighbours, whose
    sums are 0). Doubling every neighbour (a second drone at the same place and velocity) doubles the sums
    and leaves the means unchanged."""
    from vgai_lite.features import local_features
    from vgai_lite.graphs import adjacency
    gen = torch.Generator().manual_seed(0)
    r, v = torch.randn(2, 7, 2, generator=gen), torch.randn(2, 7, 2, generator=gen)
    r[0, 6] = torch.tensor([50.0, 50.0])  # alone
    sums, means = local_features(r, v, 1.5), local_features(r, v, 1.5, per_neighbour=True)
    degree = adjacency(r, 1.5).sum(-1, keepdim=True)
    torch.testing.assert_close(means * degree.clamp(min=1), sums)
    assert torch.equal(means[0, 6], torch.zeros(6))
    i = 0  # drone 0 with its neighbours doubled (offset by 1 mm, beyond the distance floor)
    r2 = torch.cat((r[:1], r[:1, 1:] + 1e-3), 1)
    v2 = torch.cat((v[:1], v[:1, 1:]), 1)
    torch.testing.assert_close(local_features(r2, v2, 1.5, per_neighbour=True)[0, i],
                               local_features(r[:1], v[:1], 1.5, per_neighbour=True)[0, i], rtol=0.05, atol=0.05)


def test_a_dagnn_with_mean_features_sees_the_sums_divided_by_the_degree():
    from vgai_lite.features import local_features
    model = AggregationMLP(3, 6, (8,))
    cfg = FlockConfig(N=12)
    r, v = sample_initial_state(cfg, 2, torch.Generator().manual_seed(0))
    ctrl = DAGNNController(model, cfg, feature_transform="per_neighbour")
    torch.testing.assert_close(ctrl.features(r, v), local_features(r, v, cfg.R, per_neighbour=True))
    assert not torch.allclose(ctrl.features(r, v), local_features(r, v, cfg.R))

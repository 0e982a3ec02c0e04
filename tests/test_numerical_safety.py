"""No silent NaN: bad states are refused with the place they went bad, and no state makes one.

The property test flies 10,000 random initial conditions (coincident agents, near-collisions,
isolated agents, fast and still swarms) under the expert, Local, the DAGNN and VGAI.
"""

import math

import pytest
import torch

from vgai_lite.book import DATA_DIR
from vgai_lite.checkpoints import load_controller
from vgai_lite.config import DISTANCE_FLOOR, FlockConfig
from vgai_lite.controllers import ExpertController, LocalController, expert_control, local_control, potential
from vgai_lite.features import local_features
from vgai_lite.flocking import NonFiniteStateError, rollout, step
from vgai_lite.graphs import adjacency

CFG = FlockConfig()


@pytest.fixture(scope="module")
def learned():
    return {"DAGNN": load_controller(DATA_DIR / "dagnn" / "dagnn_K4.pt"),
            "VGAI": load_controller(DATA_DIR / "vgai" / "vgai_F24.pt")}


def _state(N=4, B=2, seed=0):
    g = torch.Generator().manual_seed(seed)
    return torch.rand(B, N, 2, generator=g) * 2, torch.randn(B, N, 2, generator=g)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_every_state_taking_function_names_the_first_non_finite_agent(bad, learned):
    r, v = _state()
    r[1, 2, 0] = bad
    calls = {"expert_control": lambda: expert_control(r, v, CFG), "local_control": lambda: local_control(r, v, CFG),
             "local_features": lambda: local_features(r, v, CFG.R), "adjacency": lambda: adjacency(r, CFG.R),
             "step": lambda: step(r, v, torch.zeros_like(r), CFG), "rollout": lambda: rollout(ExpertController(CFG), CFG, r, v, 2)}
    for name, c in learned.items():
        c.reset()
        calls[name] = lambda c=c: c(r, v)
    for name, call in calls.items():
        with pytest.raises(NonFiniteStateError, match="swarm 1, agent 2") as info:
            call()
        assert (info.value.swarm, info.value.agent) == (1, 2), name
    r, v = _state()
    v[0, 3, 1] = bad
    with pytest.raises(NonFiniteStateError, match="v is not finite"):
        expert_control(r, v, CFG)


def test_rollout_stops_at_the_step_and_agent_where_the_flight_went_bad():
    r, v = _state(N=5)
    calls = []

    def breaks_at_step_4(r, v):
        calls.append(1)
        u = torch.zeros_like(r)
        if len(calls) == 5:
            u[0, 3, 1] = math.nan
        return u

    with pytest.raises(NonFiniteStateError, match="at step 4: swarm 0, agent 3") as info:
        rollout(breaks_at_step_4, CFG, r, v, steps=10)
    assert info.value.step == 4 and len(calls) == 5
    # a finite acceleration whose state overflows float32 is caught one step later, where it happened
    with pytest.raises(NonFiniteStateError, match=r"the state \(r, v\) is not finite at step 1: swarm 0, agent 0"):
        rollout(lambda r, v: torch.zeros_like(r), FlockConfig(Ts=1e30), r, v * 0 + torch.tensor([1e20, 0.0]), steps=3)


def test_coincident_agents_give_finite_commands_and_no_push_between_them():
    r = torch.tensor([[[0.0, 0.0], [0.0, 0.0], [0.3, 0.0]]])
    v = torch.tensor([[[1.0, 0.0], [1.0, 0.0], [1.0, 0.0]]])
    cfg = CFG.replace(N=3)
    for u in (expert_control(r, v, cfg), local_control(r, v, cfg), local_features(r, v, cfg.R)):
        assert torch.isfinite(u).all()
    # agents 0 and 1 are pushed away from agent 2 only, along -x, equally
    u = expert_control(r, v, cfg)
    assert torch.equal(u[0, 0], u[0, 1]) and u[0, 0, 0] < 0 and u[0, 0, 1] == 0
    assert torch.isfinite(potential(torch.zeros(1), cfg)).all()


def test_the_distance_floor_changes_nothing_above_it():
    """Above 1 mm the potential and features are eq. 3's and section 3.2's exactly."""
    d2 = torch.tensor([DISTANCE_FLOOR ** 2 * 1.01, 0.01, 0.2])
    assert torch.equal(potential(d2, CFG), 1 / d2 - torch.log(d2))
    r = torch.tensor([[[0.0, 0.0], [0.002, 0.0]]])
    X = local_features(r, torch.zeros_like(r), CFG.R)
    assert torch.allclose(X[0, 0, 2], torch.tensor(-0.002 / 0.002 ** 4))


def test_learned_controllers_build_no_autograd_graph_unless_asked(learned):
    r, v = _state(N=6)
    for name, c in learned.items():
        c.reset()
        with torch.enable_grad():
            u = c(r, v)
        assert u.grad_fn is None and not u.requires_grad, name
        c.reset()
        c.gradients = True
        try:
            with torch.enable_grad():
                u = c(r, v)
            assert u.requires_grad, name
        finally:
            c.gradients = False


def _random_swarms(N: int, B: int, g: torch.Generator) -> tuple[torch.Tensor, torch.Tensor]:
    """B swarms of N agents: positions on discs of 1 cm to 4 m; a quarter with two coincident agents,
    a quarter with a pair 1e-7 to 1e-2 m apart; velocities up to 10 m/s, a tenth of the swarms at rest."""
    radius = 10 ** (torch.rand(B, 1, 1, generator=g) * 2.6 - 2)
    r = (torch.rand(B, N, 2, generator=g) * 2 - 1) * radius
    kind = torch.randint(0, 4, (B,), generator=g)
    r[kind == 0, 1] = r[kind == 0, 0]
    gap = 10 ** (torch.rand(B, 1, generator=g) * 5 - 7)
    angle = torch.rand(B, 1, generator=g) * 2 * math.pi
    near = r[:, 0] + gap * torch.cat((angle.cos(), angle.sin()), dim=-1)
    r[kind == 1, 1] = near[kind == 1]
    v = (torch.rand(B, N, 2, generator=g) * 2 - 1) * 10 ** (torch.rand(B, 1, 1, generator=g) * 2 - 1)
    v[torch.rand(B, generator=g) < 0.1] = 0
    return r, v


VGAI_STARTS_PER_N = 250
"""VGAI flies the first 250 starts of each N in the property test below (the kinds of start are drawn
independently per swarm, so each kind is among them about 60 times)."""


@pytest.mark.slow
def test_property_ten_thousand_random_starts_never_make_a_nan(learned):
    """10,000 initial conditions (N = 2, 3, 4, 6; 2,500 each) flown by the expert, Local and the DAGNN
    (20 steps), and the first 1,000 of them (250 per N, every kind of start among them) by VGAI (3 steps,
    as it renders every view: its frames before t = 0, its motion input and two exchanges; all 10,000
    took VGAI two minutes, most of this file's time): every state, action and cost is finite (rollout
    would raise at the first that is not)."""
    g = torch.Generator().manual_seed(15)
    total = 0
    for N in (2, 3, 4, 6):
        cfg = CFG.replace(N=N, min_neighbours=0)
        r, v = _random_swarms(N, 2500, g)
        total += len(r)
        flights = {"expert": (ExpertController(cfg), 20), "Local": (LocalController(cfg), 20),
                   "DAGNN": (load_controller(DATA_DIR / "dagnn" / "dagnn_K4.pt", cfg=cfg), 20),
                   "VGAI": (load_controller(DATA_DIR / "vgai" / "vgai_F24.pt", cfg=cfg), 3)}
        for name, (controller, steps) in flights.items():
            B = VGAI_STARTS_PER_N if name == "VGAI" else len(r)
            traj = rollout(controller, cfg, r[:B], v[:B], steps=steps)
            for label, x in (("r", traj.r), ("v", traj.v), ("u", traj.u), ("cost", traj.cost),
                             ("min_distance", traj.min_distance)):
                assert torch.isfinite(x).all(), f"{name}, N = {N}: {label} not finite"
    assert total == 10_000

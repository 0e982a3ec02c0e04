"""Throughput of the simulator: agent-steps per second of ``step`` + ``expert_control``.

Run ``python -m vgai_lite benchmark``. An agent-step is one agent advanced by one time step with
the expert's action computed. The unbatched numpy loop below is a plain one-swarm implementation of
the same equations, written the way a per-swarm environment (such as gym-flock) computes them: it
is the baseline the batched torch simulator is compared against on the same machine.
"""

from __future__ import annotations

import dataclasses
import inspect
import json
import time
from pathlib import Path

import numpy as np
import torch
from torch.utils.benchmark import Timer as TorchTimer

from ..config import FlockConfig
from ..controllers import expert_control
from ..evaluate import relative_cost
from ..flocking import sample_initial_state, step
from ..aggregation import AggregationBuffer
from ..graphs import adjacency, gso
from ..imitation import ROUND_CHECK_SEED_OFFSET, EpisodeStore
from ..learned_controllers import VGAIController
from ..physics import raycast_depth
from ..render import RenderConfig, egocentric_depth, render_egocentric, render_topdown
from ..camera import draw_camera
from ..vision import camera_input
from ..vgai_config import BOOK, VGAITrainConfig
from ..vgai_training import fit_state_estimator, joint_loss, sample_windows, train_vgai, window_batch


def _numpy_expert_step(x: np.ndarray, cfg: FlockConfig) -> np.ndarray:
    """One swarm, state x = [r, v] of shape (N, 4): expert action, then one step (numpy)."""
    diff = x[:, None, :] - x[None, :, :]
    r2 = diff[:, :, 0] ** 2 + diff[:, :, 1] ** 2
    np.fill_diagonal(r2, np.inf)
    inside = r2 <= cfg.rho ** 2
    w = np.where(inside, 2.0 / r2 ** 2 + 2.0 / r2, 0.0)
    u = np.stack((-diff[:, :, 2].sum(1) + (w * diff[:, :, 0]).sum(1),
                  -diff[:, :, 3].sum(1) + (w * diff[:, :, 1]).sum(1)), axis=1)
    u = np.clip(u, -cfg.u_max, cfg.u_max)
    out = x.copy()
    out[:, :2] += x[:, 2:] * cfg.Ts + u * 0.5 * cfg.Ts ** 2
    out[:, 2:] += u * cfg.Ts
    return out


def _time(fn, min_seconds: float) -> tuple[int, float]:
    """(calls, seconds) of ``fn`` run for at least ``min_seconds`` after a warm-up
    (``torch.utils.benchmark``, at the threads torch uses now)."""
    m = TorchTimer("fn()", globals={"fn": fn}, num_threads=torch.get_num_threads()).blocked_autorange(
        min_run_time=min_seconds)
    return len(m.raw_times) * m.number_per_run, sum(m.raw_times) * m.number_per_run


def run(N: int = 50, batches=(1, 256), steps: int = 20, min_seconds: float = 2.0,
        dtype=torch.float32, device=None) -> list[dict]:
    """Measure agent-steps/s for the numpy baseline and the torch simulator at each batch size."""
    cfg = FlockConfig(N=N)
    rows = []
    r, v = sample_initial_state(cfg, 1, torch.Generator().manual_seed(0), dtype=torch.float64)
    x0 = torch.cat((r[0], v[0]), dim=-1).numpy()

    def numpy_run():
        x = x0
        for _ in range(steps):
            x = _numpy_expert_step(x, cfg)

    n, sec = _time(numpy_run, min_seconds)
    rows.append({"impl": "numpy, one swarm (baseline)", "batch": 1, "N": N,
                 "agent_steps_per_s": n * steps * N / sec})
    for B in batches:
        r, v = sample_initial_state(cfg, B, torch.Generator().manual_seed(1), dtype=dtype, device=device)

        @torch.no_grad()
        def torch_run():
            rr, vv = r, v
            for _ in range(steps):
                rr, vv = step(rr, vv, expert_control(rr, vv, cfg), cfg)
            if rr.is_cuda:
                torch.cuda.synchronize()

        n, sec = _time(torch_run, min_seconds)
        rows.append({"impl": f"torch {str(dtype).replace('torch.', '')}", "batch": B, "N": N,
                     "agent_steps_per_s": n * steps * N * B / sec})
    base = rows[0]["agent_steps_per_s"]
    for row in rows:
        row["speedup_vs_baseline"] = row["agent_steps_per_s"] / base
    return rows


def run_render(swarms: int = 64, N: int = 50, min_seconds: float = 2.0, device=None) -> list[dict]:
    """Agent-images per second of both renderers (default RenderConfig) and of the pymunk ray caster
    producing the same depth strip (one swarm at a time, as pymunk works)."""
    cfg, rcfg = FlockConfig(N=N), RenderConfig()
    r, _ = sample_initial_state(cfg, swarms, torch.Generator().manual_seed(0), device=device)
    rows = []
    for name, fn in (("egocentric panorama", lambda: render_egocentric(r, cfg, rcfg)),
                     ("egocentric depth strip", lambda: egocentric_depth(r, rcfg)),
                     ("top-down crop", lambda: render_topdown(r, cfg, rcfg))):
        n, sec = _time(fn, min_seconds)
        rows.append({"renderer": name, "agent_images_per_s": n * swarms * N / sec})
    r64 = r[0].double().cpu()
    n, sec = _time(lambda: raycast_depth(r64, rcfg), min_seconds)
    rows.append({"renderer": "pymunk ray caster, depth strip", "agent_images_per_s": n * N / sec})
    return rows


SCALING_TEAMS = (50, 100, 200, 400)
"""Team sizes of ``run_render_scaling``."""


def run_render_scaling(nearest: int = 49, teams=SCALING_TEAMS, swarms: int = 4, min_seconds: float = 1.0,
                       device=None) -> list[dict]:
    """Microseconds per drone image of the panorama against the team size N, drawing every drone and
    drawing each drone's ``nearest`` nearest (``RenderConfig.nearest``); the same initial states
    (sample_initial_state, "repair" from N = 100 as the evaluation draws large teams) for both."""
    rows = []
    for N in teams:
        cfg = FlockConfig(N=N, init_method="repair" if N >= 100 else "reject")
        r, _ = sample_initial_state(cfg, swarms, torch.Generator().manual_seed(0), device=device)
        row = {"N": N}
        for key, rcfg in (("all_us", RenderConfig()), ("nearest_us", RenderConfig(nearest=nearest))):
            n, sec = _time(lambda: render_egocentric(r, cfg, rcfg), min_seconds)
            row[key] = 1e6 * sec / (n * swarms * N)
        rows.append(row)
    return rows


@torch.no_grad()
def run_flight_profile(teams=(50, 200), swarms: int = 2, nearest: int = 49, min_seconds: float = 0.5,
                       device=None) -> list[dict]:
    """Where one step of a VGAI flight goes, against the team size: microseconds per drone and step of
    each part (the book's VGAI, ``BOOK``, untrained: the time does not depend on the weights), with the
    panorama drawn for every drone and for each drone's ``nearest`` nearest. The O(N^2) parts are those
    whose time per drone grows with N: the GSO (every pair's distance), the expert's action of eq. 2 (the
    centralized teacher, flown for the cost) and the panorama drawing every drone."""
    model = BOOK.new_model().to(device).eval()
    culled = dataclasses.replace(BOOK.vision, render=dataclasses.replace(BOOK.vision.render, nearest=nearest))
    rows = []
    for N in teams:
        cfg = FlockConfig(N=N, init_method="repair" if N >= 100 else "reject")
        r, v = sample_initial_state(cfg, swarms, torch.Generator().manual_seed(0), device=device)
        images = camera_input(BOOK.vision, cfg, r, r, None)
        X = model.features(images)
        S = gso(adjacency(r, cfg.R), BOOK.gso)
        buffer = AggregationBuffer(BOOK.K)
        parts = {"panorama and motion frame, every drone": lambda: camera_input(BOOK.vision, cfg, r, r, None),
                 f"panorama and motion frame, {nearest} nearest": lambda: camera_input(culled, cfg, r, r, None),
                 "CNN": lambda: model.features(images),
                 "GSO S(t) (every pair's distance)": lambda: gso(adjacency(r, cfg.R), BOOK.gso),
                 "aggregation (eq. 6) and MLP": lambda: model.mlp(buffer.push(X, S)),
                 "the expert's action (eq. 2, for the cost)": lambda: expert_control(r, v, cfg),
                 "physics step": lambda: step(r, v, torch.zeros_like(v), cfg)}
        for part, fn in parts.items():
            n, sec = _time(fn, min_seconds)
            rows.append({"N": N, "part": part, "us_per_drone_step": 1e6 * sec / (n * swarms * N)})
    return rows


CHECK_EPISODES = inspect.signature(train_vgai).parameters["check_episodes"].default
"""Episodes of each round check of a training (``train_vgai``'s default)."""


def run_vgai_training(steps: int = 30, episodes: int = 4, tcfg=None) -> dict:
    """Seconds per gradient step of VGAI's stage 1 (visual state estimation) and stage 3 (joint
    K-step BPTT), and per evaluation episode, at the book's VGAI (``BOOK``); projects the time of
    a full default training from them (flight collection and round checks included)."""
    cfg, tcfg = FlockConfig(), tcfg or BOOK
    gen = torch.Generator().manual_seed(0)
    r0, v0 = sample_initial_state(cfg, episodes, gen)
    start = time.perf_counter()
    store = EpisodeStore()
    store.fly(None, cfg, r0, v0, 0.0, gen)
    r, v, u = store.tensors()
    collect_expert = (time.perf_counter() - start) / episodes
    model = tcfg.new_model()
    start = time.perf_counter()
    fit_state_estimator(model.cnn, cfg, dataclasses.replace(tcfg, warm_steps=steps), store.groups(), gen, progress=False)
    stage1 = (time.perf_counter() - start) / steps
    opt = torch.optim.Adam(model.parameters(), lr=tcfg.lr)
    model.train()
    parts = {"render": 0.0, "forward": 0.0, "backward": 0.0}  # where a joint step's time goes
    for _ in range(steps):
        t0 = time.perf_counter()
        cam = draw_camera(tcfg.camera, tcfg.vision.render, tcfg.windows, cfg.N, gen)  # as joint_round draws them
        batch = window_batch(cfg, tcfg, r, v, u, *sample_windows(r.shape[0], r.shape[1], tcfg, gen),
                             cam.repeat(tcfg.K).at(0) if cam is not None else None)
        t1 = time.perf_counter()
        loss = joint_loss(model, tcfg, batch)
        t2 = time.perf_counter()
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        t3 = time.perf_counter()
        parts["render"] += t1 - t0
        parts["forward"] += t2 - t1
        parts["backward"] += t3 - t2
    stage3 = sum(parts.values()) / steps
    model.eval()
    learner = VGAIController(model, cfg, tcfg.vision, tcfg.gso)
    start = time.perf_counter()
    relative_cost(learner, cfg, episodes=episodes, seed=tcfg.seed + ROUND_CHECK_SEED_OFFSET, flock_times=())  # as a round check flies
    episode = (time.perf_counter() - start) / episodes  # the learner and the expert flying one episode
    flights = tcfg.expert_episodes * collect_expert + tcfg.dagger_rounds * tcfg.episodes_per_round * episode
    checks = (tcfg.dagger_rounds + 1) * CHECK_EPISODES * episode
    projected = tcfg.warm_steps * stage1 + tcfg.dagger_rounds * tcfg.joint_steps * stage3 + flights + checks
    return {"stage1_step_s": stage1, "joint_step_s": stage3, **{f"joint_{k}_s": x / steps for k, x in parts.items()},
            "eval_episode_s": episode,
            "expert_episode_s": collect_expert, "projected_training_s": projected}


def main(args=None) -> None:
    if args is not None and getattr(args, "vgai", False):
        recipe, label = BOOK, "the book's VGAI (BOOK)"
        if getattr(args, "train_config", None):  # a training record's configuration, e.g. one through a camera
            recipe = VGAITrainConfig.from_dict(json.loads(Path(args.train_config).read_text())["train_config"])
            label = f"the training of {args.train_config}"
        out = run_vgai_training(tcfg=recipe)
        print(f"torch {torch.__version__}, {torch.get_num_threads()} threads, {label}")
        t, N = recipe, FlockConfig().N
        print(f"stage 1 step ({t.warm_states} swarm states x {N} images): {out['stage1_step_s']:.3f} s")
        print(f"joint BPTT step ({t.windows} windows x {t.K} steps x {N} images): {out['joint_step_s']:.3f} s: "
              f"rendering and cameras {out['joint_render_s']:.3f}, forward {out['joint_forward_s']:.3f}, "
              f"backward and Adam {out['joint_backward_s']:.3f}")
        print(f"one evaluation episode (VGAI + expert, 200 steps, N = {N}): {out['eval_episode_s']:.2f} s")
        print(f"projected training ({t.warm_steps:,} + {t.dagger_rounds} x {t.joint_steps} steps, flights, round checks): "
              f"{out['projected_training_s'] / 60:.1f} min")
        return
    rows = run()
    print(f"torch {torch.__version__}, {torch.get_num_threads()} threads")
    print(f"{'implementation':32s} {'batch':>6s} {'N':>4s} {'agent-steps/s':>15s} {'vs baseline':>12s}")
    for row in rows:
        print(f"{row['impl']:32s} {row['batch']:6d} {row['N']:4d} {row['agent_steps_per_s']:15,.0f} "
              f"{row['speedup_vs_baseline']:11.1f}x")
    rc = RenderConfig()
    print(f"\nrenderers, 64 swarms x 50 agents, panorama {rc.view_height} x {rc.panorama_width} "
          f"(4 cameras of {rc.view_height} x {rc.view_width}), {len(rc.channels)} channels; "
          f"top-down {rc.topdown_size} x {rc.topdown_size}")
    rrows = run_render()
    strip = next(x for x in rrows if x["renderer"] == "egocentric depth strip")["agent_images_per_s"]
    for row in rrows:
        print(f"{row['renderer']:32s} {row['agent_images_per_s']:12,.0f} agent-images/s")
    ray = rrows[-1]["agent_images_per_s"]
    print(f"depth strip: torch / pymunk = {strip / ray:.0f}x")
    nearest = 49
    print(f"\npanorama, microseconds per drone image against the team, 4 swarms; every drone drawn / "
          f"each drone's {nearest} nearest (RenderConfig(nearest={nearest}))")
    srows = run_render_scaling(nearest)
    for row in srows:
        print(f"N = {row['N']:4d}: {row['all_us']:7.1f} / {row['nearest_us']:7.1f}")
    first, last = srows[0], srows[-1]
    print(f"N = {last['N']} against N = {first['N']}: {last['all_us'] / first['all_us']:.2f}x every drone, "
          f"{last['nearest_us'] / first['nearest_us']:.2f}x the {nearest} nearest")
    prof = run_flight_profile(nearest=nearest)
    small, large = min(x["N"] for x in prof), max(x["N"] for x in prof)
    print(f"\none step of a VGAI flight (the book's), microseconds per drone: N = {small} / N' = {large}")
    for part in dict.fromkeys(x["part"] for x in prof):
        a, b = (next(x["us_per_drone_step"] for x in prof if x["part"] == part and x["N"] == n) for n in (small, large))
        print(f"{part:46s} {a:8.1f} / {b:8.1f}  ({b / a:.2f}x)")

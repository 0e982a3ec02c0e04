"""Experiment: what keeps VGAI's velocities apart late in a flight? Damping against forcing.

    python tools/experiments/consensus_limit.py --out data/experiments/consensus_limit.json
    python tools/experiments/consensus_limit.py --N 200 --checkpoints data/dagnn/dagnn_K4.pt,data/vgai/vgai_F24.pt \
        --out data/experiments/consensus_limit_N200.json   (given checkpoints, flown in teams of N, radius R)

The velocity variance V = (1/N) sum_i ||v_i - vbar||^2 changes by dV/dt = (2/N) sum_i (v_i - vbar).(u_i - ubar):
it falls only where the actions oppose the drones' velocity disagreements. So we ask two questions
of each controller, at states of its own held-out 500-step flights (t = 2 s and 5 s, 10 episodes),
with two counterfactual histories of the same formation r(t), flown at constant velocity for the K
steps that fill the delayed aggregation (and the motion frames before them):

  u_rest   every drone at the swarm's mean velocity vbar (no disagreement at all)
  u_moving every drone at its own velocity v_i(t)

  damping gain  gamma = - sum_i dv_i.(u_moving_i - u_rest_i) / sum_i ||dv_i||^2   (1/s), dv_i = v_i - vbar
                how hard the controller brakes a velocity disagreement it sees (expert: N = 50 before
                saturation; a gain gamma alone would shrink V as exp(-2 gamma t))
  forcing at rest  f = rms_i (u_rest_i - mean u_rest)   (m/s^2)
                how hard it pushes drones apart in velocity when they already agree (the expert: only the
                potential's pushes, 0 once the formation is at rest)

The expert is left out: its flights align to within rounding (dv = 0), and its gain is N = 50 with no
forcing at rest, by eq. 2. A controller flocks when f is small against gamma: a disagreement of speed s costs gamma s of
braking, so the velocity spread settles where the two balance, near (f / gamma)^2 in variance.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from vgai_lite import FlockConfig, load_controller, rollout, sample_initial_state  # noqa: E402
from vgai_lite.book import DATA_DIR, WORKING_SEED  # noqa: E402
from vgai_lite.lab.reproduce import ReproduceConfig, flight_config  # noqa: E402
from vgai_lite.lab.provenance import Provenance, repo_relative, sha256  # noqa: E402

VGAIS = {"VGAI on clean frames without the learner flying alone (DAgger's mixture only), training seed 0": "experiments/vgai_F24_mixture.pt",
         "VGAI, ablation row 1 (the paper's CNN, loss and mixture; the book's sensor and warm starts)":
             "experiments/vgai_F24_plain.pt",
         "the paper's VGAI (one gray frame), training seed 0": "experiments/vgai_paper_seed0.pt",
         "VGAI through the camera, gray + depth (vgai_depthcam: the book's recipe), training seed 0":
             "experiments/vgai_depthcam.pt",
         "VGAI through the camera, gray only (vgai_camera_narrow_gray), training seed 0":
             "experiments/vgai_camera_narrow_gray.pt"}
"""The VGAIs flown beside the recipe on clean frames (its three training seeds, data/experiments/vgai_clean_seedS;
the book's VGAI until the camera model), by label."""
from vgai_lite.flocking import velocity_variance  # noqa: E402

TIMES = (2.0, 5.0)
RESAMPLES = 2000


def median_ci95(x: torch.Tensor, resamples: int = RESAMPLES, seed: int = 0) -> list:
    """Bootstrap 95 % interval of the median of per-flight values x (episodes,): the interval
    ``findings.compare`` reads (key ``ci95``), so a gain or a forcing is told apart by the book's one rule."""
    idx = torch.randint(len(x), (resamples, len(x)), generator=torch.Generator().manual_seed(seed))
    meds = x[idx].median(dim=1).values
    return [round(float(meds.quantile(0.025)), 5), round(float(meds.quantile(0.975)), 5)]


@torch.no_grad()
def probe(controller, cfg: FlockConfig, r: torch.Tensor, vel: torch.Tensor, K: int) -> torch.Tensor:
    """The action at formation r (B, N, 2) after a history of K steps flown at constant velocities
    vel (B, N, 2) (the motion frames before it drawn the same way): (B, N, 2)."""
    if hasattr(controller, "reset"):
        controller.reset()
    u = None
    for k in range(K):
        u = controller(r - (K - 1 - k) * cfg.Ts * vel, vel)
    return u.clamp(-cfg.u_max, cfg.u_max)


@torch.no_grad()
def damping_and_forcing(controller, cfg: FlockConfig, episodes: int = 10, seed: int = WORKING_SEED) -> dict:
    r0, v0 = sample_initial_state(cfg, episodes, torch.Generator().manual_seed(seed))
    steps = int(round(max(TIMES) / cfg.Ts)) + 1
    traj = rollout(controller, cfg, r0, v0, steps=steps)
    K = getattr(controller, "K", 1)
    out = {}
    for t in TIMES:
        i = int(round(t / cfg.Ts))
        r, v = traj.r[i], traj.v[i]
        vbar = v.mean(dim=1, keepdim=True).expand_as(v)
        dv = v - vbar
        u_rest, u_moving = probe(controller, cfg, r, vbar, K), probe(controller, cfg, r, v, K)
        gamma = -(dv * (u_moving - u_rest)).sum((1, 2)) / dv.square().sum((1, 2))
        force = (u_rest - u_rest.mean(dim=1, keepdim=True)).square().sum(-1).mean(-1).sqrt()
        var = velocity_variance(traj.v[i:i + 1])[0]
        out[f"{t:g}s"] = {"velocity_variance_median": float(var.median()),
                          "relative_speed_rms_median": float(var.sqrt().median()),
                          "damping_gain_median": float(gamma.median()),
                          "damping_gain_median_ci95": median_ci95(gamma),
                          "forcing_at_rest_rms_median": float(force.median()),
                          "forcing_at_rest_rms_median_ci95": median_ci95(force),
                          "balance_variance_median": float(((force / gamma.clamp(min=1e-6)) ** 2).median())}
    return out


def report(label: str, res: dict) -> None:
    print(label, flush=True)
    for t, x in res.items():
        print(f"  {t}: variance {x['velocity_variance_median']:.2e}, damping gain {x['damping_gain_median']:.2f} /s, "
              f"forcing at rest {x['forcing_at_rest_rms_median']:.3f} m/s², (f/gamma)² {x['balance_variance_median']:.2e}",
              flush=True)


def fly_given(args, cfg: FlockConfig, paths: list, argv) -> int:
    """Damping and forcing of the given checkpoints in teams of cfg.N at radius cfg.R (what limits a controller
    flown beyond its training's team or radius); the expert's own gain there is N, by eq. 2."""
    for path in paths:
        if not path.is_file():
            raise SystemExit(f"--checkpoints: no checkpoint at {path}")
    command = " ".join(["python tools/experiments/consensus_limit.py"] + (argv or sys.argv[1:]))
    out = {"command": command, "episodes": args.episodes, "seed": args.seed, "N": cfg.N, "R": cfg.R,
           "expert_damping_gain": cfg.N, "controllers": {}}
    with Provenance(command) as prov:
        for path in paths:
            # the controller's graph (and a VGAI's camera) in the flight's team and radius, as reproduce flies a column
            res = damping_and_forcing(load_controller(path, cfg=cfg), cfg, args.episodes, seed=args.seed)
            out["controllers"][path.stem] = res
            report(path.stem, res)
    out["provenance"] = prov.record(seed=args.seed, episodes=args.episodes,
                                    checkpoints={repo_relative(p): sha256(p) for p in paths})
    if args.out:
        Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--episodes", type=int, default=10)
    p.add_argument("--out", default=None)
    p.add_argument("--N", type=int, default=None, help="team size flown (default: the book's N)")
    p.add_argument("--R", type=float, default=None, help="communication radius flown, m (default: the book's R)")
    p.add_argument("--seed", type=int, default=WORKING_SEED, help="seed of the episodes' initial conditions")
    p.add_argument("--checkpoints", default=None, metavar="PATH,PATH",
                   help="fly only these controllers (labelled by file name) instead of the book's set")
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    cfg = FlockConfig()
    if args.N is not None or args.R is not None:  # a table's column, flown as reproduce flies it
        rc = ReproduceConfig()
        cfg = flight_config(rc, "N", args.N) if args.N is not None else flight_config(rc, "R", args.R)
        cfg = dataclasses.replace(cfg, R=args.R) if args.R is not None else cfg
    if args.checkpoints:
        return fly_given(args, cfg, [Path(x) for x in args.checkpoints.split(",")], argv)
    from estimator_in_the_loop import VisionDAGNN, odd_estimator  # the modular vision pilot

    dagnn = load_controller(DATA_DIR / "dagnn" / "dagnn_K4.pt")
    read = [DATA_DIR / "dagnn" / "dagnn_K4.pt", DATA_DIR / "experiments" / "estimator_odd8_synth0.5.pt"]
    pilots = {"DAGNN (K - 1 = 3)": dagnn,
              "modular vision pilot (odd estimator -> DAGNN's MLP)": VisionDAGNN(dagnn, *odd_estimator(cfg))}
    for path in sorted((DATA_DIR / "experiments").glob("vgai_clean_seed*.pt")):
        pilots[f"VGAI, the recipe on clean frames, training seed {path.stem.rsplit('seed', 1)[1]}"] = load_controller(path)
        read.append(path)
    for label, rel in VGAIS.items():
        pilots[label] = load_controller(DATA_DIR / rel)
        read.append(DATA_DIR / rel)
    command = " ".join(["python tools/experiments/consensus_limit.py"] + (argv or sys.argv[1:]))
    out = {"command": command, "episodes": args.episodes, "seed": WORKING_SEED, "controllers": {}}
    with Provenance(command) as prov:
        for label, c in pilots.items():
            res = damping_and_forcing(c, cfg, args.episodes)
            out["controllers"][label] = res
            report(label, res)
    out["provenance"] = prov.record(seed=WORKING_SEED, episodes=args.episodes,
                                    checkpoints={repo_relative(p): sha256(p) for p in read})
    if args.out:
        Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

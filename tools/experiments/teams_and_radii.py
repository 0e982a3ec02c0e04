"""Experiment: a controller trained on one team and radius, or on many, flown across the teams and
radii of Tables 2b and 3 (issue: one controller for every team and radius).

    python tools/experiments/teams_and_radii.py --name dagnn_teams --teams 50,100,200 --radii 1.0,2.0
    python tools/experiments/teams_and_radii.py --name dagnn_K4 --evaluate data/dagnn/dagnn_K4.pt
    python tools/experiments/teams_and_radii.py --name vgai_depthcam_nearest49 --evaluate data/experiments/vgai_depthcam.pt --nearest 49

Trains the book's DAGNN (``DAGNNTrainConfig()``, K - 1 = 3) with its swarms flown in groups whose N
is drawn from ``--teams`` and R uniformly from ``--radii`` (``imitation.flight_groups``), or
evaluates a checkpoint, then flies it on validation episodes (``book.VALIDATION_SEED``: this is a
choice, so never the test episodes) at every N' of ``--fly-teams`` (R = 1.5 m) and every R of
``--fly-radii`` (N = 50), as ``reproduce.flight_config`` flies the tables' columns. Writes
``data/experiments/NAME_teams.json`` (and the checkpoint ``NAME.pt`` when it trains): per cell the
relative cost with its interval, the velocity variance at 5 s, connectivity at 5 s, closest approaches, and
the share of episodes whose graph is connected at t = 0 (``consensus.connected_at_start``) with the
share of those it keeps connected.
``--test`` flies a controller chosen on them on the test episodes instead (reporting only).
``--nearest K`` flies a VGAI with a renderer that draws only each drone's K nearest drones
(``RenderConfig.nearest``): in a team larger than it trained in, the panorama it trained on.
``--teacher K`` trains the DAGNN to imitate the K-hop oracle of ``khop_oracle.py`` (the expert's gain on the exact
mean velocity within K hops, the expert's potential) instead of the centralized expert of eq. 2: a measurement
of what limits a DAGNN at R = 1 m (a teacher no local controller can follow, or the learner), not the paper's
method. The checkpoint's own training configuration does not name the teacher; the record does.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import sys
from pathlib import Path
from unittest import mock

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from vgai_lite import DAGNNTrainConfig, FlockConfig, load_controller, relative_cost, train_dagnn  # noqa: E402
from vgai_lite.book import DATA_DIR, TEST_SEED, VALIDATION_SEED  # noqa: E402
from vgai_lite.consensus import connected_at_start  # noqa: E402
from vgai_lite.lab.provenance import Provenance  # noqa: E402
from vgai_lite.lab.reproduce import ReproduceConfig, flight_config  # noqa: E402
from vgai_lite import imitation  # noqa: E402
from khop_oracle import KHopOracle  # noqa: E402


def _numbers(text: str, kind):
    return tuple(kind(x) for x in text.split(",") if x)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--name", required=True)
    p.add_argument("--teams", default="", help="N drawn per group of training swarms, e.g. 50,100,200")
    p.add_argument("--radii", default="", help="low,high: R (m) drawn uniformly per group, e.g. 1.0,2.0")
    p.add_argument("--K", type=int, default=None, help="the DAGNN's taps (K - 1 exchanges; default DAGNNTrainConfig's 4)")
    p.add_argument("--seed", type=int, default=None, help="the training's seed (default DAGNNTrainConfig's 0)")
    p.add_argument("--feature-transform", default=None, help="the DAGNN's feature transform (none, signed_log, per_neighbour)")
    p.add_argument("--evaluate", default=None, metavar="CKPT", help="no training: fly this checkpoint")
    p.add_argument("--fly-teams", default="50,100,200")
    p.add_argument("--fly-radii", default="1.0,2.0")
    p.add_argument("--episodes", type=int, default=10, help="validation episodes per cell")
    p.add_argument("--test", action="store_true",
                   help="report a controller chosen before on the test episodes (book.TEST_SEED; writes NAME_teams_test.json)")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--teacher", type=int, default=None, metavar="K",
                   help="train the DAGNN on the K-hop oracle's actions (khop_oracle.KHopOracle) instead of the expert's")
    p.add_argument("--nearest", type=int, default=None, metavar="K",
                   help="a VGAI's renderer draws only each drone's K nearest drones (RenderConfig.nearest; "
                        "default: as trained, every drone)")
    args = p.parse_args(argv)
    torch.set_num_threads(args.threads)
    command = " ".join(["python tools/experiments/teams_and_radii.py"] + (argv or sys.argv[1:]))
    folder = DATA_DIR / "experiments"
    out = {"command": command, "nearest": args.nearest, "cells": {}}
    if args.evaluate:
        ckpt = Path(args.evaluate)
        controller = load_controller(ckpt)
    else:
        ckpt = folder / f"{args.name}.pt"
        tcfg = DAGNNTrainConfig(teams=_numbers(args.teams, int), radii=_numbers(args.radii, float),
                                **{k: v for k, v in (("K", args.K), ("seed", args.seed),
                                                              ("feature_transform", args.feature_transform)) if v is not None})
        if args.teacher is not None and args.teacher < 1:
            raise SystemExit(f"--teacher takes the oracle's hops, a whole number >= 1; got {args.teacher}")
        teacher = (mock.patch.object(imitation, "expert_control", lambda r, v, cfg: KHopOracle(cfg, args.teacher)(r, v))
                   if args.teacher else contextlib.nullcontext())  # the labels of DAgger's flights (eq. 9's U*)
        with Provenance(command) as prov, teacher:
            controller, hist = train_dagnn(FlockConfig(), tcfg, checkpoint=ckpt, progress=False)
        out["teacher"] = f"{args.teacher}-hop oracle (khop_oracle.KHopOracle)" if args.teacher else "the expert (eq. 2)"
        out.update(train_config=tcfg.to_dict(), train_seconds=round(hist["seconds"], 1),
                   round_checks=hist["rounds"], training=prov.record())
    rc, seed = ReproduceConfig(), TEST_SEED if args.test else VALIDATION_SEED
    cells = [("N", n) for n in _numbers(args.fly_teams, int)] + [("R", r) for r in _numbers(args.fly_radii, float)]
    with Provenance(command) as prov:
        for table, column in cells:
            flight = flight_config(rc, table, column)
            flown = load_controller(ckpt, cfg=flight)
            if args.nearest is not None:  # the panorama of a VGAI: each drone's K nearest only
                render = dataclasses.replace(flown.vision.render, nearest=args.nearest)
                flown.vision = dataclasses.replace(flown.vision, render=render)
            res = relative_cost(flown, flight, episodes=args.episodes, seed=seed, name=args.name)
            start = connected_at_start(flight, args.episodes, seed=seed)  # which swarms start in one piece
            end = res.flocking.groups_at_end == 1
            print(f"{table} = {column}: {res}; connected at t = 0 in {start.double().mean():.0%}", flush=True)
            out["cells"][f"{table}={column}"] = {"config": {"N": flight.N, "R": flight.R}, **res.summary(),
                                                 "share_connected_at_start": round(float(start.double().mean()), 3),
                                                 "share_kept_connected": round(float(end[start].double().mean()), 3)}
    out["evaluation"] = prov.record(checkpoint=ckpt, seed=seed, episodes=args.episodes)
    path = folder / f"{args.name}_teams{'_test' if args.test else ''}.json"
    path.write_text(json.dumps(out, indent=1) + "\n")
    print("wrote", path)
    return 0


if __name__ == "__main__":
    sys.exit(main())

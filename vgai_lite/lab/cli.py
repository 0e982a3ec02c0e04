"""Command line: ``python -m vgai_lite COMMAND`` (``vgai_lite/__main__.py`` calls ``main``).

  lab        open the book in JupyterLab (adds --allow-root when run as root)
  evaluate   relative cost of a controller against the centralized expert (prints, optional JSON)
  demo       headless: fly the expert and the local heuristic, print costs, save pictures
  export     headless: execute every notebook and write it as HTML, to read without Jupyter
  benchmark  agent-steps per second of the simulator
  train-dagnn  train (or load) the book's DAGNN baselines, evaluate them, write data/dagnn/
  train-vgai   train (or load) the book's VGAI and visual state estimators, write data/vgai/
  reproduce    the paper's tables (F, K, v_init, R, N'): train what is missing, evaluate, data/results/;
               --only robustness: the perturbation sweep of notebook 08, data/robustness/
  site       the book as a static website (Sphinx + MyST-NB, from the executed notebooks), site/
  pdf        the whole book as one offline PDF (the website printed by headless Chromium), book.pdf
  student-copies  write the notebooks with every exercise's solution replaced by a stub
  grade        execute a student's notebook in quick mode and score its exercises (JSON)
  nbgrader-course  lay the graded notebooks out as an nbgrader course (needs requirements-grading.txt)
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from ..book import WORKING_SEED, ROOT


def _cfg_from(args):
    from ..config import FlockConfig

    changes = {k: getattr(args, k) for k in ("N", "R", "v_init", "T", "rho") if getattr(args, k, None) is not None}
    return FlockConfig(**changes)


def _add_cfg_args(p):
    p.add_argument("--N", type=int, help="number of agents (default 50)")
    p.add_argument("--R", type=float, help="communication radius in m (default 1.5)")
    p.add_argument("--v-init", dest="v_init", type=float, help="initial velocity scale in m/s (default 3)")
    p.add_argument("--T", type=int, help="steps per episode (default 200)")
    p.add_argument("--rho", type=float, help="potential radius in m (default 0.5)")


def trust_book(notebooks: Path) -> list:
    """Sign the book's own notebooks as trusted (what ``jupyter trust`` does), so that JupyterLab
    shows their HTML and script outputs (the meshcat 3-D view of notebook 04) as committed, without
    re-running them. Only the notebooks of this repository, exactly as they are now, are signed."""
    import nbformat
    from nbformat.sign import NotebookNotary

    notary, signed = NotebookNotary(), []
    for path in sorted(notebooks.glob("[0-9][0-9]_*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        if not notary.check_signature(nb):
            notary.sign(nb)
        signed.append(path.name)
    return signed


def cmd_lab(args, extra):
    notebooks = ROOT / "notebooks"
    print(f"trusted the book's {len(trust_book(notebooks))} notebooks (their committed outputs show as they are)")
    cmd = [sys.executable, "-m", "jupyter", "lab", f"--notebook-dir={notebooks}",
           str(notebooks / "00_overview.ipynb")]
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        cmd.append("--allow-root")
    cmd += extra
    print("running:", " ".join(cmd), flush=True)
    os.execv(cmd[0], cmd)


def cmd_evaluate(args, extra):

    from ..consensus import consensus
    from ..controllers import ExpertController, LocalController
    from ..evaluate import relative_cost

    cfg = _cfg_from(args)
    if args.controller == "local":
        controller = LocalController(cfg)
    elif args.controller == "expert":
        controller = ExpertController(cfg)
    else:  # a checkpoint file (.pt) or the name of a shipped controller (vgai_F24, dagnn_K4, ...)
        from ..checkpoints import load_controller, resolve

        try:
            path = resolve(args.controller)
        except (ValueError, FileNotFoundError) as exc:
            raise SystemExit(f"--controller must be 'local', 'expert', a checkpoint file (.pt) or a shipped "
                             f"controller's name: {exc}") from exc
        controller = load_controller(path)
        # fly it in the stored configuration, with the changes asked for on the command line
        changes = {k: getattr(args, k) for k in ("N", "R", "v_init", "T", "rho") if getattr(args, k) is not None}
        if args.N is not None and args.N != controller.trained_config.N:
            changes.setdefault("init_method", "repair")
        cfg = controller.trained_config.replace(**changes)
        controller.cfg = cfg
    from .provenance import Provenance

    with Provenance(" ".join(["python -m vgai_lite"] + sys.argv[1:])) as prov:
        res = relative_cost(controller, cfg, episodes=args.episodes, seed=args.seed, device=args.device)
    print(res)
    if args.consensus:
        flock = consensus(controller, cfg, episodes=args.consensus, seed=args.seed)
        print(flock)
    if args.json:
        out = {"config": cfg.to_dict(), **res.summary(), "pinned": res.pinned(),
               **({"consensus": flock.summary()} if args.consensus else {}),
               "provenance": prov.record(checkpoint=path if args.controller not in ("local", "expert") else None,
                                         seed=args.seed, episodes=args.episodes)}
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(out, indent=2) + "\n")
        print("wrote", args.json)


def cmd_demo(args, extra):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import torch

    from ..controllers import ExpertController, LocalController
    from ..flocking import rollout, sample_initial_state
    from ..viz import animate_swarms, animation_html, plot_trajectories, plot_velocity_variance

    cfg = _cfg_from(args)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    r0, v0 = sample_initial_state(cfg, args.episodes, torch.Generator().manual_seed(args.seed))
    trajs = {c.name: rollout(c, cfg, r0, v0) for c in (ExpertController(cfg), LocalController(cfg))}
    for name, tr in trajs.items():
        print(f"{name:12s} mean cost {tr.cost.mean():8.2f}  "
              f"(relative {tr.cost.mean() / trajs['Centralized'].cost.mean():.2f})")
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    for ax, (name, tr) in zip(axes, trajs.items()):
        plot_trajectories(ax, tr)
        ax.set_title(f"{name}: paths of swarm 0")
    plot_velocity_variance(axes[2], trajs, cfg.Ts)
    fig.tight_layout()
    fig.savefig(out / "demo.png", dpi=100)
    (out / "demo_animation.html").write_text(animation_html(animate_swarms(trajs, cfg)))
    print("wrote", out / "demo.png", "and", out / "demo_animation.html")


def cmd_export(args, extra):
    import nbformat
    from nbclient import NotebookClient
    from nbconvert import HTMLExporter

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for path in sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        if args.execute:
            print("executing", path.name, flush=True)
            NotebookClient(nb, timeout=3600, kernel_name="python3",
                           resources={"metadata": {"path": str(path.parent)}}).execute()
        html, _ = HTMLExporter().from_notebook_node(nb)
        target = out / (path.stem + ".html")
        target.write_text(html)
        print("wrote", target)


def cmd_train_dagnn(args, extra):
    import torch

    from .runs import DAGNN_RUNS, book_dagnn

    names = sorted(DAGNN_RUNS) if args.all else args.names
    if not names:
        raise SystemExit(f"name one or more runs, or --all; the book's runs are {sorted(DAGNN_RUNS)}")
    torch.set_num_threads(args.threads)
    for name in names:
        controller, result = book_dagnn(name, retrain=args.retrain, episodes=args.episodes, write_json=True)
        print(result)
        print(f"  trained in {controller.meta['history']['seconds']:.0f} s; wrote data/dagnn/{name}.pt and .json")


def cmd_train_vgai(args, extra):
    import torch

    from .runs import ESTIMATOR_RUNS, VGAI_RUNS, VGAI_SEED_RUNS, book_estimator, book_vgai, choose_seed

    torch.set_num_threads(args.threads)
    if args.estimators:
        for name in sorted(ESTIMATOR_RUNS):
            cnn, vision, meta = book_estimator(name, retrain=args.retrain)
            print(f"{name}: trained in {meta['seconds']:.0f} s; correlation with the exact features by step:")
            for t, q in meta["quality"].items():
                print(f"  t = {t:>3}: " + " ".join(f"{x:5.2f}" for x in q))
    names = list(args.names) + (sorted(VGAI_SEED_RUNS) if args.seeds else [])
    for name in names:
        controller, result = book_vgai(name, retrain=args.retrain, episodes=args.episodes, write_json=True)
        print(result)
        where = "data/vgai/seeds" if name in VGAI_SEED_RUNS else "data/vgai"
        print(f"  trained in {controller.meta['history']['seconds']:.0f} s; wrote {where}/{name}.pt and .json")
    if args.choose:
        record = choose_seed()
        for name, c in record["candidates"].items():
            print(f"{name}: validation relative cost {c['relative_cost_mean']:.2f} on {c['episodes']} episodes")
        print(f"chosen: {record['chosen']} -> data/vgai/vgai_F24.pt (set runs.VGAI_F24_SEED = {record['chosen_seed']})")
    if not names and not args.estimators and not args.choose:
        raise SystemExit(f"name a run ({sorted(VGAI_RUNS)}), or --seeds, --choose or --estimators")


def cmd_student_copies(args, extra):
    from .course import make_student_copies

    for path in make_student_copies(args.out, args.source):
        print("wrote", path)


def cmd_nbgrader_course(args, extra):
    from .course import nbgrader_course

    for path in nbgrader_course(args.out, args.source):
        print("wrote", path)
    print(f"then, in {args.out}: nbgrader generate_assignment NN (student version in release/NN/), and "
          "VGAI_LITE_QUICK=1 nbgrader autograde NN --create (hand-ins in submitted/STUDENT/NN/)")


def cmd_grade(args, extra):
    from .course import grade_notebook

    failed = False
    for nb in args.notebooks:
        report = grade_notebook(nb, out=args.out, notebook=args.notebook, quick=not args.full,
                                timeout=args.timeout)
        print(f"{report['notebook']}: {report['score']}/{report['max_score']} in {report['seconds']:.0f} s")
        for k, e in report["exercises"].items():
            print(f"  {k} {'PASSED' if e['passed'] else 'NOT PASSED'}: {e['message']}")
        for e in report["cell_errors"]:
            print(f"  cell {e['cell']} raised {e['error']}")
        if "written_to" in report:
            print("  wrote", report["written_to"])
        failed |= report["score"] < report["max_score"]
    return 1 if (failed and args.strict) else 0


def cmd_reproduce(args, extra):
    import torch

    from .reproduce import TABLES, ReproduceConfig, format_table, run

    torch.set_num_threads(args.threads)
    given = {k: getattr(args, k) for k in ("seeds", "vgai_seeds", "episodes", "episodes_large")
             if getattr(args, k) is not None}  # the others keep ReproduceConfig's defaults, written there once
    rc = ReproduceConfig(quick=args.quick, retrain=args.retrain, extras=args.extras, **given)
    for t in args.only or []:
        if t not in TABLES and t != "robustness":
            raise SystemExit(f"--only takes table names {list(TABLES)} or 'robustness', got {t!r}")
    only = args.only
    if only and "robustness" in only:
        from . import robustness

        rb = robustness.RobustnessConfig.quick_sweep() if args.quick else robustness.RobustnessConfig()
        res = robustness.run(rb, out=args.out if only == ["robustness"] else None)
        print(robustness.format_results(res))
        only = [t for t in only if t != "robustness"]
        if not only:
            return
    ray = None
    if args.ray is not None:
        ray = {"address": None if args.ray == "local" else args.ray, "cpus": args.ray_cpus, "threads": args.threads}
    results = run(only, rc, out=args.out, ray=ray)
    for table in results["tables"]:
        print()
        print(format_table(results, table))
    p = results["provenance"]
    print(f"\nwall time {p['wall_seconds']:.0f} s; ours (paper's); results in "
          f"{args.out or ('data/results_quick' if args.quick else 'data/results')}/results.json and .csv")


def cmd_site(args, extra):
    from . import website

    info = website.build(args.out, quiet=not args.verbose)
    for w in info["warnings"]:
        print(w)
    print(f"built {len(info['pages'])} pages in {info['seconds']:.0f} s, {info['megabytes']:.1f} MB: "
          f"open {info['out']}/index.html (or serve it: python -m http.server -d {args.out})")


def cmd_pdf(args, extra):
    from . import pdf

    info = pdf.build(args.out, site=args.site)
    print(f"printed {len(info['chapters'])} pages of the book ({info['pages']} PDF pages, "
          f"{info['animations']} animations as their first frame) in {info['seconds']:.0f} s: {info['out']}")


def cmd_benchmark(args, extra):
    import torch

    from . import benchmark

    if args.threads:
        torch.set_num_threads(args.threads)
    benchmark.main(args)


def _add_book_parsers(sub):
    """The book's other forms: the website and the PDF."""
    p = sub.add_parser("site", help="the book as a static website from the executed notebooks (needs requirements-site.txt)")
    p.add_argument("--out", default="site", help="folder for the site (default ./site)")
    p.add_argument("--verbose", action="store_true", help="show Sphinx's output")
    p = sub.add_parser("pdf", help="the whole book as one offline PDF (needs requirements-site.txt and Chromium)")
    p.add_argument("--out", default="book.pdf", help="the PDF file (default ./book.pdf)")
    p.add_argument("--site", default=None, help="print this site, built before by `site`, instead of building one")


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m vgai_lite", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("lab", help="open the book in JupyterLab; other flags go to jupyter lab")
    p = sub.add_parser("evaluate", help="relative cost of a controller against the expert")
    p.add_argument("--controller", default="local",
                   help="'local', 'expert' or a checkpoint, e.g. data/dagnn/dagnn_K4.pt")
    p.add_argument("--consensus", type=int, default=0, metavar="E",
                   help="also fly E episodes of 5 s and print the velocity variance at 0.5, 1, 2, 5 s and "
                        "whether the swarm stays connected (did it flock?)")
    p.add_argument("--episodes", type=int, default=50)
    p.add_argument("--seed", type=int, default=WORKING_SEED, help=f"initial-condition seed (default {WORKING_SEED})")
    p.add_argument("--device", default=None)
    p.add_argument("--json", help="also write the figures to this JSON file")
    _add_cfg_args(p)
    p = sub.add_parser("demo", help="headless: expert vs local, pictures and an HTML animation")
    p.add_argument("--episodes", type=int, default=20)
    p.add_argument("--seed", type=int, default=WORKING_SEED)
    p.add_argument("--out", default="out")
    _add_cfg_args(p)
    p = sub.add_parser("export", help="headless: write the notebooks as HTML pages")
    p.add_argument("--out", default="out/html")
    p.add_argument("--execute", action="store_true", help="run each notebook first (full mode: minutes)")
    p = sub.add_parser("benchmark", help="agent-steps per second of step + expert_control")
    p.add_argument("--vgai", action="store_true", help="instead: VGAI training steps per second, projected training time")
    p.add_argument("--train-config", dest="train_config", default=None, metavar="RECORD",
                   help="with --vgai: the training configuration of this record (e.g. data/experiments/vgai_depthcam.json)")
    p.add_argument("--threads", type=int, default=None, help="torch threads (default torch's)")
    p = sub.add_parser("train-dagnn", help="train (or load) the book's DAGNNs, evaluate, write data/dagnn/")
    p.add_argument("names", nargs="*", help="runs to train, e.g. dagnn_K4")
    p.add_argument("--all", action="store_true", help="every run the book ships")
    p.add_argument("--retrain", action="store_true", help="train even if an up-to-date checkpoint exists")
    p.add_argument("--episodes", type=int, default=50, help="working episodes of the record (seed book.WORKING_SEED)")
    p.add_argument("--threads", type=int, default=1, help="torch threads (run two jobs on two cores)")
    p = sub.add_parser("train-vgai", help="train (or load) the book's VGAI and state estimators, write data/vgai/")
    p.add_argument("names", nargs="*", help="VGAI runs to train, e.g. vgai_F24")
    p.add_argument("--estimators", action="store_true", help="the single- and two-frame state estimators")
    p.add_argument("--seeds", action="store_true", help="the default VGAI's three training seeds (data/vgai/seeds/)")
    p.add_argument("--choose", action="store_true",
                   help="pick vgai_F24 among the seeds on the validation episodes (data/vgai/seeds/choice.json)")
    p.add_argument("--retrain", action="store_true")
    p.add_argument("--episodes", type=int, default=20, help="validation episodes of each record (seed VALIDATION_SEED)")
    p.add_argument("--threads", type=int, default=2)
    p = sub.add_parser("reproduce", help="the paper's tables: train what is missing, evaluate, write data/results/")
    p.add_argument("--only", nargs="+", metavar="TABLE", help="tables to run: F K v_init R N (default all), or robustness (notebook 08's sweep)")
    p.add_argument("--quick", action="store_true", help="every table in small form (tiny trainings, 2 short episodes)")
    p.add_argument("--seeds", type=int, default=None, help="training seeds of the DAGNN rows (default: ReproduceConfig's)")
    p.add_argument("--vgai-seeds", dest="vgai_seeds", type=int, default=None,
                   help="training seeds of the VGAI rows (default: ReproduceConfig's; each is a VGAI training)")
    p.add_argument("--episodes", type=int, default=None, help="test episodes per cell, N' <= 75 (default: ReproduceConfig's)")
    p.add_argument("--episodes-large", dest="episodes_large", type=int, default=None,
                   help="test episodes per cell for N' >= 100 (default: ReproduceConfig's)")
    p.add_argument("--out", default=None, help="results folder (default data/results, or data/results_quick)")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--retrain", action="store_true",
                   help="from scratch: train every model anew (shipped checkpoints included) and recompute every cell")
    p.add_argument("--extras", action="store_true",
                   help="also our rows beyond the paper's that need VGAI trainings (VGAI retrained at R = 1.0, 2.0)")
    p.add_argument("--ray", nargs="?", const="local", default=None, metavar="ADDRESS",
                   help="run the trainings and cells as Ray tasks (each with --threads CPUs): on a new local Ray "
                        "instance, or on the cluster at ADDRESS (e.g. auto, or HEAD:6379 of `ray start --head`); "
                        "needs requirements-cluster.txt")
    p.add_argument("--ray-cpus", dest="ray_cpus", type=int, default=None,
                   help="CPUs of the local Ray instance (default: all of this machine's)")
    _add_book_parsers(sub)
    p = sub.add_parser("student-copies", help="notebooks with solutions replaced by stubs, outputs cleared")
    p.add_argument("--out", default="student", help="folder for the copies (default ./student)")
    p.add_argument("--source", default=None, help="folder of the solution notebooks (default the book's)")
    p = sub.add_parser("nbgrader-course", help="the graded notebooks as an nbgrader course: source/NN/, config")
    p.add_argument("--out", default="course", help="the course folder (default ./course)")
    p.add_argument("--source", default=None, help="folder of the solution notebooks (default the book's)")
    p = sub.add_parser("grade", help="execute notebooks (quick mode) and score their exercises")
    p.add_argument("notebooks", nargs="+", help="notebook files named NN_*.ipynb")
    p.add_argument("--out", default=None, help="folder (or .json file) for the JSON report(s)")
    p.add_argument("--notebook", default=None, help="the book notebook's number, if the file name lacks it")
    p.add_argument("--full", action="store_true", help="run in full mode instead of quick mode")
    p.add_argument("--timeout", type=int, default=600, help="seconds allowed per cell")
    p.add_argument("--strict", action="store_true", help="exit with status 1 unless every exercise passed")
    args, extra = parser.parse_known_args(argv)
    if extra and args.command != "lab":
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    return {"lab": cmd_lab, "evaluate": cmd_evaluate, "demo": cmd_demo, "export": cmd_export,
     "benchmark": cmd_benchmark, "train-dagnn": cmd_train_dagnn,
     "train-vgai": cmd_train_vgai, "student-copies": cmd_student_copies,
     "reproduce": cmd_reproduce, "site": cmd_site, "pdf": cmd_pdf,
     "grade": cmd_grade, "nbgrader-course": cmd_nbgrader_course}[args.command](args, extra)

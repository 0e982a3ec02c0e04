"""Experiment: every table of notebook 07 recomputed as ONE run, alone, timed, and checked against the committed tables.

    python tools/experiments/reproduce_timed.py --threads 2 --adopt

``python -m vgai_lite reproduce`` reads back the cells an earlier invocation computed (data/results/cells/),
so data/results/results.json's times are those of many invocations, some sharing the cores. This runs
``reproduce`` once into a fresh folder (``--work``, default a temporary one) holding only the models the
committed tables flew (the shipped checkpoints, and data/results/models/ copied): every cell is
evaluated now, none read back, and no model is trained (each checkpoint's training time is in its record,
``training_recorded``). Writes data/results/timed_run.json: the wall time of the run, the load average
while it ran, and whether every cell's relative cost equals the committed one (the largest difference).
Run it with nothing else on the machine: the time is the point. ``--adopt`` makes that run the book's tables:
its cells, results.json and results.csv replace data/results/'s (so every number of notebook 07 and the README
comes from this one run), and the record lists the cells the committed tables did not have yet (a new row).
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from vgai_lite.book import DATA_DIR  # noqa: E402
from vgai_lite.lab.provenance import Provenance  # noqa: E402
from vgai_lite.lab.reproduce import ReproduceConfig, run  # noqa: E402


def cell_costs(results: dict) -> dict[str, float]:
    """table/row/column -> the cell's mean relative cost, for every cell of a results.json."""
    return {f"{t}/{row}/{col}": cell["relative_cost_mean"]
            for t, table in results["tables"].items() for row, cells in table["rows"].items()
            for col, cell in cells.items() if cell is not None}


def name_the_command(path: Path, command: str) -> None:
    """The adopted results.json says which command computed it (``reproduce``'s provenance names the
    script's own argv, which ``python -m vgai_lite`` would not rerun)."""
    results = json.loads(path.read_text())
    results["provenance"]["command"] = command
    results["provenance"]["invocations"][-1]["command"] = command
    path.write_text(json.dumps(results, indent=1) + "\n")


def relink(cells_dir: Path) -> int:
    """Point every cell's checkpoint that lay in a timed run's temporary models folder (``.../vgai_reproduce_*/models/NAME``,
    a copy of data/results/models) at the repository's own copy, data/results/models/NAME; returns how many it changed."""
    changed = 0
    for path in sorted(Path(cells_dir).glob("*.json")):
        cell = json.loads(path.read_text())
        ck = cell.get("checkpoint")
        if ck and "vgai_reproduce_" in ck and Path(ck).parent.name == "models":
            ours = DATA_DIR / "results" / "models" / Path(ck).name
            if not ours.exists():
                raise SystemExit(f"{path.name}: its checkpoint {Path(ck).name} is not in data/results/models")
            cell["checkpoint"] = str(ours.relative_to(DATA_DIR.parent))
            path.write_text(json.dumps(cell, indent=1) + "\n")  # as table_cells writes it
            changed += 1
    return changed


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--work", default=None, help="the fresh results folder (default: a temporary one, removed after)")
    p.add_argument("--out", default=str(DATA_DIR / "results" / "timed_run.json"))
    p.add_argument("--adopt", action="store_true",
                   help="make this run the book's tables: replace data/results/cells, results.json and results.csv by its own")
    p.add_argument("--relink", action="store_true",
                   help="no run: point the committed cells' checkpoints at data/results/models (runs adopted before relink)")
    args = p.parse_args(argv)
    if args.relink:
        print(f"relinked {relink(DATA_DIR / 'results' / 'cells')} cells to data/results/models")
        return 0
    torch.set_num_threads(args.threads)
    committed = json.loads((DATA_DIR / "results" / "results.json").read_text())
    rc = ReproduceConfig(**{k: v for k, v in committed["provenance"]["reproduce_config"].items()
                            if k in ReproduceConfig.__dataclass_fields__})
    work = Path(args.work) if args.work else Path(tempfile.mkdtemp(prefix="vgai_reproduce_"))
    if (work / "cells").exists():
        raise SystemExit(f"{work} already holds cells: a timed run must compute every cell, give a fresh --work")
    shutil.copytree(DATA_DIR / "results" / "models", work / "models", dirs_exist_ok=True)
    command = " ".join(["python tools/experiments/reproduce_timed.py"] + (argv or sys.argv[1:]))
    with Provenance(command) as prov:
        fresh = run(None, rc, out=work, progress=False)
    ours, theirs = cell_costs(fresh), cell_costs(committed)
    if set(theirs) - set(ours):
        raise SystemExit(f"the run lacks cells the committed tables have: {sorted(set(theirs) - set(ours))}")
    new_cells = sorted(set(ours) - set(theirs))  # a row or column the committed tables did not have yet
    diff = {k: abs(ours[k] - theirs[k]) for k in theirs}
    worst = max(diff, key=diff.get)
    compute = fresh["provenance"]["compute_seconds"]
    computed = len(list((work / "cells").glob("*.json")))  # the folder started empty: every cell file is this run's
    record = {"command": command, "reproduce_config": fresh["provenance"]["reproduce_config"],
              "wall_seconds": fresh["provenance"]["wall_seconds"], "cells": compute["cells"],
              "cells_computed_now": compute["cells_computed_now"],  # reproduce's count: a cell two jobs share counts once read back
              "cells_computed_in_this_run": computed,
              "models_trained_now": fresh["provenance"]["invocations"][-1]["models_trained_now"],
              "training_recorded_seconds": compute["training_recorded"],
              "cells_equal_committed": all(d <= 1e-3 for d in diff.values()),
              "cells_not_in_committed": new_cells, "adopted": args.adopt,
              "largest_difference": {"cell": worst, "committed": theirs[worst], "now": ours[worst]},
              "provenance": prov.record(seed=rc.seed)}
    Path(args.out).write_text(json.dumps(record, indent=1) + "\n")
    print(f"{record['cells']} cells ({record['cells_computed_in_this_run']} computed in this run, {record['models_trained_now']} models "
          f"trained) in {record['wall_seconds'] / 60:.1f} min at {args.threads} threads, load average "
          f"{record['provenance']['load_average_mean']}; every cell equals the committed one: "
          f"{record['cells_equal_committed']} (largest difference {worst}: {theirs[worst]} -> {ours[worst]})")
    if args.adopt:  # this run becomes the book's tables
        results_dir = DATA_DIR / "results"
        shutil.rmtree(results_dir / "cells")
        shutil.copytree(work / "cells", results_dir / "cells")
        relink(results_dir / "cells")  # the repository's checkpoints, not the temporary copies
        for name in ("results.json", "results.csv"):
            shutil.copy2(work / name, results_dir / name)
        name_the_command(results_dir / "results.json", command)
        print(f"adopted: data/results/cells ({computed} cells), results.json and results.csv are this run's")
    if not args.work:
        shutil.rmtree(work)
    return 0


if __name__ == "__main__":
    sys.exit(main())

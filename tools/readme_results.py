"""Write the README's results section from the records in data/ (no number in it is typed by hand).

    python tools/readme_results.py           # print the section
    python tools/readme_results.py --write   # replace it in README.md, between the markers

The section lies between ``<!-- results:begin -->`` and ``<!-- results:end -->``; a test checks that
the committed README equals what this script writes.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from vgai_lite.reproduce import PAPER  # noqa: E402

BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"
README = ROOT / "README.md"


def _load(rel: str) -> dict:
    return json.loads((ROOT / rel).read_text())


def _ci(rec: dict) -> str:
    lo, hi = rec["relative_cost_mean_ci95"]
    return f"{rec['relative_cost_mean']:.2f} ({lo:.2f}-{hi:.2f})"


def section() -> str:
    dagnn = {k: _load(f"data/dagnn/dagnn_K{k}.json") for k in (1, 2, 3, 4)}
    vgai = {n: _load(f"data/vgai/vgai_{n}.json") for n in ("F24", "F12", "F6", "K3", "K2")}
    results = _load("data/results/results.json")
    local = results["tables"]["v_init"]["rows"]["Local"]["3.0"]
    prov = results["provenance"]
    scratch = [i for i in prov.get("invocations", []) if i["retrain"]]
    eps = dagnn[4]["episodes"]
    p = PAPER

    def vg_minutes(rec):
        return (rec["train_seconds"] + (rec.get("stage1_seconds") or 0.0 if rec.get("stage1_cached") else 0.0)) / 60

    rows = [
        "| controller | relative cost (95% CI) | paper | command |",
        "|---|---|---|---|",
        f"| Local heuristic | {local['relative_cost_mean']:.2f} ({local['ci95'][0]:.2f}-{local['ci95'][1]:.2f}), "
        f"{local['episodes']} episodes | {p['v_init']['Local'][3.0]:.2f} | `python -m vgai_lite reproduce --only v_init` |",
        f"| DAGNN, K-1 = 3 | {_ci(dagnn[4])} | {p['K']['DAGNN'][3]:.2f} | "
        "`python -m vgai_lite evaluate --controller data/dagnn/dagnn_K4.pt` |",
        f"| DAGNN, K-1 = 0 / 1 / 2 | {dagnn[1]['relative_cost_mean']:.2f} / {dagnn[2]['relative_cost_mean']:.2f} / "
        f"{dagnn[3]['relative_cost_mean']:.2f} | - / {p['K']['DAGNN'][1]:.2f} / {p['K']['DAGNN'][2]:.2f} | "
        "`python -m vgai_lite train-dagnn dagnn_K1 dagnn_K2 dagnn_K3` |",
        f"| VGAI, F = 24, K-1 = 3 (images only) | {_ci(vgai['F24'])} | {p['F']['VGAI'][24]:.2f} | "
        "`python -m vgai_lite evaluate --controller data/vgai/vgai_F24.pt` |",
        f"| VGAI, K-1 = 1 / 2, F = 24 | {_ci(vgai['K2'])} / {_ci(vgai['K3'])} | {p['K']['VGAI'][1]:.2f} / "
        f"{p['K']['VGAI'][2]:.2f} | `python -m vgai_lite evaluate --controller data/vgai/vgai_K2.pt` (and `vgai_K3.pt`) |",
        f"| VGAI, F = 6 / 12, K-1 = 3 | {_ci(vgai['F6'])} / {_ci(vgai['F12'])} | {p['F']['VGAI'][6]:.2f} / "
        f"{p['F']['VGAI'][12]:.2f} | `python -m vgai_lite evaluate --controller data/vgai/vgai_F6.pt` (and `vgai_F12.pt`) |",
    ]
    d4, v24 = dagnn[4], vgai["F24"]
    text = [
        f"All on {eps} held-out episodes (seed {d4['seed']}) unless stated, N = 50, R = 1.5 m, v_init = 3 m/s; "
        "relative cost = cost of eq. 1 over the centralized expert's cost on the same initial conditions.",
        "",
        *rows,
        "",
        f"Safety on the same episodes: episodes with a pair closer than 0.05 m: DAGNN {d4['share_below_0.05m']:.0%}, "
        f"VGAI {v24['share_below_0.05m']:.0%}, expert {d4['expert_share_below_0.05m']:.0%}; median closest approach "
        f"DAGNN {d4['median_min_distance']:.3f} m, VGAI {v24['median_min_distance']:.3f} m, expert "
        f"{d4['expert_median_min_distance']:.3f} m.",
        "",
        f"Training time, each alone on this 2-core machine: the default DAGNN {d4['train_seconds']:.0f} s; VGAI "
        + ", ".join(f"{n} {vg_minutes(r):.1f} min" for n, r in vgai.items())
        + " (K2 and K3 reuse the F24 run's first stage, whose time is counted in theirs)."
        + (f" The from-scratch reproduction of every table (`python -m vgai_lite reproduce --retrain --seeds 1`), "
           f"which trained all of these, took {scratch[-1]['wall_seconds'] / 60:.0f} min." if scratch else ""),
    ]
    return "\n".join([BEGIN, *text, END])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="replace the section in README.md")
    args = ap.parse_args()
    new = section()
    if not args.write:
        print(new)
        return
    text = README.read_text()
    if text.count(BEGIN) != 1 or text.count(END) != 1:
        raise SystemExit(f"README.md must hold {BEGIN} and {END} once each")
    head, rest = text.split(BEGIN)
    _, tail = rest.split(END)
    README.write_text(head + new + tail)
    print("README.md: results section rewritten")


if __name__ == "__main__":
    main()

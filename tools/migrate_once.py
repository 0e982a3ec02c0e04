"""One-time migration of data/ to the library's new configuration fields and names (then deleted).

    python tools/migrate_once.py

- every VGAI training configuration stored in a checkpoint or a record gets every field of
  VGAITrainConfig (to_dict no longer drops the fields that are 0; mlp_batch, mlp_late_stride and
  synthetic_speeds, hidden constants before, with the values they had; camera, the ideal one they
  were trained with), and every vision configuration
  its motion_scale (5.0, the former vision.MOTION_SCALE). The weights are not touched.
- the round checks' keys val_relative_cost / val_share_below_0.05m become check_relative_cost /
  check_share_below_0.05m; choice.json's selection_seed becomes validation_seed.
- every checkpoint rewritten has a new sha256: each old sha256 in a record becomes the new one, and
  each robustness cell's checkpoint id (sha1[:12] before, sha256[:12] now) too.
- the table cells (data/results/cells) and the robustness cells (data/robustness/cells) are re-keyed
  (their keys hash the configurations above), and every file that lists the keys follows.
- the records of the hypotheses whose knobs left the method get a `rerun` command at the commit that had them.
"""

from __future__ import annotations

import hashlib
import json
import re
import sys
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from vgai_lite.checkpoints import atomic_save, config_hash  # noqa: E402

DATA = ROOT / "data"
OLD_COMMIT = "b9be2ec"
REMOVED_KNOBS = ("flight_steps", "joint_early_share", "mlp_on_exact", "anchor_weight")
NEW_DEFAULTS = {"synthetic_share": 0.0, "motion_features": 0, "aux_weight": 0.0, "learner_swarms": 0.0,
                "mlp_batch": 1024, "mlp_late_stride": 4, "synthetic_speeds": [0.01, 1.5],
                "camera": {"noise": [0.0, 0.0], "blur_deg": [0.0, 0.0], "gain": [1.0, 1.0], "offset": [0.0, 0.0],
                           "dead_share": 0.0}}
VISION_KEYS = {"view", "render", "motion_gap", "motion_mode", "prehistory"}
TRAIN_KEYS = {"F", "K", "cnn_widths", "cnn_hidden", "vision", "warm_steps"}
RENAMES = {"val_relative_cost": "check_relative_cost", "val_share_below_0.05m": "check_share_below_0.05m",
           "selection_seed": "validation_seed", "validation_by_round": "round_checks",
           "VGAI, last round's plain CNN": "VGAI, the paper's recipe (plain CNN)"}


def fix(x):
    """The migrated form of any stored value (dicts walked recursively)."""
    if isinstance(x, list):
        return [fix(v) for v in x]
    if not isinstance(x, dict):
        if x == "lowest relative cost on the selection episodes":
            return "lowest relative cost on the validation episodes"
        return x
    d = {RENAMES.get(k, k): fix(v) for k, v in x.items()}
    if isinstance(d.get("validation"), list) and all(isinstance(r, dict) and "stage" in r for r in d["validation"]):
        d = {("round_checks" if k == "validation" else k): v for k, v in d.items()}
    if VISION_KEYS <= set(d) and "motion_scale" not in d:
        d = {**d, "motion_scale": 5.0}
    if TRAIN_KEYS <= set(d):
        for k in REMOVED_KNOBS:  # 0: the method's default then; non-zero: a record of a knob now gone, kept
            if k in d and not d[k]:
                del d[k]
        d = {**{k: v for k, v in NEW_DEFAULTS.items() if k not in d}, **d}
    return d


def main() -> int:
    sha_map, id_map, first_of = {}, {}, {}
    for path in sorted(DATA.rglob("*.pt")):
        raw = path.read_bytes()
        old = hashlib.sha256(raw).hexdigest()
        if old in first_of:  # a byte-for-byte copy (vgai_F24.pt of its seed's file) stays one
            path.write_bytes(first_of[old].read_bytes())
            continue
        first_of[old] = path
        payload = torch.load(path, map_location="cpu", weights_only=True)
        new = {k: (v if k in ("state_dict", "generator") else fix(v)) for k, v in payload.items()}
        atomic_save(new, path)
        sha_map[hashlib.sha256(raw).hexdigest()] = hashlib.sha256(path.read_bytes()).hexdigest()
        id_map[hashlib.sha1(raw).hexdigest()[:12]] = sha_map[hashlib.sha256(raw).hexdigest()][:12]
        id_map[hashlib.sha256(raw).hexdigest()[:12]] = sha_map[hashlib.sha256(raw).hexdigest()][:12]
    for path in sorted(DATA.rglob("*.json")):
        text = path.read_text()
        indent = 1 if text.startswith("{\n \"") else 2
        d = fix(json.loads(text))
        if path.parent.name == "experiments" and isinstance(d, dict) and "command" in d \
                and any(f"--{k.replace('_', '-')}" in d["command"] for k in REMOVED_KNOBS):
            d["rerun"] = (f"git worktree add ../vgai-lite-{OLD_COMMIT} {OLD_COMMIT} && cd ../vgai-lite-{OLD_COMMIT} "
                          f"&& {d['command']}")
        out = json.dumps(d, indent=indent) + "\n"
        for old, new in {**sha_map, **id_map}.items():
            out = out.replace(old, new)
        path.write_text(out)
    key_map = {}
    for path in sorted((DATA / "results" / "cells").glob("*.json")):
        d = json.loads(path.read_text())
        key = config_hash({k: d[k] for k in ("model", "flight", "episodes", "seed")})
        key_map[d["key"]] = key
    for path in sorted((DATA / "robustness" / "cells").glob("*.json")):
        d = json.loads(path.read_text())
        key = config_hash({k: d[k] for k in ("controller", "perturbations", "checkpoint", "flight", "episodes",
                                             "seed", "flock_times")})
        key_map[d["key"]] = key
    for folder in (DATA / "results", DATA / "robustness"):
        for path in sorted(folder.rglob("*.json")) + sorted(folder.rglob("*.csv")):
            text = path.read_text()
            new = re.sub(r"\b[0-9a-f]{12}\b", lambda m: key_map.get(m.group(0), m.group(0)), text)
            path.write_text(new)
        for path in sorted((folder / "cells").glob("*.json")):
            if path.stem in key_map and key_map[path.stem] != path.stem:
                path.rename(path.with_name(f"{key_map[path.stem]}.json"))
    print(f"{len(sha_map)} checkpoints rewritten, {len(key_map)} cells re-keyed")
    return 0


if __name__ == "__main__":
    sys.exit(main())

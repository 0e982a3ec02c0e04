"""Records that say where they came from, checked against their checkpoints.

Every record with a ``provenance`` names its command, commit, versions, threads, load average and the
sha256 of the checkpoint it flew; with ``pinned`` it keeps its first episodes' relative costs one by
one. This test checks the checkpoint is still the one the record flew, and flies the first pinned
episode again from it: a record that no longer matches its checkpoint (or a library change that moves the
numbers) fails here.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
import torch

from vgai_lite import ExpertController, FlockConfig, LocalController, load_controller, rollout, sample_initial_state
from vgai_lite.book import DATA_DIR, ROOT
from vgai_lite.flocking import flocking_cost
from vgai_lite.lab.provenance import Provenance, sha256

def _pilot(cfg):
    sys.path.insert(0, str(ROOT / "tools"))
    from test_episodes import pilot

    return pilot(cfg)


RULES = {"Local": LocalController, "local": LocalController, "modular vision pilot": _pilot,
         "k-hop oracle": None}  # tools/experiments/khop_oracle.py: a measurement without pinned episodes
"""Records of controllers that are built rather than loaded from one checkpoint (a rule, or the
modular vision pilot composed of two networks), by the name a record gives them."""

PROVENANCE_FIELDS = {"command", "git_commit", "library_modified_since_commit", "python", "torch", "torch_threads",
                     "load_average_mean", "load_average_max", "wall_seconds"}


def _records():
    out = []
    for path in sorted(DATA_DIR.rglob("*.json")):
        try:
            rec = json.loads(path.read_text())
        except json.JSONDecodeError:
            continue
        if isinstance(rec, dict) and "provenance" in rec and path.parent.name != "results":
            out.append((path, rec))
    return out


def _evaluation(rec: dict) -> dict:
    prov = rec["provenance"]
    return prov.get("evaluation", prov) if isinstance(prov, dict) else prov


RECORDS = _records()


def test_records_with_provenance_exist():
    assert RECORDS, "no record in data/ carries a provenance"


@pytest.mark.parametrize("path,rec", RECORDS, ids=[str(p.relative_to(DATA_DIR)) for p, _ in RECORDS])
def test_a_records_provenance_is_complete_and_names_its_checkpoint(path, rec):
    prov = _evaluation(rec)
    assert PROVENANCE_FIELDS <= set(prov), f"missing {PROVENANCE_FIELDS - set(prov)}"
    assert {"episodes_seed", "episodes"} <= set(prov)
    if "checkpoints" in prov:  # a record that read several networks names each, with its hash
        assert prov["checkpoints"], f"{path.name} names an empty list of checkpoints"
        for name, digest in prov["checkpoints"].items():
            assert (ROOT / name).is_file(), f"{path.name} read {name}, which is not in the repository"
            assert sha256(ROOT / name) == digest, f"{name} changed since {path.name} was written"
        return
    if rec.get("controller") in RULES:  # a rule, not a trained network: no checkpoint
        return
    assert {"checkpoint", "checkpoint_sha256"} <= set(prov)
    ckpt = ROOT / prov["checkpoint"]
    assert ckpt.is_file(), f"{path.name} flew {prov['checkpoint']}, which is not in the repository"
    assert sha256(ckpt) == prov["checkpoint_sha256"], f"{prov['checkpoint']} changed since {path.name} was written"


PINNED = [(p, r) for p, r in RECORDS if "pinned" in r]
FLEW_APART = 20.0
"""A pinned relative cost above this is a swarm that flew apart (the local heuristic costs about 4)."""


def _flight(rec: dict) -> str:
    """What a record's pinned episodes depend on: the controller flown (its checkpoint's bytes, or the
    rule), the flight configuration and the episodes. Records that agree on it fly the same episodes."""
    prov = _evaluation(rec)
    who = rec["controller"] if rec.get("controller") in RULES else prov["checkpoint_sha256"]
    return json.dumps([who, rec["config"], prov["episodes"], prov["episodes_seed"]], sort_keys=True)


FLIGHTS: dict[str, list] = {}
for _p, _r in PINNED:
    FLIGHTS.setdefault(_flight(_r), []).append((_p, _r))


def _shape(x):
    """A network's spec with its sizes and constants blanked: what decides which code its flight runs."""
    if isinstance(x, dict):
        return {k: _shape(v) for k, v in x.items()}
    if isinstance(x, list):
        return x if all(isinstance(v, str) for v in x) else "list"
    return x if x is None or isinstance(x, (bool, str)) else type(x).__name__


def _code_path(rec: dict) -> str:
    """The code a record's flight runs: the rule, or its network's kind, readout, channels, frames,
    feature transform, GSO... (the spec without its numbers) and the potential it flies under."""
    if rec.get("controller") in RULES:
        return f"rule {rec['controller']}"
    ckpt = torch.load(ROOT / _evaluation(rec)["checkpoint"], weights_only=True, map_location="cpu")
    return json.dumps([_shape(ckpt["spec"]), rec["config"].get("potential")], sort_keys=True)


def _ci_flights() -> set[str]:
    """CI flies one flight per code path (the book's reported records, ``data/test``, first): a library
    change that moves the numbers moves them there. The other flights run the same code with other
    weights; ``pytest -m archive`` flies them too (about 4 minutes on the 2 cores)."""
    chosen: dict[str, str] = {}
    for key, group in sorted(FLIGHTS.items(), key=lambda kv: (kv[1][0][0].parent.name != "test", str(kv[1][0][0]))):
        chosen.setdefault(_code_path(group[0][1]), key)
    return set(chosen.values())


CI_FLIGHTS = _ci_flights()


@pytest.mark.slow
@pytest.mark.parametrize("group", [pytest.param(g, marks=() if k in CI_FLIGHTS else pytest.mark.archive)
                                   for k, g in FLIGHTS.items()],
                         ids=[str(g[0][0].relative_to(DATA_DIR)) for g in FLIGHTS.values()])
def test_a_records_pinned_episodes_fly_again_to_the_same_costs(group):
    """Records of one flight (the same checkpoint on the same episodes, e.g. a seed's record and the
    chosen vgai_F24's) pin the same costs; its first episode is flown again once for all of them."""
    path, rec = group[0]
    for other, orec in group[1:]:
        assert orec["pinned"]["relative_cost"] == pytest.approx(rec["pinned"]["relative_cost"], rel=2e-3), \
            f"{other.name} and {path.name} flew the same checkpoint on the same episodes to different costs"
    prov = _evaluation(rec)
    cfg = FlockConfig(**rec["config"])
    if rec.get("controller") in RULES:
        controller = RULES[rec["controller"]](cfg)
    else:
        controller = load_controller(ROOT / prov["checkpoint"])
        controller.cfg = cfg
    r0, v0 = sample_initial_state(cfg, prov["episodes"], torch.Generator().manual_seed(prov["episodes_seed"]))
    threads = torch.get_num_threads()  # flown with the record's threads: a swarm that flies apart (drones
    torch.set_num_threads(prov.get("torch_threads") or threads)  # a centimetre apart) amplifies the last bits
    try:
        cost = flocking_cost(rollout(controller, cfg, r0[:1], v0[:1]).v)
        expert = rollout(ExpertController(cfg), cfg, r0[:1], v0[:1]).cost
    finally:
        torch.set_num_threads(threads)
    pinned = torch.tensor(rec["pinned"]["relative_cost"][:1])
    # a swarm that flies apart (FLEW_APART times the expert's cost) is chaotic: another CPU's last bits
    # (vgai_book_one_frame.json, 129.0 pinned: 130.1 on an AVX-512 machine) move it by about 1 %
    rtol = 2e-2 if float(pinned) > FLEW_APART else 2e-3
    assert torch.allclose(cost / expert, pinned, rtol=rtol), \
        f"{path.name}: the first pinned episode now costs {(cost / expert).tolist()} (pinned {pinned.tolist()}, rtol {rtol})"


REPRODUCE_FIELDS = {"command", "git_commit", "library_modified_since_commit", "python", "torch_threads",
                    "wall_seconds", "packages", "reproduce_config", "invocations"}


def test_the_reproductions_record_names_its_invocations():
    """``results/results.json`` holds many cells computed by several invocations of ``reproduce``:
    its provenance names each invocation (command, commit, wall time) rather than one evaluation."""
    prov = json.loads((DATA_DIR / "results" / "results.json").read_text())["provenance"]
    assert REPRODUCE_FIELDS <= set(prov), f"missing {REPRODUCE_FIELDS - set(prov)}"
    assert prov["packages"]["torch"].startswith("2.13.0")
    for inv in prov["invocations"]:
        assert {"command", "git_commit", "wall_seconds", "started"} <= set(inv), inv


def test_provenance_samples_the_load_and_needs_a_command():
    with pytest.raises(ValueError, match="command"):
        Provenance("")
    with Provenance("python -c pass", interval=0.01) as prov:
        sum(range(10 ** 5))
    rec = prov.record(seed=1, episodes=2)
    assert rec["load_average_max"] >= rec["load_average_mean"] >= 0 and rec["episodes_seed"] == 1
    with pytest.raises(RuntimeError):
        Provenance("x").record()


def test_every_committed_table_cell_names_a_checkpoint_the_repository_holds():
    """A cell's checkpoint is a file of this repository (a timed run's temporary copies are relinked when adopted)."""
    from vgai_lite.book import DATA_DIR

    missing = []
    for path in sorted((DATA_DIR / "results" / "cells").glob("*.json")):
        ck = json.loads(path.read_text()).get("checkpoint")
        if ck is not None and (Path(ck).is_absolute() or not (DATA_DIR.parent / ck).exists()):
            missing.append((path.name, ck))
    assert not missing, f"cells whose checkpoint is not a repository file: {missing[:5]}"


def test_a_checkpoint_evaluated_again_keeps_its_changes_only_when_the_flags_give_its_recipe():
    """vgai_variant.py --evaluate with change flags records them as the record's changes; flags that leave one of the
    checkpoint's changes out (or add one it was not trained with) are refused, naming the fields, before anything flies."""
    sys.path.insert(0, str(ROOT / "tools" / "experiments"))
    import vgai_variant

    ckpt = DATA_DIR / "experiments" / "vgai_camera_quiet_fixed_mlp.pt"
    gray = ["--camera", "0,0.005:0,1.4:0.9,1.1:-0.03,0.03:0.05", "--channels", "gray", "--threads", str(torch.get_num_threads())]
    with pytest.raises(SystemExit, match=r"differs from the recipe these flags give in \['joint_mlp', 'mlp_start', 'readout'\]"):
        vgai_variant.main(["--name", "unused", "--evaluate", str(ckpt), *gray])
    with pytest.raises(SystemExit, match=r"in \['feature_means'\]"):
        vgai_variant.main(["--name", "unused", "--evaluate", str(ckpt), *gray, "--readout", "local", "--mlp-start", "dagnn_K4",
                           "--joint-mlp", "off", "--feature-means"])

"""`python -m vgai_lite reproduce`: plan, reuse of shipped models, a quick run of every table."""

import csv
import dataclasses
import json
import shutil

import pytest

from vgai_lite.book import DATA_DIR
from vgai_lite.config import FlockConfig
from vgai_lite.lab.runs import VGAI_F24_SEED, VGAI_RUNS, VGAI_SEEDS
from vgai_lite.lab.table_cells import ModelSpec, _shipped_path
from vgai_lite.lab.reproduce import (PAPER, TABLES, ReproduceConfig, flight_config, models_of, plan,
                                 run)


def test_paper_numbers_sit_in_existing_cells():
    for table, rows in PAPER.items():
        for row, cols in rows.items():
            assert row in TABLES[table]["rows"]
            assert set(cols) <= set(TABLES[table]["columns"])


def test_every_column_flies_its_controllers_in_one_configuration():
    rc = ReproduceConfig()
    jobs = plan(rc, list(TABLES))
    by_column = {}
    for table, row, column, spec, flight, episodes in jobs:
        by_column.setdefault((table, column), set()).add((json.dumps(flight.to_dict(), sort_keys=True), episodes))
    assert all(len(v) == 1 for v in by_column.values())
    assert flight_config(rc, "R", 2.0).R == 2.0 and flight_config(rc, "v_init", 1.0).v_init == 1.0
    assert flight_config(rc, "N", 200).N == 200 and flight_config(rc, "N", 200).init_method == "repair"
    # every model is trained on N = 50 (Table 3 transfers), and the default rows at the defaults
    for table, row, column, spec, flight, episodes in jobs:
        assert spec.cfg.N == 50
        if row in ("DAGNN", "DAGNN (per neighbour)", "VGAI"):
            assert spec.cfg == FlockConfig()
        # the per-neighbour row is the paper's DAGNN with each feature divided by the degree, nothing else
        if spec.kind == "dagnn":
            assert (spec.tcfg.feature_transform == "per_neighbour") == (row == "DAGNN (per neighbour)")


def test_shipped_checkpoints_are_reused_only_for_the_same_configuration():
    rc = ReproduceConfig()
    (vgai,) = models_of(rc, "F", "VGAI", 24)
    assert _shipped_path(vgai) == (DATA_DIR / "vgai" / "vgai_F24.pt" if VGAI_F24_SEED == 0
                                   else DATA_DIR / "vgai" / "seeds" / "vgai_F24_seed0.pt")
    shipped = models_of(ReproduceConfig(vgai_seeds=VGAI_SEEDS), "F", "VGAI", 24)  # the shipped training seeds
    assert all(_shipped_path(s) is not None for s in shipped)
    dagnn = models_of(rc, "K", "DAGNN", 2)
    assert [_shipped_path(s) for s in dagnn] == [DATA_DIR / "dagnn" / "dagnn_K3.pt", None, None]
    assert all(_shipped_path(s) is None for s in models_of(rc, "R", "DAGNN (retrained)", 1.0))
    # one DAGNN per neighbour flies every column of Tables 2b and 3: the shipped one (training seed 0)
    for table in ("R", "N"):
        for column in TABLES[table]["columns"]:
            assert [_shipped_path(s) for s in models_of(rc, table, "DAGNN (per neighbour)", column)] == \
                [DATA_DIR / "dagnn" / "dagnn_K4_per_neighbour.pt", None, None]
    for name in ("vgai_F6", "vgai_F12", "vgai_K2", "vgai_K3"):
        assert _shipped_path(ModelSpec("vgai", FlockConfig(), VGAI_RUNS[name])) == DATA_DIR / "vgai" / f"{name}.pt"
    # the tables fly the VGAIs the book ships at F = 6, 12 and K - 1 = 1, 2 (runs.VGAI_RUNS), whatever their recipe
    assert [_shipped_path(models_of(rc, "F", "VGAI", F)[0]) for F in (6, 12)] == \
        [DATA_DIR / "vgai" / "vgai_F6.pt", DATA_DIR / "vgai" / "vgai_F12.pt"]
    assert [_shipped_path(models_of(rc, "K", "VGAI", k)[0]) for k in (1, 2)] == \
        [DATA_DIR / "vgai" / "vgai_K2.pt", DATA_DIR / "vgai" / "vgai_K3.pt"]
    quick = ReproduceConfig(quick=True)
    assert _shipped_path(models_of(quick, "F", "VGAI", 24)[0]) is None


def test_bad_requests_are_refused(tmp_path):
    with pytest.raises(ValueError, match="unknown table"):
        run(["table9"], ReproduceConfig(quick=True), out=tmp_path, progress=False)
    with pytest.raises(ValueError, match="positive integer"):
        ReproduceConfig(seeds=0)


@pytest.mark.slow
def test_quick_run_of_every_table_is_complete_and_resumable(tmp_path):
    rc = ReproduceConfig(quick=True, seeds=2)
    results = run(None, rc, out=tmp_path, progress=False)
    assert list(results["tables"]) == list(TABLES)
    prov = results["provenance"]
    for key in ("git_commit", "packages", "wall_seconds", "reproduce_config", "compute_seconds"):
        assert key in prov
    assert prov["packages"]["torch"].startswith("2.13.0")
    for table, t in results["tables"].items():
        for column in t["columns"]:
            cells = [t["rows"][row].get(str(column)) for row in t["rows"]]
            cells = [c for c in cells if c is not None]
            assert cells
            # one set of held-out episodes per column: the expert's figures agree in every row
            assert len({c["expert_min_distance"] for c in cells}) == 1
            for c in cells:  # a ratio of two costs of eq. 1 on the same episodes: around it its interval
                # over episodes (one training seed) or the training seeds' own costs (several)
                lo, hi = c["ci95"] if c.get("ci95") else (min(c["per_seed"]), max(c["per_seed"]))
                assert 0 < lo <= c["relative_cost_mean"] <= hi and c["min_distance"] > 0
        for row in t["rows"]:
            if row.startswith("DAGNN") and t["rows"][row]:
                assert all(len(c["per_seed"]) == 2 and c["seed_std"] is not None for c in t["rows"][row].values())
    with open(tmp_path / "results.csv") as f:
        assert len(list(csv.DictReader(f))) == sum(len(r) for t in results["tables"].values()
                                                   for r in t["rows"].values())
    cells = sorted((tmp_path / "cells").glob("*.json"))
    stamps = {p: p.stat().st_mtime_ns for p in cells}
    again = run(["K", "N"], rc, out=tmp_path, progress=False)  # nothing new to compute
    assert sorted((tmp_path / "cells").glob("*.json")) == cells
    assert all(p.stat().st_mtime_ns == stamps[p] for p in cells)
    assert again["tables"]["K"] == results["tables"]["K"]


@pytest.mark.slow
def test_retrain_trains_every_model_again_and_recomputes_every_cell(quick_table_k, tmp_path):
    first, folder, _ = quick_table_k  # reproduce --only K --quick --seeds 1 (conftest.py), copied here
    shutil.copytree(folder, tmp_path / "K")
    rc = ReproduceConfig(quick=True, seeds=1)
    models = sorted((tmp_path / "K" / "models").glob("*.pt"))
    assert len(models) == 6  # DAGNN and VGAI at K - 1 = 1, 2, 3; the three VGAIs share one stage 1
    stamps = {p: p.stat().st_mtime_ns for p in models + sorted((tmp_path / "K" / "cells").glob("*.json"))}
    assert len(list((tmp_path / "K" / "stage1").glob("*.pt"))) == 1
    again = run(["K"], dataclasses.replace(rc, retrain=True), out=tmp_path / "K", progress=False)
    assert all(p.stat().st_mtime_ns != t for p, t in stamps.items())
    runs = again["provenance"]["invocations"]
    assert [r["retrain"] for r in runs] == [False, True]
    assert runs[0]["models_trained_now"] == runs[1]["models_trained_now"] == 6
    assert runs[1]["cells_computed_now"] == first["provenance"]["compute_seconds"]["cells"]


def test_extras_add_a_vgai_trained_at_each_radius_only_when_asked():
    plain = plan(ReproduceConfig(), ["R"])
    extra = plan(ReproduceConfig(extras=True), ["R"])
    assert not any(row == "VGAI (retrained)" for _, row, *_ in plain)
    retrained = {column: spec for _, row, column, spec, flight, _ in extra if row == "VGAI (retrained)"}
    assert sorted(retrained) == [1.0, 1.5, 2.0]
    for column, spec in retrained.items():
        assert spec.kind == "vgai" and spec.cfg.R == column
    assert _shipped_path(retrained[1.5]) == _shipped_path(models_of(ReproduceConfig(), "F", "VGAI", 24)[0])  # the default
    assert _shipped_path(retrained[2.0]) is None


def test_the_plain_cnn_records_of_retrained_configurations_are_kept():
    """Every configuration retrained with the default recipe keeps its plain-CNN record (notebooks 06-07)."""
    import json

    from vgai_lite.lab.runs import PLAIN_RUNS
    from vgai_lite.vgai_config import VGAITrainConfig

    assert "vgai_F24_plain" in PLAIN_RUNS
    for name, tcfg in PLAIN_RUNS.items():
        rec = json.loads((DATA_DIR / "experiments" / f"{name}.json").read_text())
        assert VGAITrainConfig.from_dict(rec["train_config"]) == tcfg, name


def test_the_camera_choice_follows_the_seed_rule_on_clean_validation_frames(tmp_path):
    """By runs.SEED_RULE on clean frames of the validation episodes: among the trainings that flocked the
    cheapest (the cheapest of all where none flocked), never by a perturbed setting."""
    import json as _json

    from vgai_lite.book import VALIDATION_SEED
    from vgai_lite.lab.runs import CAMERA_RUNS, chosen_camera_runs

    def summary(cost, variance):
        return {"relative_cost_mean": cost, "seed": VALIDATION_SEED, "flocking_horizon_s": 5.0,
                "velocity_variance_median": {"2s": variance, "5s": variance}, "share_connected_at_end": 1.0}

    costs = {"vgai_depthcam_wide": (2.7, 1e-3), "vgai_camera_gray": (1.5, 1e-2), "vgai_depthcam": (2.6, 1e-3),
             "vgai_camera_narrow_gray": (1.9, 2e-2)}
    for name, (c, var) in costs.items():
        rec = {"settings": {"clean": summary(c, var), "noise0.05": summary(0.1, 1e-4)}}
        (tmp_path / f"{name}_cameras.json").write_text(_json.dumps(rec))
    # by the clean cost, never by a perturbed one; gray only: neither flocks, so the cheaper
    assert chosen_camera_runs(tmp_path) == {"gray + depth": "vgai_depthcam", "gray only": "vgai_camera_gray"}
    rec = _json.loads((tmp_path / "vgai_depthcam_cameras.json").read_text())
    rec["settings"]["clean"]["velocity_variance_median"]["5s"] = 5e-3  # cheaper, but its swarm does not settle
    (tmp_path / "vgai_depthcam_cameras.json").write_text(_json.dumps(rec))
    assert chosen_camera_runs(tmp_path)["gray + depth"] == "vgai_depthcam_wide"
    rec = _json.loads((tmp_path / "vgai_camera_gray_cameras.json").read_text())
    rec["settings"]["clean"]["seed"] = VALIDATION_SEED + 2000  # e.g. the test episodes: no choice on them
    (tmp_path / "vgai_camera_gray_cameras.json").write_text(_json.dumps(rec))
    with pytest.raises(ValueError, match="validation"):
        chosen_camera_runs(tmp_path)
    shipped = chosen_camera_runs()
    assert shipped["gray + depth"] in {r["gray + depth"] for r in CAMERA_RUNS.values()}
    assert shipped["gray only"] in {r["gray only"] for r in CAMERA_RUNS.values()}


def test_every_shipped_model_is_found_finished_with_its_run_configuration():
    """The load-or-train rule must recognise every shipped checkpoint, or the first `reproduce` or
    notebook that asks for it trains it again (as adding a field to a configuration once did)."""
    from vgai_lite.book import DATA_DIR
    from vgai_lite.checkpoints import is_finished_with
    from vgai_lite.config import FlockConfig
    from vgai_lite.lab.runs import DAGNN_RUNS, VGAI_RUNS, VGAI_SEED_RUNS

    cfg = FlockConfig()
    runs = [(DATA_DIR / "dagnn" / f"{n}.pt", t) for n, t in DAGNN_RUNS.items()]
    runs += [(DATA_DIR / "vgai" / f"{n}.pt", t) for n, t in VGAI_RUNS.items()]
    runs += [(DATA_DIR / "vgai" / "seeds" / f"{n}.pt", t) for n, t in VGAI_SEED_RUNS.items()]
    stale = [p.name for p, t in runs if not is_finished_with(p, cfg, t.to_dict(), read=t.read_stored)]
    assert not stale, f"these shipped checkpoints would be trained again: {stale}"


def test_a_stored_configuration_is_read_with_the_values_of_fields_added_since():
    from vgai_lite.dagnn_training import DAGNNTrainConfig
    from vgai_lite.vgai_config import VGAITrainConfig, book_recipe

    old = {k: v for k, v in DAGNNTrainConfig().to_dict().items() if k not in DAGNNTrainConfig.LEGACY_FIELDS}
    assert DAGNNTrainConfig.read_stored(old) == DAGNNTrainConfig().to_dict()
    assert DAGNNTrainConfig.read_stored(old) != DAGNNTrainConfig(teams=(50, 100)).to_dict()
    book = book_recipe().to_dict()
    old = {k: v for k, v in book.items() if k != "warm_starts"}
    old["vision"] = {**old["vision"], "render": {k: v for k, v in old["vision"]["render"].items() if k != "nearest"}}
    assert VGAITrainConfig.read_stored(old) == book  # written before warm_starts and nearest: warm-started, every drone drawn
    assert VGAITrainConfig.read_stored({"no such": 1}) == {"no such": 1}  # unreadable: matches nothing, trained again

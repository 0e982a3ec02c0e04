"""The book's named runs: the DAGNNs, VGAIs and state estimators it ships in ``data/``, by name.

Introduced in notebook 03 (DAGNN), 05 (estimators) and 06 (VGAI). ``book_dagnn``/``book_vgai``
load a shipped controller when its configuration matches (``imitation.load_or_train``), train it
otherwise, and evaluate it on the book's held-out episodes. One rule for the records beside the
checkpoints (``data/*/NAME.json``): they are written when the model was trained now, or when the
caller asks (the command line's ``train-dagnn`` and ``train-vgai`` do), so that a notebook run in
quick mode never overwrites a shipped record.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path
from typing import Optional, Union

from ..book import DATA_DIR, VALIDATION_SEED, WORKING_SEED
from ..checkpoints import is_finished_with, load_estimator, save_estimator
from ..config import FlockConfig
from ..dagnn_training import DAGNNTrainConfig, train_dagnn
from ..evaluate import flocked, relative_cost
from ..imitation import load_or_train
from .provenance import Provenance, sha256
from ..state_estimation import estimator_quality, train_state_estimator
from ..vgai_config import BOOK_SENSOR, VGAITrainConfig, book_recipe
from ..vgai_training import train_vgai
from .stage1_cache import cached
from ..vision import VisionConfig

PER_NEIGHBOUR = "per_neighbour"
"""``DAGNNTrainConfig.feature_transform`` of the DAGNN trained once at N = 50, R = 1.5 m that flocks at
N' = 200 (notebook 03, section 9): each feature a mean over the drone's neighbours, not a sum."""

DAGNN_RUNS: dict[str, DAGNNTrainConfig] = {
    "dagnn_K4": DAGNNTrainConfig(),                          # the default: K - 1 = 3 exchanges
    "dagnn_K3": DAGNNTrainConfig(K=3),                       # Table 1b: K - 1 = 2
    "dagnn_K2": DAGNNTrainConfig(K=2),                       # Table 1b: K - 1 = 1
    "dagnn_K1": DAGNNTrainConfig(K=1),                       # no exchange at all
    "dagnn_K4_no_dagger": DAGNNTrainConfig(p_learner=0.0),   # behaviour cloning on expert data only
    "dagnn_K4_mean": DAGNNTrainConfig(gso="row_normalized"), # GSO comparison (notebook 03)
    "dagnn_K4_sum": DAGNNTrainConfig(gso="adjacency"),
    "dagnn_K4_signed_log": DAGNNTrainConfig(feature_transform="signed_log"),
    "dagnn_K4_per_neighbour": DAGNNTrainConfig(feature_transform=PER_NEIGHBOUR),  # the row "DAGNN (per neighbour)" of Tables 2b and 3
}
"""The DAGNNs the book ships in data/dagnn/ (FlockConfig() defaults), by name. ``dagnn_K4`` is the paper's
(the local features' sums); ``dagnn_K4_per_neighbour`` divides each sum by the drone's degree (notebook 03, section 9),
the one DAGNN that flies every column of Tables 2b and 3 (their row "DAGNN (per neighbour)"); it flocks at every
N' up to 200, not at R = 1 m."""

VGAI_SEEDS = 3
"""Training seeds of the default VGAI the book ships (``train-vgai --seeds``; how long each took is in
its record, data/vgai/seeds/NAME.json)."""

VGAI_SEED_RUNS: dict[str, VGAITrainConfig] = {f"vgai_F24_seed{s}": book_recipe(seed=s) for s in range(VGAI_SEEDS)}
"""Trainings of the default VGAI that differ only in the training seed, in data/vgai/seeds/: how far
apart trainings land, and the pool the book's vgai_F24 is chosen from (``choose_seed``)."""

VGAI_F24_SEED = 1
"""The training seed of the book's vgai_F24: the one of VGAI_SEED_RUNS that SEED_RULE picks on the
validation episodes (book.VALIDATION_SEED, never the test seed), as chosen and recorded
in data/vgai/seeds/choice.json by ``python -m vgai_lite train-vgai --choose`` (a test checks the two agree)."""

VGAI_RUNS: dict[str, VGAITrainConfig] = {
    "vgai_F24": book_recipe(seed=VGAI_F24_SEED),  # the paper's default: F = 24, K - 1 = 3, egocentric
    # Tables 1a and 1b, the book's recipe:
    "vgai_F6": book_recipe(F=6),     # as many features as the DAGNN's (F_m = 2)
    "vgai_K2": book_recipe(K=2),     # K - 1 = 1 exchange (stage 1 shared with vgai_F24's)
    "vgai_F12": book_recipe(F=12),   # F_m = 4
    "vgai_K3": book_recipe(K=3),     # K - 1 = 2 exchanges (the same)
}
"""The VGAI controllers the book ships in data/vgai/, by name."""

PLAIN_RUNS: dict[str, VGAITrainConfig] = {
    f"{name}_plain": VGAITrainConfig(F=t.F, K=t.K, **BOOK_SENSOR) for name, t in VGAI_RUNS.items() if t.motion_features}
"""The book's configurations trained with the paper's loss, CNN and DAgger on the book's sensor after
its warm starts (``BOOK_SENSOR``; "the paper's recipe" of notebook 11's first ablation, before the
paper's VGAI itself was flown): their records (and vgai_F24_plain's checkpoint) are kept in
data/experiments/, for notebook 11's table and notebook 07's two trainings of one configuration."""

TIMED_ALONE = "vgai_depthcam_seed3"
"""The book's recipe (``BOOK``, training seed 3) trained alone on the two cores at two threads, nothing else
running (data/experiments/NAME.json): the recipe's training time, and where it goes (``seconds_by_phase``)."""

CAMERA_SEED_RUNS: tuple = ("vgai_depthcam", "vgai_depthcam_seed1", "vgai_depthcam_seed2", TIMED_ALONE)
"""Every training of the book's recipe through the camera, training seeds 0 to 3 (data/experiments/NAME.json;
seeds 0-2 copied to data/vgai/seeds/vgai_F24_seedS when the camera became the book's, the pool its
vgai_F24 was chosen from; seed 3 trained later, alone, to time the recipe): the recipe's record over
seeds, its camera evaluations on the validation episodes, NAME_cameras.json (notebook 08)."""

def seed_records(names: tuple = CAMERA_SEED_RUNS, folder: Optional[Path] = None) -> list[dict]:
    """The records of every training of one VGAI configuration (default: the book's recipe, CAMERA_SEED_RUNS),
    data/experiments/NAME.json, all on the same validation episodes: the spread between training seeds that
    ``findings.seed_spread`` measures and every single-training VGAI cell is judged with (``findings.one_training``)."""
    folder = DATA_DIR / "experiments" if folder is None else Path(folder)
    recs = [json.loads((folder / f"{n}.json").read_text()) for n in names]
    if len({(r["seed"], r["episodes"]) for r in recs}) != 1:
        raise ValueError(f"seed_records: {names} were not flown on the same episodes")
    return recs


CLEAN_SEED_RUNS: tuple = ("vgai_clean_seed0", "vgai_clean_seed1", "vgai_clean_seed2")
"""The book's recipe on clean frames (``BOOK_RECIPE`` without ``BOOK_CAMERA``; the book's VGAI until the
camera), training seeds 0, 1 and 2: data/experiments/NAME.pt and .json (validation episodes). What the
camera costs on clean frames, and the leave-one-out's row without the camera."""

TRAINING_TARGET_MINUTES = 45
"""The most a training of the book may take alone on the two cores (the camera issue's target)."""

DEPARTURES: dict[str, frozenset] = {
    "the learner flying alone": frozenset({"learner_swarms"}),
    "the depth channel": frozenset({"vision", "camera"}),  # the camera: no range error without depth
    "the warm starts": frozenset({"warm_starts"}),
    "the second frame": frozenset({"vision", "motion_features"}),
    "the odd motion features": frozenset({"motion_features"}),
    "the synthetic relative velocities": frozenset({"synthetic_share"}),
    "the state-estimation loss in stage 3": frozenset({"aux_weight"}),
    "the camera model": frozenset({"camera"}),
}
"""The book's departures from the paper that a leave-one-out takes back, each with the fields of
``VGAITrainConfig`` it may set (a test checks that every leave-one-out training differs from its recipe in
these alone; the depth channel's camera differs only where the recipe's gives depth a range error)."""

LEFT_WITHOUT: dict[str, str] = {
    "the second frame": "no motion channel, so no odd motion features",
    "the depth channel": "gray and its motion channel",
    "the state-estimation loss in stage 3": "eq. 10 alone in the joint training",
    "the synthetic relative velocities": "stage 1 on the expert's states alone",
    "the odd motion features": "a plain CNN",
    "the learner flying alone": "DAgger's mixture only",
    "the warm starts": "joint BPTT from random weights",
    "the camera model": "clean frames in training",
}
"""What a recipe keeps when a departure is taken back (the leave-one-out tables' labels)."""

LEAVE_ONE_OUT: dict[str, tuple[str, str]] = {d: (name, LEFT_WITHOUT[d]) for d, name in {
    "the second frame": "vgai_depthcam_one_frame",
    "the depth channel": "vgai_camera_narrow_gray",
    "the state-estimation loss in stage 3": "vgai_depthcam_no_aux",
    "the synthetic relative velocities": "vgai_depthcam_no_synthetic",
    "the odd motion features": "vgai_depthcam_no_odd",
    "the learner flying alone": "vgai_depthcam_no_learner",
    "the warm starts": "vgai_depthcam_no_warm",
    "the camera model": CLEAN_SEED_RUNS[0],
}.items()}
"""The book's recipe (``BOOK``, through the camera: CAMERA_SEED_RUNS) without one of its departures from the
paper at a time (training seed 0, the same 20 validation episodes, flown on clean frames): departure ->
(data/experiments/NAME.json, what is left). The yardstick is the recipe over its training seeds (CAMERA_SEED_RUNS).
Notebook 11's leave-one-out table and the book's one sentence on what VGAI's flocking needs
(``findings.needs``). The team and radius randomisation is not a row: it is not part of the recipe
(notebook 07: trained over teams and radii, VGAI transferred worse)."""

LEAVE_ONE_OUT_CLEAN: dict[str, tuple[str, str]] = {d: (name, LEFT_WITHOUT[d]) for d, name in {
    "the learner flying alone": "vgai_F24_validation",
    "the depth channel": "vgai_learner_gray",
    "the warm starts": "vgai_book_no_warm",
    "the second frame": "vgai_book_one_frame",
    "the odd motion features": "vgai_book_no_odd",
    "the synthetic relative velocities": "vgai_book_no_synthetic",
    "the state-estimation loss in stage 3": "vgai_book_no_aux",
}.items()}
"""The same leave-one-out from the recipe on clean frames (``BOOK`` without ``BOOK_CAMERA``; CLEAN_SEED_RUNS,
the book's recipe before the camera), trained first: notebook 11 sets it beside the one through the camera,
which shows whether a departure's worth depends on the camera."""

PAPER_SEEDS = (0, 1, 2)
"""Training seeds of the paper's VGAI (``PAPER``) in the book's simulator: data/experiments/vgai_paper_seedS."""

CAMERA_RUNS: dict[str, dict[str, str]] = {
    "wide": {"gray + depth": "vgai_depthcam_wide", "gray only": "vgai_camera_gray"},
    "narrower": {"gray + depth": "vgai_depthcam", "gray only": "vgai_camera_narrow_gray"},
}
"""The recipe trained through a camera (``VGAITrainConfig.camera``, training seed 0), by the width of
the camera's ranges and the sensor: data/experiments/NAME.pt, .json and NAME_cameras.json (notebook 08).
The narrower ranges with gray + depth won (``chosen_camera_runs``) and became the book's recipe
(``vgai_config.BOOK_CAMERA``): vgai_depthcam is the book's vgai_F24_seed0."""


SEED_RULE = "among the seeds that flocked on the validation episodes, the lowest relative cost (all seeds if none flocked)"
"""How the book's vgai_F24 is chosen among its training seeds (``pick_seed``): a user wants a swarm that
flocks first and a low cost second, so a cheaper training whose swarm does not settle (``evaluate.flocked``)
is not the one shipped."""


def pick_seed(candidates: dict) -> str:
    """SEED_RULE: ``candidates`` maps a name to its validation summary ("relative_cost_mean", "flocked");
    returns the chosen name."""
    if not candidates:
        raise ValueError("pick_seed needs at least one candidate training")
    pool = [n for n in candidates if candidates[n]["flocked"]] or list(candidates)
    return min(pool, key=lambda n: candidates[n]["relative_cost_mean"])


def chosen_camera_runs(folder: Optional[Path] = None) -> dict[str, str]:
    """For each sensor of CAMERA_RUNS, the camera training that SEED_RULE (``pick_seed``, the book's one
    rule for such choices) picks on clean frames of the validation episodes (``camera_eval``'s record,
    NAME_cameras.json), read by 08 and 09 alike. Returns {"gray + depth": name, "gray only": name}."""
    folder = DATA_DIR / "experiments" if folder is None else Path(folder)
    chosen = {}
    for sensor in ("gray + depth", "gray only"):
        costs = {}
        for ranges in (r for r in CAMERA_RUNS.values() if sensor in r):
            rec = json.loads((folder / f"{ranges[sensor]}_cameras.json").read_text())["settings"]["clean"]
            if rec["seed"] != VALIDATION_SEED:
                raise ValueError(f"{ranges[sensor]}_cameras.json is not on the validation episodes "
                                 f"(seed {rec['seed']}, expected {VALIDATION_SEED}): a choice is made on them")
            costs[ranges[sensor]] = {"relative_cost_mean": rec["relative_cost_mean"], "flocked": flocked(rec)}
        chosen[sensor] = pick_seed(costs)
    return chosen


STAGE1_CACHE = DATA_DIR / "results" / "stage1"
"""Where ``book_vgai`` keeps (and finds) stage 1 of a VGAI training: runs that differ only in K share
it, as in ``reproduce``, which uses the same folder."""

ESTIMATOR_RUNS: dict[str, VisionConfig] = {
    "estimator_motion": VisionConfig(),                 # [I(t), 5 (I(t) - I(t-5))]
    "estimator_single": VisionConfig(motion_gap=0),     # I(t) only
}
"""The state estimators the book ships in data/vgai/, by name."""


def write_evaluation(path: Union[str, Path], result, cfg: FlockConfig, extra: Optional[dict] = None,
                     provenance: Optional[dict] = None) -> Path:
    """Save a RelativeCost's summary with its configuration as JSON (what the notebooks display),
    its first episodes one by one (``RelativeCost.pinned``) and, when given, its provenance
    (``vgai_lite.lab.provenance``)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    out = {"config": dataclasses.asdict(cfg), **result.summary(), "pinned": result.pinned(), **(extra or {})}
    if provenance is not None:
        out["provenance"] = provenance
    path.write_text(json.dumps(out, indent=2) + "\n")
    return path


def training_minutes(record: dict) -> float:
    """Minutes a training took, stages 1 to 3, from its record: ``train_seconds`` counts stage 1 when it
    was trained in the same run; when it was read from the cache (``stage1_cached``), its recorded
    ``stage1_seconds`` are added."""
    stage1 = record.get("stage1_seconds") or 0.0 if record.get("stage1_cached") else 0.0
    return (record["train_seconds"] + stage1) / 60


def how_trained(record: dict) -> Optional[str]:
    """How a training ran, from its record's provenance: its torch threads, and "alone" when the
    machine's mean load average while it trained stayed within half a job of those threads, else
    "sharing the cores" (e.g. "1 thread, sharing the cores": one of two trainings side by side). None
    for a record written before provenance. The load itself stays in the record."""
    p = record.get("provenance", {}).get("training")
    if p is None:
        return None
    n = p["torch_threads"]
    return f"{n} thread{'s' if n > 1 else ''}, {'alone' if p['load_average_mean'] <= n + 0.5 else 'sharing the cores'}"


def _check_name(name: str, runs: dict, kind: str) -> None:
    if name not in runs:
        raise ValueError(f"unknown run {name!r}; the book's {kind} runs are {sorted(runs)}")


def _book_model(name: str, runs: dict, folder: str, train, retrain: bool, episodes: int, progress: bool,
                write_json: bool, record, seed: int = WORKING_SEED, **train_kwargs):
    """Load or train data/FOLDER/NAME.pt, evaluate it on ``episodes`` episodes of ``seed``; write
    NAME.json (with ``record(history)``) when trained now or asked. Returns (controller, RelativeCost)."""
    _check_name(name, runs, folder.split("/")[0].upper())
    cfg, tcfg = FlockConfig(), runs[name]
    path = DATA_DIR / folder / f"{name}.pt"
    controller, trained = load_or_train(path, cfg, tcfg, train, retrain=retrain, progress=progress, **train_kwargs)
    command = f"python -m vgai_lite train-{folder.split('/')[0]} {name} --episodes {episodes}" \
        + (" --retrain" if retrain else "")
    with Provenance(command) as prov:
        result = relative_cost(controller, cfg, episodes=episodes, seed=seed, name=name)
    hist = controller.meta["history"]
    if write_json or trained:
        write_evaluation(path.with_suffix(".json"), result, cfg,
                         extra={"train_config": tcfg.to_dict(), "train_seconds": round(hist["seconds"], 1),
                                **record(hist)},
                         provenance=prov.record(checkpoint=path, seed=seed, episodes=episodes))
    return controller, result


def book_dagnn(name: str, retrain: bool = False, episodes: int = 50, progress: bool = True,
               write_json: bool = False):
    """Load (or train: its record in data/dagnn/ says how long) the book's DAGNN ``name`` and evaluate it on ``episodes``
    working episodes (seed WORKING_SEED). Returns (controller, RelativeCost)."""
    return _book_model(name, DAGNN_RUNS, "dagnn", train_dagnn, retrain, episodes, progress, write_json,
                       lambda hist: {"round_checks": hist["rounds"]})


def book_vgai(name: str, retrain: bool = False, episodes: int = 20, progress: bool = True,
              write_json: bool = False):
    """Load (or train: its record in data/vgai/ says how long, ``training_minutes``) the book's VGAI ``name`` (of VGAI_RUNS, or of VGAI_SEED_RUNS
    in data/vgai/seeds/) and evaluate it on ``episodes`` validation episodes (seed VALIDATION_SEED):
    the record beside a VGAI checkpoint is the evaluation its choice was made on (``choose_seed``);
    the book reports its VGAIs on the test episodes (``tools/test_episodes.py``) and in the paper's
    tables (``reproduce``). Returns (controller, RelativeCost)."""
    runs, folder = (VGAI_SEED_RUNS, "vgai/seeds") if name in VGAI_SEED_RUNS else (VGAI_RUNS, "vgai")
    return _book_model(name, runs, folder, train_vgai, retrain, episodes, progress, write_json,
                       lambda hist: {"stage1_seconds": round(hist.get("stage1_seconds", 0.0), 1),
                                     "stage1_cached": hist.get("stage1_cached"),  # then not in train_seconds
                                     "round_checks": hist["rounds"]},
                       seed=VALIDATION_SEED, stage1=cached(STAGE1_CACHE))


def book_estimator(name: str, retrain: bool = False, steps: int = 3000, progress: bool = True):
    """Load (or train and save) the book's state estimator ``name`` in data/vgai/.
    Returns (cnn, vision, meta)."""
    _check_name(name, ESTIMATOR_RUNS, "estimator")
    path = DATA_DIR / "vgai" / f"{name}.pt"
    vision = ESTIMATOR_RUNS[name]
    if path.is_file() and not retrain:
        cnn, stored_vision, meta = load_estimator(path)
        if stored_vision == vision and meta.get("steps") == steps:
            return cnn, vision, meta
    cfg = FlockConfig()
    cnn, losses, seconds = train_state_estimator(cfg, vision, steps=steps, progress=progress)
    quality = estimator_quality(cnn, vision, cfg, seed=WORKING_SEED)
    meta = {"steps": steps, "losses": losses, "seconds": seconds,
            "quality": {str(t): q for t, q in quality.items()}}
    save_estimator(path, cnn, vision, meta)
    return cnn, vision, meta


def choose_seed() -> dict:
    """Pick the book's vgai_F24 among the trainings of VGAI_SEED_RUNS (``train-vgai --seeds``) by
    ``pick_seed``'s rule on the validation episodes (seed VALIDATION_SEED, never the test seed), read
    from each seed's record (``book_vgai``'s evaluation, checked to be of that checkpoint and those
    episodes). Copies the chosen checkpoint and its record to data/vgai/vgai_F24.pt / .json, writes
    data/vgai/seeds/choice.json, and returns that record. VGAI_F24_SEED must then name the chosen seed."""
    cfg, candidates = FlockConfig(), {}
    folder = DATA_DIR / "vgai"
    for name, tcfg in VGAI_SEED_RUNS.items():
        path = folder / "seeds" / f"{name}.pt"
        if not is_finished_with(path, cfg, tcfg.to_dict(), read=tcfg.read_stored):
            raise FileNotFoundError(f"{path} is missing or not a finished training of {name}: "
                                    "run `python -m vgai_lite train-vgai --seeds` first")
        rec = json.loads(path.with_suffix(".json").read_text())
        prov = rec["provenance"].get("evaluation", rec["provenance"])
        if prov["checkpoint_sha256"] != sha256(path) or rec["seed"] != VALIDATION_SEED:
            raise ValueError(f"{path.with_suffix('.json')} is not an evaluation of {path.name} on the validation "
                             f"episodes (seed {VALIDATION_SEED}): run `python -m vgai_lite train-vgai {name}`")
        candidates[name] = {k: rec[k] for k in ("relative_cost_mean", "relative_cost_mean_ci95", "episodes", "seed")}
        candidates[name].update(training_seed=tcfg.seed, variance_5s=rec["velocity_variance_median"]["5s"],
                                share_connected_at_end=rec["share_connected_at_end"], flocked=flocked(rec))
    best = pick_seed(candidates)
    for suffix in (".pt", ".json"):
        shutil.copyfile(folder / "seeds" / f"{best}{suffix}", folder / f"vgai_F24{suffix}")
    record = {"rule": SEED_RULE, "validation_seed": VALIDATION_SEED,
              "episodes": candidates[best]["episodes"], "chosen": best, "chosen_seed": VGAI_SEED_RUNS[best].seed,
              "chosen_sha256": sha256(folder / "vgai_F24.pt"), "candidates": candidates}
    (folder / "seeds" / "choice.json").write_text(json.dumps(record, indent=1) + "\n")
    return record

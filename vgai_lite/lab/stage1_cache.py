"""A folder of trained first stages of VGAI, so that trainings that share one train it once.

Stage 1 of ``vgai_training.train_vgai`` (visual state estimation) depends on the flight configuration
and on a few fields of the training configuration, not on K, the MLP or the DAgger schedule: Table 1b's
K = 2, 3, 4 trainings share it. ``cached(folder)`` is a stage-1 function for ``train_vgai(...,
stage1=...)``: it reads the CNN at the end of stage 1, and the sampling generator's state then, from
the folder when this exact stage 1 was trained before, else trains it (``vgai_training.fit_stage1``) and
writes it there. A run that reads it continues exactly as if it had trained it; its history then says
``stage1_cached`` and keeps the seconds the stage took when it was trained.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable, Union

import torch

from ..checkpoints import atomic_save, config_hash, load_weights, weights
from ..config import FlockConfig
from ..vgai_config import VGAITrainConfig
from ..vgai_training import fit_stage1

FORMAT = "vgai-lite-stage1/3"

STAGE1_FIELDS = ("F", "cnn_widths", "cnn_hidden", "vision", "expert_episodes", "warm_steps", "warm_states",
                 "lr", "early_steps", "early_share", "seed", "synthetic_share", "synthetic_speeds",
                 "motion_features", "camera", "teams", "radii", "group_swarms",
                 "feature_means")
"""The training configuration's fields stage 1 depends on (with the flight configuration)."""


def stage1_identity(cfg: FlockConfig, tcfg: VGAITrainConfig) -> dict:
    """What stage 1 depends on: runs that agree on it train the very same stage-1 CNN."""
    t = tcfg.to_dict()
    return {"config": cfg.to_dict(), "train": {k: t[k] for k in STAGE1_FIELDS}}


def stage1_file(folder: Union[str, Path], cfg: FlockConfig, tcfg: VGAITrainConfig) -> Path:
    """Where the stage 1 of (cfg, tcfg) is kept in ``folder``."""
    return Path(folder) / f"stage1_F{tcfg.F}_{config_hash({'format': FORMAT, **stage1_identity(cfg, tcfg)})}.pt"


def cached(folder: Union[str, Path]) -> Callable:
    """A stage-1 function for ``train_vgai(..., stage1=cached(folder))`` (``fit_stage1``'s signature)."""

    def stage1(cnn, cfg: FlockConfig, tcfg: VGAITrainConfig, flights: list, gen: torch.Generator,
               progress: bool = True) -> dict:
        path = stage1_file(folder, cfg, tcfg)
        if path.is_file():
            payload = torch.load(path, map_location="cpu", weights_only=True)
            load_weights(cnn, payload["state_dict"], path)
            cnn.eval()
            gen.set_state(payload["generator"])
            return {**payload["record"], "stage1_cached": path.name}
        record = fit_stage1(cnn, cfg, tcfg, flights, gen, progress)
        atomic_save({"identity_json": json.dumps({"format": FORMAT, **stage1_identity(cfg, tcfg)}, sort_keys=True),
                     "state_dict": weights(cnn), "generator": gen.get_state(), "record": record}, path)
        return record

    return stage1
